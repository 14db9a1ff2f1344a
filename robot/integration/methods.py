"""The registry of integrators: one :class:`IntegratorTraits` per method name.

Everything the step loop (:mod:`robot.integration.event_loop`), the solver
factory (:func:`robot.integration.solvers.make_solver`), the scene parser and the
studies need to know about a method is one record here, so a new method is one
:func:`register` call in its own file (next to its ``OdeSolver`` class)::

    register(IntegratorTraits("Euler", solver=ExplicitEuler, fixed_step=True, explicit=True, stages=1, replayable=True))

The traits decide:

* ``fixed_step``: the step size is ``first_step`` (no error control; no
  step-size-collapse check; restarts keep ``first_step``);
* ``explicit``: no Newton iterations (the Newton-Euler cross-check offers the
  explicit variable-step methods, :data:`robot.validation.event_loop.SOLVERS`);
* ``takes_jacobian``: the Newton iterations take a user ``df/dy`` (``jac=``);
* ``second_order_structure``: the method needs the layout ``y = [q, v, extra]``
  and the configuration update (``structure=``, Lie-group methods);
* ``stages``: right-hand sides per attempted step (explicit Runge-Kutta, FSAL),
  from which rejected steps are counted; None: not countable that way;
* ``replayable``: an accepted step is a function of its start state and size
  only, so the force-peak search can redo an earlier step exactly; otherwise it
  interpolates the recorded end states (cubic Hermite);
* ``step_sizes``: default step sizes of the work-precision sweep (fixed step);
* ``available``: False when an optional dependency is missing (CVODE without
  scikit-sundae): the method is then not on offer.

:func:`register` checks the traits (types and ranges: a bad one is refused with
a :class:`robot.errors.RegistrationError` naming the field, its value and the
valid range) and the solver class: an ``OdeSolver``-like class (``step``,
``dense_output``; ``_step_impl`` and ``_dense_output_impl`` implemented if it
derives from a base ``OdeSolver``; a constructor taking the arguments
:func:`robot.integration.solvers.make_solver` passes for these traits). A class
given as ``"module:attribute"`` is imported and checked when the method is first
looked up (the scene's ``[solver]`` validation), the error naming the method.

Plain data: importing this module imports neither Pinocchio nor the solvers'
numerics (classes may be given as ``"module:attribute"`` and are imported on use).
The old per-trait tables (``METHODS``, ``FIXED_STEP_METHODS``,
``JACOBIAN_METHODS``, ``STRUCTURED_METHODS``, ``STAGES``) are live read-only views
of the registry (:func:`names`, :class:`TraitView`).
"""

from __future__ import annotations

import functools
import importlib
import inspect
import math
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Callable, NoReturn


@dataclass(frozen=True)
class IntegratorTraits:
    """What the step loop, the solver factory and the studies know about one integration method."""

    name: str
    #: the solver class (the contract of ``scipy.integrate.OdeSolver``: scipy's methods or a subclass of
    #: :class:`robot.integration.solver_base.OdeSolver`), or ``"module:attribute"`` imported on first use
    solver: type | str
    fixed_step: bool = False
    explicit: bool = False
    takes_jacobian: bool = False
    second_order_structure: bool = False
    stages: int | None = None
    replayable: bool = False
    step_sizes: tuple[float, ...] = ()
    available: Callable[[], bool] | None = None
    description: str = ""

    def solver_class(self) -> type:
        """The solver class (imported and checked on first use if it was registered by name)."""
        if isinstance(self.solver, str):
            return _imported_solver_class(self)
        return self.solver

    def is_available(self) -> bool:
        return self.available is None or bool(self.available())


_REGISTRY: dict[str, IntegratorTraits] = {}


def register(traits: IntegratorTraits, *, replace: bool = False) -> IntegratorTraits:
    """Add a method to the registry (``replace=True`` to redefine an existing name); its traits and class checked."""
    if not isinstance(traits, IntegratorTraits):
        _refuse(f"register() takes IntegratorTraits, got {type(traits).__name__}", "traits", traits)
    if traits.name in _REGISTRY and not replace:
        _refuse(f"integrator method={traits.name!r} is already registered (pass replace=True to redefine it)", "name", traits.name)
    check_traits(traits)
    if not isinstance(traits.solver, str):
        check_solver_class(traits, traits.solver)
    _REGISTRY[traits.name] = traits
    return traits


#: the boolean traits
FLAGS = ("fixed_step", "explicit", "takes_jacobian", "second_order_structure", "replayable")


