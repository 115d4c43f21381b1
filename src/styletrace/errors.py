"""The exceptions a user can cause, one family so that front ends catch them in one place.

Every message is one line that names the bad value and what is allowed. The command line prints it
after `styletrace: error:` and exits with status 2; the Python API raises it as it is.
"""
from __future__ import annotations


class StyletraceError(Exception):
    """Base of every error caused by input (arguments, parameters, scenes, the machine's set-up)."""


class BackendError(StyletraceError, RuntimeError):
    """No usable JIT backend; the message says how to get one."""


class StyleError(StyletraceError, ValueError):
    """A bad style name or style parameter."""


class SettingsError(StyletraceError, ValueError):
    """A bad setting of the `stylized` integrator (inner samples, estimator, stylize, depths,
    ...)."""


class SceneError(StyletraceError, ValueError):
    """A scene that cannot be found or loaded."""


class UsageError(StyletraceError, ValueError):
    """Malformed command-line or API arguments (flags, output paths, sample counts)."""


__all__ = ["StyletraceError", "BackendError", "StyleError", "SettingsError", "SceneError",
           "UsageError"]
