"""The registry of force element types: ``@register("spring_damper")`` on a :class:`ForceElement` subclass.

A scene's ``[[force]]`` table with ``type = "NAME"`` is parsed by
``FORCE_TYPES["NAME"].parse`` (no Pinocchio) and built on the mechanism by
``FORCE_TYPES["NAME"].build``. A new element type is one module of this package
that defines and registers its class (imported by the package's ``__init__``).
"""

from __future__ import annotations

from typing import Callable, TypeVar

from robot.dynamics.forces.base import ForceElement

FORCE_TYPES: dict[str, type[ForceElement]] = {}

E = TypeVar("E", bound=type[ForceElement])


def register(type_name: str) -> Callable[[E], E]:
    """Class decorator: make ``cls`` the element of ``type = type_name``."""

    def decorate(cls: E) -> E:
        if type_name in FORCE_TYPES:
            raise ValueError(f"force element type {type_name!r} is registered twice ({FORCE_TYPES[type_name].__name__}, {cls.__name__})")
        cls.type_name = type_name
        FORCE_TYPES[type_name] = cls
        return cls

    return decorate
