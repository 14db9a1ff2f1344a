"""The registry of force element types: ``@register("spring_damper")`` on a :class:`ForceElement` subclass.

A scene's ``[[force]]`` table with ``type = "NAME"`` is parsed by
``FORCE_TYPES["NAME"].parse`` (no Pinocchio) and built on the mechanism by
``FORCE_TYPES["NAME"].build``. A new element type is one module of this package
that defines and registers its class (imported by the package's ``__init__``),
or a user's module imported before the scene is loaded.

:func:`register` checks the class against the contract of :class:`ForceElement`
(``docs/dynamics.md``, "Adding a force element"): the methods it must define and the
arguments they are called with, ``KEYS``, ``state_dependent`` and ``actuator``;
it refuses a class that breaks it with a :class:`robot.errors.RegistrationError`
naming the class and what is wrong. It also makes the class's ``parse`` report a
failure other than a :class:`robot.errors.RobotError` (a ``KeyError`` for a
missing key, ...) as a :class:`SceneError` naming the element and the exception.
"""

from __future__ import annotations

import functools
import inspect
from typing import Callable, TypeVar

from robot.dynamics.forces.base import ForceElement
from robot.errors import RegistrationError, RobotError, SceneError

FORCE_TYPES: dict[str, type[ForceElement]] = {}

E = TypeVar("E", bound=type[ForceElement])

#: method -> the arguments the simulator calls it with (after ``self`` or ``cls``)
CALLED_WITH: dict[str, tuple[str, ...]] = {
    "parse": ("table", "where", "base_dir"),
    "build": ("name", "parameters", "mechanism", "where"),
    "apply": ("kinematics", "t", "q", "v", "out"),
    "potential_energy": ("kinematics", "q"),
}
#: exceptions of a user's ``parse`` reported as a SceneError (a RobotError passes as raised)
PARSE_FAILURES = (LookupError, TypeError, ValueError, ArithmeticError)
_GUARDED = "_reports_scene_errors"  # marks the parse wrapper of a registered class


def register(type_name: str) -> Callable[[E], E]:
    """Class decorator: make ``cls`` the element of ``type = type_name`` (its contract checked first)."""
    if not isinstance(type_name, str) or not type_name.strip():
        raise RegistrationError(f"force element type name {type_name!r} must be a non-empty string (the scene's type = ...)", key="type", value=type_name)

    def decorate(cls: E) -> E:
        if type_name in FORCE_TYPES:
            raise RegistrationError(
                f"force element type {type_name!r} is registered twice ({FORCE_TYPES[type_name].__name__}, {class_name(cls)}): "
                "choose another type name",
                key="type",
                value=type_name,
            )
        check_contract(cls, type_name)
        _report_parse_failures_as_scene_errors(cls)
        cls.type_name = type_name
        FORCE_TYPES[type_name] = cls
        return cls

    return decorate


def check_contract(cls: type, type_name: str) -> None:
    """RegistrationError naming ``cls`` and everything it lacks of the :class:`ForceElement` contract."""
    if not (isinstance(cls, type) and issubclass(cls, ForceElement)):
        raise RegistrationError(f"force element type {type_name!r}: {cls!r} is not a subclass of robot.dynamics.forces.ForceElement", key="type", value=type_name)
    problems = [f"it does not define {name}" for name in sorted(getattr(cls, "__abstractmethods__", ()))]
    signature_problems = (_signature_problem(cls, method) for method in CALLED_WITH)
    problems += [problem for problem in signature_problems if problem]
    keys = getattr(cls, "KEYS", None)
    if not isinstance(keys, (set, frozenset)) or not all(isinstance(key, str) for key in keys):
        problems.append(f"KEYS={keys!r} must be a set of the scene keys (strings) of its [[force]] table")
    for flag in ("state_dependent", "actuator"):
        if not isinstance(getattr(cls, flag, None), bool):
            problems.append(f"{flag}={getattr(cls, flag, None)!r} must be True or False")
    if problems:
        raise RegistrationError(
            f"force element type {type_name!r} ({class_name(cls)}) does not meet the ForceElement contract: {'; '.join(problems)} "
            "(docs/dynamics.md, 'Adding a force element')",
            key="type",
            value=type_name,
        )


def _signature_problem(cls: type, method: str) -> str | None:
    """Why ``cls.method`` cannot be called as the simulator calls it; None if it can (or its signature is unknown)."""
    function = getattr(cls, method, None)
    if function is None or getattr(function, "__isabstractmethod__", False):
        return None  # reported as not defined
    if not callable(function):
        return f"{method} is not callable"
    arguments = CALLED_WITH[method]
    bound_to_class = method in ("parse", "build")
    try:
        signature = inspect.signature(function)
    except (TypeError, ValueError):  # a builtin or an odd callable: not checked
        return None
    try:
        signature.bind(*(() if bound_to_class else ("self",)), *arguments)
    except TypeError:
        shown = ", ".join(arguments) if bound_to_class else ", ".join(("self", *arguments))
        kind = "a classmethod " if bound_to_class else ""
        return f"{method}{signature} cannot be called as {kind}{method}({shown})"
    return None


def _report_parse_failures_as_scene_errors(cls: type) -> None:
    """Wrap ``cls.parse`` (once along the class tree): PARSE_FAILURES become a SceneError naming the element."""
    parse = inspect.getattr_static(cls, "parse")
    if getattr(getattr(parse, "__func__", parse), _GUARDED, False):
        return  # inherited from a registered class: already wrapped (and bound to the class it is called on)
    descriptor = isinstance(parse, (classmethod, staticmethod))

    @functools.wraps(getattr(parse, "__func__", parse))
    def guarded(klass, table, where, base_dir):
        user_parse = parse.__get__(None, klass) if descriptor else parse  # a classmethod binds to the class called on
        try:
            return user_parse(table, where, base_dir)
        except RobotError:
            raise
        except PARSE_FAILURES as exc:
            raise _parse_failure(klass, where, exc) from exc

    setattr(guarded, _GUARDED, True)
    cls.parse = classmethod(guarded)


def _parse_failure(cls: type, where: str, exc: Exception) -> SceneError:
    """The SceneError for a user's ``parse`` that raised ``exc`` (a KeyError: the key is missing)."""
    if isinstance(exc, KeyError) and exc.args:
        key = exc.args[0]
        return SceneError(f"{where}: key {key!r} is missing ({class_name(cls)}.parse needs it): add {key} = ... to the [[force]] table", key=str(key))
    return SceneError(
        f"{where}: {class_name(cls)}.parse could not read the table ({type(exc).__name__}: {exc}): check the values of its keys "
        f"({', '.join(sorted(getattr(cls, 'KEYS', ())))})"
    )


def class_name(cls: object) -> str:
    """``module.qualname`` of a class (what messages name an element's class by)."""
    return f"{getattr(cls, '__module__', '?')}.{getattr(cls, '__qualname__', repr(cls))}"
