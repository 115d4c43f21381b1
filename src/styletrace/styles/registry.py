"""Name -> style class. The CLI, the Mitsuba plugin and the docs all read this one table."""
from __future__ import annotations

from typing import Any

from .base import Style
from .params import StyleError

_STYLES: dict[str, type[Style]] = {}


def register(cls: type[Style]) -> type[Style]:
    if not cls.name or cls.name in _STYLES:
        raise ValueError(f"style name {cls.name!r} is empty or taken")
    _STYLES[cls.name] = cls
    return cls


def names() -> list[str]:
    return sorted(_STYLES)


def get(name: str) -> type[Style]:
    try:
        return _STYLES[name]
    except KeyError:
        raise StyleError(f"unknown style '{name}': available styles are {', '.join(names())}") from None


def create(name: str, **values: Any) -> Style:
    return get(name)(**values)
