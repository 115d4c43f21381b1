"""Scene analysis: what a loaded scene holds for the kernel (graph.py: styled BSDFs wherever they
sit, media, null surfaces) and its scene-relative `auto` style values (defaults.py: a pilot of the
path kernel)."""

