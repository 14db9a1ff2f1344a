"""The registry of clearance joint types: ``type = "NAME"`` in a scene -> a :class:`~clearance_contact.joint.ClearanceJoint` subclass.

The shipped types (``spherical``, ``revolute``) register themselves where they are
defined; a new type registers itself the same way, from any module::

    from clearance_contact import ClearanceJoint, register_joint_type

    @register_joint_type
    class PointOnPlane(ClearanceJoint):
        type_name = "point_on_plane"
        ...

Everything else (scene parser, simulator, result files, animation) asks
:func:`joint_type` for the class and the class for its keys, layout and drawing.
"""

from __future__ import annotations

import importlib

from .errors import ContactParameterError, require_unregistered
from .joint import ClearanceJoint

__all__ = ["register_joint_type", "joint_type", "joint_types", "COMMON_SCENE_KEYS"]

#: scene keys of every clearance joint, read by the scene parser itself (a type's keys must differ)
COMMON_SCENE_KEYS = frozenset({"joint", "type", "outer_on", "material", "outer_material", "inner_material", "restitution", "friction"})

_TYPES: dict[str, type[ClearanceJoint]] = {}

#: the shipped types' modules: imported (so registered) on the first look-up, not at package import
BUILTIN_MODULES = ("clearance_contact.spherical", "clearance_contact.revolute", "clearance_contact.translational")
_builtins_loaded = False


def _load_builtins() -> None:
    """Import the shipped types' modules (they register themselves), once.

    Marked loaded only after every import succeeded: a failed import leaves the
    registry to try again on the next look-up (the types registered so far stay;
    registering the same class again is allowed).
    """
    global _builtins_loaded
    if not _builtins_loaded:
        for module in BUILTIN_MODULES:
            importlib.import_module(module)
        _builtins_loaded = True


def register_joint_type(cls: type[ClearanceJoint]) -> type[ClearanceJoint]:
    """Register ``cls`` under ``cls.type_name`` and return it (usable as a class decorator).

    The shipped types are loaded first (unless ``cls`` is one of them, registering
    itself), so that a user type can never take a shipped type's name, whenever it
    is registered.  Raises :class:`ContactParameterError` if ``cls`` is not a :class:`ClearanceJoint`
    subclass with a name, candidates and a kernel, if its scene keys clash with the
    common ones, or if another class already holds the name (registering the same
    class again is allowed: modules may be reloaded).
    """
    if not (isinstance(cls, type) and issubclass(cls, ClearanceJoint)):
        raise ContactParameterError(f"joint type {cls!r} must be a subclass of clearance_contact.ClearanceJoint")
    name = cls.type_name
    if not isinstance(name, str) or not name.isidentifier():
        raise ContactParameterError(f"{cls.__name__}.type_name={name!r} must be a non-empty identifier")
    if cls.N_CANDIDATES < 1 or cls.N_ECCENTRICITY < 0:
        raise ContactParameterError(
            f"{cls.__name__}: N_CANDIDATES={cls.N_CANDIDATES!r} must be >= 1 and N_ECCENTRICITY={cls.N_ECCENTRICITY!r} >= 0"
        )
    if cls.kernel_function is None or cls.penetration_kernel is None:
        raise ContactParameterError(f"{cls.__name__} must define kernel and penetration_kernel")
    clash = sorted(COMMON_SCENE_KEYS & set(cls.SCENE_KEYS))
    missing = sorted(set(cls.REQUIRED_KEYS + cls.GEOMETRY_KEYS + cls.NAME_KEYS) - set(cls.SCENE_KEYS))
    if clash or missing:
        raise ContactParameterError(
            f"{cls.__name__}: SCENE_KEYS must not repeat the common keys ({', '.join(clash) or 'none'}) and must "
            f"contain REQUIRED_KEYS, GEOMETRY_KEYS and NAME_KEYS (missing: {', '.join(missing) or 'none'})"
        )
    if cls.__module__ not in BUILTIN_MODULES:
        _load_builtins()
    require_unregistered("joint type", name, _TYPES.get(name), cls, sorted(_TYPES), key="type_name")
    _TYPES[name] = cls
    return cls


def joint_type(name: str) -> type[ClearanceJoint]:
    """The class registered as ``name``; :class:`ContactParameterError` naming the registered ones otherwise."""
    _load_builtins()
    try:
        return _TYPES[name]
    except (KeyError, TypeError):
        raise ContactParameterError(
            f"clearance joint type {name!r} is not registered; registered types: {', '.join(sorted(_TYPES))}"
        ) from None


def joint_types() -> tuple[str, ...]:
    """The registered type names, sorted."""
    _load_builtins()
    return tuple(sorted(_TYPES))
