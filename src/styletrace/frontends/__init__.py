"""The front ends: the command line, the gallery and its equal-time section, the docs tables, the
status line."""
