"""How a caller names a render's settings, so that an error speaks the caller's words.

    COMMAND_LINE.value("spp", 4)     # '--spp 4'
    PYTHON.value("spp", 4)           # 'spp=4'
    BLENDER.value("spp", 4)          # "'Camera samples' 4"

Every front end builds its `pipeline.job.Job` with its terms (`Job.terms`); the budget, `resolve`
and the runner name a bad or conflicting count through them. The keys are the Job's own names:
`samples` (paths per pixel), `spp` (camera samples per pixel), `inner` (children per stylized
vertex), `pass_spp` (camera samples per pass), `seed`, `width`, `height`, `passes` (the data
passes).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Mapping


@dataclass(frozen=True)
class Terms:
    """One caller's names for the Job's settings.

    Args:
        names: {key: the caller's name}; a key left out is named as the key itself.
        style: how a name and a value are joined: "flag" ('--spp 4'), "keyword" ('spp=4') or
            "label" ("'Camera samples' 4").
    """
    names: Mapping[str, str] = field(default_factory=dict)
    style: str = "keyword"

    def name(self, key: str) -> str:
        """The caller's name of `key` (a flag, a keyword, a field's label)."""
        return self.names.get(key, key)

    def value(self, key: str, value: Any) -> str:
        """`key` set to `value`, as the caller writes it.

        Args:
            key: the Job's name of the setting. value: its value (already text, or str()-able).

        Returns:
            '--spp 4', 'spp=4' or "'Camera samples' 4".
        """
        name = self.name(key)
        if self.style == "flag":
            return f"{name} {value}"
        if self.style == "label":
            return f"'{name}' {value}"
        return f"{name}={value}"


#: `styletrace render`'s flags
COMMAND_LINE = Terms({"samples": "--samples", "spp": "--spp", "inner": "--inner",
                      "pass_spp": "--pass-spp", "seed": "--seed", "width": "--width",
                      "height": "--height", "passes": "--passes",
                      "mist": "--mist"}, "flag")
#: `styletrace.render`'s keywords (and `render_buffer`'s)
PYTHON = Terms({}, "keyword")
#: the Blender add-on's render settings, by their labels
BLENDER = Terms({"samples": "Samples", "spp": "Camera samples", "inner": "Inner samples",
                 "pass_spp": "Camera samples per pass", "seed": "Seed",
                 "passes": "Passes"}, "label")
__all__ = ["Terms", "COMMAND_LINE", "PYTHON", "BLENDER"]