def check_traits(traits: IntegratorTraits) -> None:
    """RegistrationError naming the first field of ``traits`` of a wrong type or out of its range."""
    name = traits.name
    if not isinstance(name, str) or not name or name.strip() != name:
        _refuse(f"integrator name={name!r} must be a non-empty string without surrounding spaces", "name", name)
    where = f"integrator method={name!r}"
    for flag in FLAGS:
        value = getattr(traits, flag)
        if not isinstance(value, bool):
            _refuse(f"{where}: {flag}={value!r} must be True or False", flag, value)
    stages = traits.stages
    if stages is not None and (isinstance(stages, bool) or not isinstance(stages, int) or stages < 1):
        _refuse(
            f"{where}: stages={stages!r} must be None or an integer in the valid range [1, inf): the right-hand sides "
            "of one attempted step, from which the rejected steps are counted (None: not countable that way)",
            "stages",
            stages,
        )
    sizes = traits.step_sizes
    if not isinstance(sizes, tuple) or not all(isinstance(h, (int, float)) and not isinstance(h, bool) and 0 < h < math.inf for h in sizes):
        _refuse(f"{where}: step_sizes={sizes!r} must be a tuple of step sizes in s, each in the valid range (0, inf)", "step_sizes", sizes)
    if traits.available is not None and not callable(traits.available):
        _refuse(f"{where}: available={traits.available!r} must be None or a function returning True or False", "available", traits.available)
    if not isinstance(traits.description, str):
        _refuse(f"{where}: description={traits.description!r} must be a string", "description", traits.description)
    solver = traits.solver
    if isinstance(solver, str):
        module, colon, attribute = solver.partition(":")
        if not (colon and all(part.isidentifier() for part in module.split(".")) and attribute.isidentifier()):
            _refuse(f"{where}: solver={solver!r} must be a class or 'module:attribute' (e.g. 'scipy.integrate:RK45')", "solver", solver)
    elif not isinstance(solver, type):
        _refuse(f"{where}: solver={solver!r} must be a class (an OdeSolver subclass) or 'module:attribute', not a {type(solver).__name__}", "solver", solver)


def check_solver_class(traits: IntegratorTraits, cls: object) -> None:
    """RegistrationError unless ``cls`` is an ``OdeSolver``-like class the solver factory can build for ``traits``."""
    where = f"integrator method={traits.name!r}: solver {getattr(cls, '__module__', '?')}.{getattr(cls, '__qualname__', cls)}"
    if not isinstance(cls, type):
        _refuse(f"{where} is not a class (give an OdeSolver subclass)", "solver", cls)
    problems = [f"it has no method {method}()" for method in ("step", "dense_output") if not callable(getattr(cls, method, None))]
    problems += [f"it does not implement {method} (the base OdeSolver's raises NotImplementedError)" for method in _BASE_STUBS if _inherits_stub(cls, method)]
    problems += [_constructor_problem(traits, cls)]
    problems = [p for p in problems if p]
    if problems:
        _refuse(
            f"{where} is not an OdeSolver-like class: {'; '.join(problems)} (robot.integration.solver_base describes the contract)",
            "solver",
            cls,
        )


#: methods a subclass of a base ``OdeSolver`` (this package's or scipy's) must implement
_BASE_STUBS = ("_step_impl", "_dense_output_impl")
_BASE_MODULES = ("robot.integration.solver_base", "scipy.integrate._ivp.base")


def _inherits_stub(cls: type, method: str) -> bool:
    """Whether ``cls.method`` is the not-implemented stub of a base ``OdeSolver`` (scipy's is not imported to tell)."""
    function = getattr(cls, method, None)
    return function is not None and getattr(function, "__qualname__", "") == f"OdeSolver.{method}" and getattr(function, "__module__", "") in _BASE_MODULES


def _constructor_problem(traits: IntegratorTraits, cls: type) -> str | None:
    """Why ``cls(fun, t0, y0, t_bound, **options)`` cannot be called as the solver factory calls it for ``traits``."""
    if traits.second_order_structure:
        options: tuple[str, ...] = ("first_step", "rtol", "atol", "structure")
    elif traits.fixed_step:
        options = ("first_step",)
    else:
        options = ("rtol", "atol", "max_step", "first_step") + (("jac",) if traits.takes_jacobian else ())
    try:
        signature = inspect.signature(cls)
    except (TypeError, ValueError):  # not introspectable: not checked
        return None
    try:
        signature.bind("fun", "t0", "y0", "t_bound", **{option: None for option in options})
    except TypeError:
        return f"its constructor {cls.__name__}{signature} does not take (fun, t0, y0, t_bound, {', '.join(o + '=' for o in options)})"
    return None


@functools.lru_cache(maxsize=None)
def _imported_solver_class(traits: IntegratorTraits) -> type:
    """The class named ``"module:attribute"`` by ``traits.solver``, imported and checked (cached once it passes)."""
    module, _, attribute = traits.solver.partition(":")
    try:
        cls = getattr(importlib.import_module(module), attribute)
    except (ImportError, AttributeError) as exc:
        _refuse(
            f"integrator method={traits.name!r}: its solver {traits.solver!r} cannot be imported ({type(exc).__name__}: {exc}); "
            "install the module or fix the name given to register()",
            "solver",
            traits.solver,
        )
    check_solver_class(traits, cls)
    return cls


def _refuse(message: str, key: str, value: object) -> NoReturn:
    """Raise the RegistrationError (imported here: the registry stays plain data, see the module docstring)."""
    from robot.errors import RegistrationError

    raise RegistrationError(message, key=key, value=value)


def unregister(name: str) -> None:
    """Remove a method (tests that register a toy method clean up with it)."""
    _REGISTRY.pop(name, None)


