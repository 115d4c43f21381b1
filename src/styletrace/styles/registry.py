"""Name -> style class. The CLI, the Mitsuba plugin and the docs all read this one table."""
from __future__ import annotations

from typing import Any

from .base import Style
from .params import StyleError

_STYLES: dict[str, type[Style]] = {}
_COMPOSITES: dict[str, type[Style]] = {}  # made on first use, one class per spelling


def register(cls: type[Style]) -> type[Style]:
    """Add a style class to the registry (a class decorator).

    Args:
        cls: the style class; its `name` is the registry key.

    Returns:
        cls, unchanged.

    Raises:
        ValueError: a style of that name is registered already.
    """
    if not cls.name or cls.name in _STYLES:
        raise ValueError(f"style name {cls.name!r} is empty or taken")
    _STYLES[cls.name] = cls
    return cls


def names() -> list[str]:
    return sorted(_STYLES)


def get(name: str) -> type[Style]:
    """The class of a registered style, or of a composition 'a+b+...' (see `compose`).

    Args:
        name: a registered style name, or names joined by '+'.

    Returns:
        The style class.

    Raises:
        StyleError: an unknown name, or a composition that cannot be built.
    """
    try:
        return _STYLES[name]
    except KeyError:
        pass
    from .compose import composite_class, is_composite
    if is_composite(name):
        if name not in _COMPOSITES:
            _COMPOSITES[name] = composite_class(name, get)
        return _COMPOSITES[name]
    raise StyleError(
        f"unknown style '{name}': available styles are {', '.join(names())}, or a composition "
        f"such as contrast+sepia"
    ) from None


def create(name: str, **values: Any) -> Style:
    """A style instance by name, its parameters validated.

    Args:
        name: as for `get`.
        **values: parameter values, as `Param.parse` reads them.

    Returns:
        The style.

    Raises:
        StyleError: an unknown style or a bad parameter value.
    """
    return get(name)(**values)
