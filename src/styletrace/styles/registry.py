"""Name -> style class. The CLI, the Mitsuba plugin and the docs all read this one table."""
from __future__ import annotations

from typing import Any

from styletrace.styles.base import Style
from styletrace.styles.params import StyleError

_STYLES: dict[str, type[Style]] = {}
_COMPOSITES: dict[str, type[Style]] = {}  # made on first use, one class per spelling


def register_style(cls: type[Style]) -> type[Style]:
    """Add a style class to the registry (a class decorator).

    Args:
        cls: the Style subclass; its `name` is the registry key.

    Returns:
        cls, unchanged.

    Raises:
        ValueError: the name is empty or taken.
    """
    if not cls.name or cls.name in _STYLES:
        raise ValueError(f"style name {cls.name!r} is empty or taken")
    _STYLES[cls.name] = cls
    return cls


def style_names() -> list[str]:
    """The registered styles' names, sorted (compositions not included)."""
    return sorted(_STYLES)


def style_class(name: str) -> type[Style]:
    """The class of a registered style, or of a composition 'a+b+...' (see `compose`).

    Args:
        name: a registered name, or operands joined by '+' (its class is made once and kept).

    Returns:
        The Style subclass.

    Raises:
        StyleError: an unknown style, or a bad composition.
    """
    try:
        return _STYLES[name]
    except KeyError:
        pass
    from styletrace.styles.compose import composite_class, is_composite
    if is_composite(name):
        if name not in _COMPOSITES:
            _COMPOSITES[name] = composite_class(name, style_class)
        return _COMPOSITES[name]
    raise StyleError(
        f"unknown style '{name}': available styles are {', '.join(style_names())}, or a "
        f"composition such as contrast+sepia"
    ) from None


def create(name: str, **values: Any) -> Style:
    """A style by name with its parameter values.

    Args:
        name: as `style_class` takes it.
        **values: parameter name -> value, as `Style` takes them.

    Returns:
        The style.

    Raises:
        StyleError: an unknown style, an unknown parameter or a bad value.
    """
    return style_class(name)(**values)