def names(predicate: Callable[[IntegratorTraits], bool] | None = None) -> list[str]:
    """The available methods, in registration order, optionally those whose traits satisfy ``predicate``."""
    return [name for name, t in _REGISTRY.items() if t.is_available() and (predicate is None or predicate(t))]


def traits(method: str) -> IntegratorTraits:
    """The traits of an available method; ``ValueError`` naming the method and the choices otherwise."""
    found = _REGISTRY.get(method)
    if found is None or not found.is_available():
        raise ValueError(f"integrator method={method!r} is not on offer; choose one of {', '.join(names())}")
    return found


class TraitView(Mapping):
    """A live read-only mapping ``method -> value`` over the registry (the old trait tables, kept as views)."""

    def __init__(self, value: Callable[[IntegratorTraits], object], keep: Callable[[IntegratorTraits], bool] = lambda t: True):
        self._value, self._keep = value, keep

    def __getitem__(self, method: str):
        found = _REGISTRY.get(method)
        if found is None or not found.is_available() or not self._keep(found):
            raise KeyError(method)
        return self._value(found)

    def __iter__(self) -> Iterator[str]:
        return iter(names(self._keep))

    def __len__(self) -> int:
        return len(names(self._keep))

    def __repr__(self) -> str:
        return f"{type(self).__name__}({dict(self)!r})"


@functools.cache
def _cvode_importable() -> bool:
    """CVODE runs through its C interface (the libraries scikit-sundae ships) or else scikit-sundae's binding.

    The binding is imported only when the libraries cannot be loaded directly:
    ``sksundae`` imports ``scipy.sparse`` and ``scipy.optimize`` (0.3-0.6 s).
    """
    from robot.integration import cvode_direct  # ctypes and numpy only

    return cvode_direct.available() or cvode_direct.scikit_sundae_cvode() is not None


#: method name -> solver class (the methods on offer)
METHODS: Mapping[str, type] = TraitView(IntegratorTraits.solver_class)
#: fixed-step methods (``first_step`` is the step size); a mapping used as a set of names
FIXED_STEP_METHODS: Mapping[str, bool] = TraitView(lambda t: True, lambda t: t.fixed_step)
#: methods whose Newton iterations take a user Jacobian
JACOBIAN_METHODS: Mapping[str, bool] = TraitView(lambda t: True, lambda t: t.takes_jacobian)
#: methods that need the second-order structure of the state
STRUCTURED_METHODS: Mapping[str, bool] = TraitView(lambda t: True, lambda t: t.second_order_structure)
#: right-hand-side calls per attempted step (explicit Runge-Kutta, FSAL)
STAGES: Mapping[str, int] = TraitView(lambda t: t.stages, lambda t: t.stages is not None)
#: default step sizes of the work-precision sweep (fixed-step methods)
STEP_SIZES: Mapping[str, tuple[float, ...]] = TraitView(lambda t: t.step_sizes, lambda t: bool(t.step_sizes))

# scipy's own methods (explicit Runge-Kutta first: RK45 is the default)
register(IntegratorTraits("RK45", "scipy.integrate:RK45", explicit=True, stages=6, replayable=True, description="Dormand-Prince 5(4)"))
register(IntegratorTraits("RK23", "scipy.integrate:RK23", explicit=True, stages=3, replayable=True, description="Bogacki-Shampine 3(2)"))
register(IntegratorTraits("DOP853", "scipy.integrate:DOP853", explicit=True, stages=12, replayable=True, description="Dormand-Prince 8(5,3)"))
register(IntegratorTraits("Radau", "scipy.integrate:Radau", takes_jacobian=True, description="implicit Runge-Kutta Radau IIA, order 5"))
register(IntegratorTraits("BDF", "scipy.integrate:BDF", takes_jacobian=True, description="backward differentiation formulas, orders 1-5"))
register(IntegratorTraits("LSODA", "scipy.integrate:LSODA", takes_jacobian=True, description="Adams / BDF with stiffness switching"))
# the package's own methods (classes in robot.integration.solvers)
register(
    IntegratorTraits(
        "RK4", "robot.integration.solvers:FixedStepRK4", fixed_step=True, explicit=True, stages=4, replayable=True,
        step_sizes=(2e-5, 1e-5, 5e-6, 2.5e-6), description="classical Runge-Kutta, fixed step",
    )
)
for _name, _class, _what in (("GenAlpha", "GeneralizedAlpha", "rho_inf = 0.8"), ("Newmark", "Newmark", "rho_inf = 1, trapezoidal rule")):
    register(
        IntegratorTraits(
            _name, f"robot.integration.solvers:{_class}", fixed_step=True, second_order_structure=True,
            step_sizes=(3e-5, 1e-5, 3e-6, 1e-6), description=f"generalized-alpha on the Lie group, {_what}, fixed step",
        )
    )
for _name, _class in (("CVODE_BDF", "CVODEBDF"), ("CVODE_Adams", "CVODEAdams")):
    register(IntegratorTraits(_name, f"robot.integration.solvers:{_class}", takes_jacobian=True, available=_cvode_importable, description="SUNDIALS CVODE"))
