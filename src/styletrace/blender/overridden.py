"""Render settings with some values replaced: the settings a material preview or a frame of an
animation renders with, without writing to the user's scene."""
from __future__ import annotations

from typing import Any


class Overridden:
    """Read-only view of `settings` (a `properties.SceneSettings`) in which `values` replace the
    settings' own; every other attribute is read from `settings`.

    Args:
        settings: the render settings to read through. values: the replaced settings by name.
    Raises:
        AttributeError: a name in `values` that `settings` does not have.
    """

    def __init__(self, settings: Any, **values: Any):
        for name in values:
            if not hasattr(settings, name):
                raise AttributeError(
                    f"no render setting {name!r} to override: expected one of the "
                    f"styletrace render settings (e.g. 'seed', 'spp')"
                )
        self.__dict__["_settings"] = settings
        self.__dict__["_values"] = dict(values)

    def __getattr__(self, name: str) -> Any:
        values = self.__dict__["_values"]
        if name in values:
            return values[name]
        return getattr(self.__dict__["_settings"], name)

    def __setattr__(self, name: str, value: Any) -> None:
        raise AttributeError(f"render settings overridden for one render are read-only ({name!r})")
