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

Plain data: importing this module imports neither Pinocchio nor the solvers'
numerics (classes may be given as ``"module:attribute"`` and are imported on use).
The old per-trait tables (``METHODS``, ``FIXED_STEP_METHODS``,
``JACOBIAN_METHODS``, ``STRUCTURED_METHODS``, ``STAGES``) are live read-only views
of the registry (:func:`names`, :class:`TraitView`).
"""

from __future__ import annotations

import functools
import importlib
from collections.abc import Iterator, Mapping
from dataclasses import dataclass
from typing import Callable


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
        """The solver class (imported now if it was registered by name)."""
        if isinstance(self.solver, str):
            module, _, attribute = self.solver.partition(":")
            return getattr(importlib.import_module(module), attribute)
        return self.solver

    def is_available(self) -> bool:
        return self.available is None or bool(self.available())


_REGISTRY: dict[str, IntegratorTraits] = {}


def register(traits: IntegratorTraits, *, replace: bool = False) -> IntegratorTraits:
    """Add a method to the registry (``replace=True`` to redefine an existing name)."""
    if not isinstance(traits, IntegratorTraits):
        raise TypeError(f"register() takes IntegratorTraits, got {type(traits).__name__}")
    if traits.name in _REGISTRY and not replace:
        raise ValueError(f"integrator method={traits.name!r} is already registered (pass replace=True to redefine it)")
    if traits.fixed_step and traits.step_sizes and min(traits.step_sizes) <= 0:
        raise ValueError(f"integrator method={traits.name!r}: step_sizes={traits.step_sizes!r} must be positive")
    _REGISTRY[traits.name] = traits
    return traits


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
