"""Equations of motion: Lagrange multipliers, Baumgarte stabilisation, clearance contact.

Seed paper eq. (24) (MODEL-NOTES 5)::

    [ M(q)   Phi_q^T ] [ qdd    ]   [ Q(q, qd, t)                          ]
    [ Phi_q  0       ] [ lambda ] = [ gamma - 2 alpha Phid - beta^2 Phi    ]

``Q = -h(q, qd) + sum_c J_c^T w_c + Q_f``: ``h`` gathers gravity and velocity terms
(Pinocchio's ``nonLinearEffects``), ``w_c`` are the clearance contact wrenches
(``clearance_contact``, about each element frame origin, world axes) mapped
through the ``LOCAL_WORLD_ALIGNED`` frame Jacobians ``J_c`` of those frames,
``Q_f`` the generalized force of the scene's force elements and force-driven
actuators (:mod:`robot.dynamics.forces`; absent, and free, when there are none).
``Phi`` holds the closures and the five driving constraints
``q_k - s_k(t) = 0`` (``robot.model.constraints``); ``Phid = Phi_q qd - [0; sd]``.

Pinocchio's ``forwardDynamics(model, data, tau, J, drift)`` solves the same KKT
system in C++ with its own signs: ``M qdd + h = tau + J^T lambda_pin`` and
``J qdd = -drift``. Hence ``drift = -(gamma - 2 alpha Phid - beta^2 Phi)`` and
``lambda = -lambda_pin`` in the paper's convention.

**Redundant rows** (overconstrained mechanisms): the system is solved on the
independent rows of ``Phi_q`` (:func:`solve_kkt`, :mod:`robot.model.redundancy`),
exact for a consistent system; the reported multipliers are the minimum-norm
ones, the driving forces unique.

**Driving force sign.** The driving row of actuator k is the unit row of its
prismatic coordinate (the leg length), so the actuator's generalized force is
``-lambda_k = lambda_pin_k``: ``driving_force > 0`` means the actuator pushes
(extends the leg), ``< 0`` pulls. In general ``driving_force`` is the generalized
force the actuator applies on its joint coordinate, positive in the direction of
increasing coordinate: N on a prismatic joint, N m about a revolute joint's axis
(right-hand rule); its power ``driving_force * qd_k`` is positive when the
actuator does work on the mechanism.

State of the integrator: ``y = [q, v, W_act, W_contact]``, and ``W_force`` after
them when the model has force elements (``DynamicsModel.n_work`` accumulators:
actuators, contact, force elements). A model without force elements keeps the
two-accumulator state, so its error norms and step sequences are unchanged.

Everything per-run lives in :class:`DynamicsWorkspace` (Pinocchio ``Data`` and
caches); :class:`DynamicsModel` is immutable.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
import weakref
from typing import Callable, NamedTuple, Protocol

import numpy as np
import pinocchio as pin

from clearance_contact import ContactError, SphericalClearanceJoint

from robot.dynamics.baumgarte import Baumgarte
from robot.errors import DriveError
from robot.dynamics.probe import Probe
from robot.model import constraints as C
from robot.model import redundancy as R
from robot.dynamics import rhs_kernels as K
from robot.model.mechanism import ClearanceSite, Mechanism
from robot.model.pinocchio_arrays import frame_jacobian, tangent_map_product
from robot.dynamics.forces.force_set import BoundForces, ForceSet

LWA = pin.ReferenceFrame.LOCAL_WORLD_ALIGNED


class Drive(Protocol):
    """Prescribed actuator coordinates: ``drive(t) -> (s, sd, sdd)``."""

    def drive(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]: ...


class ClearanceJointLaw(Protocol):
    """What the dynamics needs from a ``clearance_contact`` joint (a :class:`clearance_contact.ClearanceJoint`).

    ``KERNEL_ID``: the law's id in the compiled dispatcher (:func:`robot.dynamics.rhs_kernels.law_kernel`),
    None for a law the simulator evaluates through ``evaluate``; ``SITE_KINDS``: the joints it can replace.
    """

    n_candidates: int
    KERNEL_ID: int | None
    SITE_KINDS: tuple[str, ...]

    def evaluate(self, outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates): ...

    def penetration(self, outer_rotation, outer_position, inner_rotation, inner_position) -> np.ndarray: ...


@dataclass(frozen=True, eq=False)
class ContactSite:
    """A clearance site of the mechanism bound to its contact law."""

    site: ClearanceSite
    law: ClearanceJointLaw
    first_candidate: int  # offset of its candidates in the global candidate list

    @property
    def candidates(self) -> slice:
        return slice(self.first_candidate, self.first_candidate + self.law.n_candidates)


@dataclass(frozen=True, eq=False)
class DynamicsModel:
    """Mechanism + constraints + contact laws + prescribed motion + stabilisation."""

    mechanism: Mechanism
    constraints: C.ConstraintSet
    contacts: tuple[ContactSite, ...]
    drive: Drive
    baumgarte: Baumgarte = Baumgarte()
    end_effector_frame: int = -1
    forces: ForceSet | None = None  # force elements and force-driven actuators (robot.dynamics.forces)

    def __post_init__(self) -> None:
        # every model, however made (dataclasses.replace too): the compiled calls read the drive unchecked
        check_drive_size(self)

    @property
    def n_work(self) -> int:
        """Work accumulators after ``[q, v]``: actuators, contact, and force elements when there are any."""
        return 2 if self.forces is None else 3

    @property
    def state_size(self) -> int:
        """Length of the integrator's state ``[q, v, W_act, W_contact(, W_force)]``."""
        return self.nq + self.nv + self.n_work

    @property
    def n_candidates(self) -> int:
        return sum(c.law.n_candidates for c in self.contacts)

    @property
    def nq(self) -> int:
        return self.mechanism.model.nq

    @property
    def nv(self) -> int:
        return self.mechanism.model.nv


def make_dynamics_model(
    mechanism: Mechanism,
    laws: dict[str, ClearanceJointLaw],
    drive: Drive,
    baumgarte: Baumgarte = Baumgarte(),
    end_effector_frame: str | None = None,
    forces: ForceSet | None = None,
) -> DynamicsModel:
    """Bind every clearance site of ``mechanism`` to its law in ``laws`` (by site name)."""
    missing = [s.name for s in mechanism.clearance_sites if s.name not in laws]
    extra = [name for name in laws if name not in mechanism.clearance_names]
    if missing or extra:
        raise ValueError(f"contact laws must match the clearance sites {mechanism.clearance_names}: missing {missing}, unknown {extra}")
    contacts, offset = [], 0
    for site in mechanism.clearance_sites:
        law = laws[site.name]
        if site.kind not in law.SITE_KINDS:
            raise ValueError(
                f"clearance site {site.name!r} is a {site.kind} joint but its law {type(law).__name__} replaces "
                f"{' or '.join(law.SITE_KINDS)} joints"
            )
        contacts.append(ContactSite(site, law, offset))
        offset += law.n_candidates
    ee = mechanism.frame_id(end_effector_frame or "platform")
    return DynamicsModel(mechanism, C.constraint_set(mechanism, driven=True), tuple(contacts), drive, baumgarte, ee, forces)


@dataclass
class DynamicsWorkspace:
    """Per-run mutable state: Pinocchio data, counters and the hot path's prebound views."""

    data: pin.Data
    rhs_calls: int = 0
    kernel: C.ConstraintKernel | None = None  # Phi, Phi_q, gamma on ``data`` (views bound once)
    sites: tuple = ()  # per contact site: _SiteViews on ``data``
    drive: Callable | None = None  # the drive through its interpolation table (see DriveTable)
    zero_tau: np.ndarray = field(default_factory=lambda: np.zeros(0))
    compiled: "CompiledTerms | None" = None  # the compiled right-hand side's views, when it applies
    rows: R.RowSelection | None = None  # the rows the KKT solve uses (robot.model.redundancy), set on first solve
    rank_checks: int = 0  # redundancy detections after the first (a dropped row's check failed)
    forces: BoundForces | None = None  # the force elements on ``data``, when the model has any


def make_workspace(dynamics: DynamicsModel) -> DynamicsWorkspace:
    """The per-run state of ``dynamics``."""
    model = dynamics.mechanism.model
    data = model.createData()
    kernel = C.ConstraintKernel(dynamics.constraints, data)
    return DynamicsWorkspace(
        data,
        kernel=kernel,
        sites=tuple(_SiteViews(contact, data) for contact in dynamics.contacts),
        drive=drive_table(dynamics.drive),
        zero_tau=np.zeros(model.nv),
        compiled=CompiledTerms.for_dynamics(dynamics, data, kernel),
        forces=None if dynamics.forces is None else dynamics.forces.bind(model, data),
    )


def check_drive_size(dynamics: DynamicsModel) -> None:
    """Raise :class:`robot.errors.DriveError` unless the drive gives one value of s, sd and sdd per motion actuator.

    Checked at t = 0 whenever a :class:`DynamicsModel` is made (``dataclasses.replace``
    included), so a run's set-up (``clearance run --check``) refuses a wrong drive: the
    compiled right-hand side reads the drive's values without bounds checks
    (:func:`robot.dynamics.rhs_kernels.power_series`).
    """
    mechanism = dynamics.mechanism
    expected = len(mechanism.actuator_q_index) if dynamics.constraints.driven else 0
    sizes = [np.size(values) for values in dynamics.drive.drive(0.0)]
    if sizes != [expected] * 3:
        raise DriveError(
            f"the drive {type(dynamics.drive).__name__} returns {sizes} values of (s, sd, sdd) at t=0 but the mechanism "
            f"has {expected} motion-driven actuators {list(mechanism.actuated_joints)}: give the drive one value of s, "
            "sd and sdd per motion actuator, in that order",
            key="drive",
            value=sizes,
        )


class CompiledSite(NamedTuple):
    """One clearance joint on the compiled path (views into :class:`CompiledTerms`' packed arrays)."""

    law_kernel: Callable | None  # the law's compiled kernel, None for a law evaluated through its API
    parameters: np.ndarray | None  # the kernel's parameters
    masks: np.ndarray  # (2, nv) supports of the outer and inner element frames
    outer_frame: int
    inner_frame: int
    candidates: slice  # its contact candidates in the global list
    twists: np.ndarray  # (2, 6) LWA twists of the two frames (written by the kernels)
    outputs: np.ndarray | None  # the law's output buffer
    wrench_outer: int  # offsets of the wrenches in ``outputs`` (a Python law: in [outer, inner])
    wrench_inner: int


#: closure kinds whose rows :func:`robot.dynamics.rhs_kernels.closure_drift` computes (3 and 5 rows;
#: ``tests/test_integrators.py`` checks it covers every type a mechanism file may declare)
COMPILED_CLOSURE_KINDS = ("spherical", "revolute")


class CompiledTerms:
    """Views and index arrays of the compiled right-hand side (:mod:`robot.dynamics.rhs_kernels`) on one ``pin.Data``.

    Applies when every closure is spherical or revolute (:data:`COMPILED_CLOSURE_KINDS`:
    every closure type a mechanism file can declare; rows in constraint-set order, then the
    drivers); otherwise :func:`for_dynamics` returns None and
    :func:`state_derivative` takes the Python path. Redundant rows are handled
    after the kernels: they write every row, :func:`solve_kkt` uses the independent ones. A contact law with a
    compiled ``kernel`` (``clearance_contact``'s laws) is evaluated inside the
    compiled code; any other law through its ``evaluate``. The arrays the kernels
    read and write (but Pinocchio's and ``phi_q``) are views of two packed buffers,
    ``indices`` and ``work`` (:func:`robot.dynamics.rhs_kernels.pack`): a right-hand
    side is one compiled call before its KKT solve and one after.
    """

    def __init__(self, dynamics: DynamicsModel, data: pin.Data, kernel: C.ConstraintKernel):
        model = dynamics.mechanism.model
        closures = [rows.closure for rows in dynamics.constraints.closures]
        self.placements = K.placement_buffer(data.oMf)
        # views of Pinocchio's buffers; reshaped because eigenpy hands a 6 x 1 matrix (one-dof model) over as (6,)
        self.jacobian = data.J.reshape(6, model.nv)
        self.jacobian_rate = data.dJ.reshape(6, model.nv)
        self.phi_q = kernel.phi_q  # driving rows written once by the kernel
        # sizes as plain ints (a read of a Pinocchio property costs ~0.1 us)
        self.model, self.nq, self.nq_nv, self.state_size = model, model.nq, model.nq + model.nv, dynamics.state_size
        self.n_candidates = dynamics.n_candidates
        laws = [contact.law for contact in dynamics.contacts]
        # compiled: a law whose type has a kernel id (known to rhs_kernels.law_kernel) and whose kernel
        # does everything (``law.kernel`` is None e.g. for a user-defined friction law); others: ``evaluate``
        compiled_law = [getattr(law, "KERNEL_ID", None) in K.LAW_IDS.values() and law.kernel is not None for law in laws]
        self.laws_compiled = all(compiled_law)
        # every site is evaluated inside the compiled calls (rhs_kernels.all_sites): every law a shipped compiled
        # law (also when there is none: the fused calls then evaluate no site, and the probe is one call)
        self.sites_fused = self.laws_compiled and all(law.kernel in K.LAW_IDS for law in laws)
        parameters = [np.asarray(law.kernel_parameters, dtype=float) if ok else np.zeros(0) for law, ok in zip(laws, compiled_law)]
        # each site's [start, end) in the packed law parameters and outputs (empty for a law evaluated through its API)
        parameter_ranges = _consecutive_ranges([p.shape[0] for p in parameters])
        output_sizes = [law.output_size if ok else 0 for law, ok in zip(laws, compiled_law)]
        output_ranges = _consecutive_ranges(output_sizes)
        table = _site_table(dynamics, parameter_ranges, output_ranges) if self.sites_fused else np.zeros((0, K.SITE_COLUMNS))
        actuator_q, actuator_v = (dynamics.mechanism.actuator_q_index, dynamics.mechanism.actuator_v_index) if kernel.driven else ((), ())
        gains = dynamics.baumgarte
        self.indices, self.work, views = K.pack(
            {
                K.FRAMES_A: [c.frame_a for c in closures],
                K.FRAMES_B: [c.frame_b for c in closures],
                # closure i owns rows closure_rows[i]:closure_rows[i + 1] (3 spherical, 5 revolute); drivers after
                K.CLOSURE_ROWS: [rows.row for rows in dynamics.constraints.closures] + [kernel.n_closure_rows],
                K.ACTUATOR_Q: actuator_q,
                K.ACTUATOR_V: actuator_v,
                K.CLOSURE_MASKS: K.support_mask(model, [f for c in closures for f in (c.frame_a, c.frame_b)]),
                K.SITE_TABLE: table,
                K.SITE_MASKS: np.array(
                    [K.support_mask(model, [c.site.outer_frame, c.site.inner_frame]) for c in dynamics.contacts]
                ).reshape(len(laws), 2, model.nv),
                K.PROBE_GATHER: _probe_gather(dynamics, table) if self.sites_fused else np.zeros((0, 3)),
                K.DRIFT: np.zeros(kernel.n_rows),
                K.TAU: np.zeros(model.nv),
                K.GAINS: [2.0 * gains.alpha, gains.beta * gains.beta],
                K.DRIVE: np.zeros(3 * len(actuator_q)),
                K.LAW_PARAMETERS: np.concatenate([np.zeros(0), *parameters]),
                K.LAW_OUTPUTS: np.zeros(sum(output_sizes)),
                K.SITE_TWISTS: np.zeros((len(laws), 2, 6)),
            }
        )
        self.frames_a, self.frames_b, self.closure_rows = views[K.FRAMES_A], views[K.FRAMES_B], views[K.CLOSURE_ROWS]
        self.actuator_q, self.actuator_v, self.closure_masks = views[K.ACTUATOR_Q], views[K.ACTUATOR_V], views[K.CLOSURE_MASKS]
        self.site_table, self.site_masks, self.probe_gather = views[K.SITE_TABLE], views[K.SITE_MASKS], views[K.PROBE_GATHER]
        self.drift, self.tau, self.gains, self.drive_values = views[K.DRIFT], views[K.TAU], views[K.GAINS], views[K.DRIVE]
        self.site_parameters, self.site_outputs_buffer = views[K.LAW_PARAMETERS], views[K.LAW_OUTPUTS]
        self.site_twists = views[K.SITE_TWISTS]
        self._build_sites(dynamics, compiled_law, parameter_ranges, output_ranges)
        self._build_output_views(dynamics)

    def _build_sites(
        self,
        dynamics: DynamicsModel,
        compiled_law: list[bool],
        parameter_ranges: list[tuple[int, int]],
        output_ranges: list[tuple[int, int]],
    ) -> None:
        """One :class:`CompiledSite` per contact site: its parameters, masks, twists and outputs are views of the packed arrays."""
        self.sites = []
        sites = zip(dynamics.contacts, compiled_law, parameter_ranges, output_ranges)
        for index, (contact, ok, parameter_range, output_range) in enumerate(sites):
            law, site = contact.law, contact.site
            self.sites.append(
                CompiledSite(
                    law.kernel if ok else None,
                    self.site_parameters[slice(*parameter_range)] if ok else None,
                    self.site_masks[index],
                    site.outer_frame,
                    site.inner_frame,
                    contact.candidates,
                    self.site_twists[index],
                    self.site_outputs_buffer[slice(*output_range)] if ok else None,
                    law.WRENCH_OUTER if ok else 0,  # a Python law's wrenches are stacked [outer, inner]
                    law.WRENCH_INNER if ok else 6,
                )
            )

    def _build_output_views(self, dynamics: DynamicsModel) -> None:
        # per site: candidate slice and views of its law's penetration, rate and normal force outputs
        self.site_outputs = []
        for contact, site in zip(dynamics.contacts, self.sites):
            law, buffer, k = contact.law, site.outputs, contact.law.n_candidates
            if buffer is not None:
                self.site_outputs.append(
                    (
                        contact.candidates,
                        buffer[law.PENETRATION : law.PENETRATION + k],
                        buffer[law.PENETRATION_RATE : law.PENETRATION_RATE + k],
                        buffer[law.NORMAL_FORCE : law.NORMAL_FORCE + k],
                    )
                )

    @classmethod
    def for_dynamics(cls, dynamics: DynamicsModel, data: pin.Data, kernel: C.ConstraintKernel) -> "CompiledTerms | None":
        """The compiled terms, or None where the kernels do not have the closures' equations.

        :func:`robot.dynamics.rhs_kernels.closure_drift` has the rows of spherical and
        revolute closures, in constraint-set order; a closure of another kind, or one
        with a rotation offset on frame b (the misaligned centring rows of the initial
        assembly, never in a dynamics model), leaves the model to the Python path.
        """
        constraints = dynamics.constraints
        if any(rows.closure.kind not in COMPILED_CLOSURE_KINDS or rows.rotation_offset_b is not None for rows in constraints.closures):
            return None
        offsets = np.cumsum([0] + [rows.closure.n_equations for rows in constraints.closures])
        if [rows.row for rows in constraints.closures] != offsets[:-1].tolist() or constraints.n_closure_rows != offsets[-1]:
            return None
        return cls(dynamics, data, kernel)


def _consecutive_ranges(sizes: list[int]) -> list[tuple[int, int]]:
    """``[start, end)`` of each of ``sizes`` laid end to end from 0."""
    ends = np.cumsum(sizes, dtype=np.int64).tolist()
    return [(end - size, end) for size, end in zip(sizes, ends)]


def _site_table(dynamics: DynamicsModel, parameter_ranges: list[tuple[int, int]], output_ranges: list[tuple[int, int]]) -> np.ndarray:
    """The site table of :func:`robot.dynamics.rhs_kernels.all_sites` (every law a shipped compiled law)."""
    table = np.zeros((len(dynamics.contacts), K.SITE_COLUMNS), dtype=np.int64)
    for row, contact, parameter_range, output_range in zip(table, dynamics.contacts, parameter_ranges, output_ranges):
        law, site = contact.law, contact.site
        row[K.SITE_LAW] = K.LAW_IDS[law.kernel]
        row[K.SITE_OUTER], row[K.SITE_INNER] = site.outer_frame, site.inner_frame
        row[K.SITE_FIRST], row[K.SITE_LAST] = contact.candidates.start, contact.candidates.stop
        row[K.SITE_PARAMETERS], row[K.SITE_PARAMETERS_END] = parameter_range
        row[K.SITE_OUT], row[K.SITE_OUT_END] = output_range
        row[K.SITE_WRENCH_OUTER], row[K.SITE_WRENCH_INNER] = law.WRENCH_OUTER, law.WRENCH_INNER
    return table


def _probe_gather(dynamics: DynamicsModel, table: np.ndarray) -> np.ndarray:
    """Per candidate: where its penetration, rate and normal force lie in the packed law outputs (the probe)."""
    gather = np.zeros((dynamics.n_candidates, 3), dtype=np.int64)
    for contact, row in zip(dynamics.contacts, table):
        law, first = contact.law, row[K.SITE_OUT]
        for j in range(law.n_candidates):
            candidate = contact.candidates.start + j
            gather[candidate] = (first + law.PENETRATION + j, first + law.PENETRATION_RATE + j, first + law.NORMAL_FORCE + j)
    return gather


class DriveTable:
    """A drive's ``(s, sd, sdd)(t)`` through piecewise polynomials, verified against the drive.

    The exact drive of a platform trajectory (inverse kinematics, ~70 us a call)
    costs more than the rest of the right-hand side, so the integrator reads it
    from a table: on each segment of width ``width`` (built on first use) every
    output is interpolated at ``degree + 1`` Chebyshev nodes, and the polynomial
    is checked against the exact drive at ``checks`` points between the nodes; a
    segment whose check misses ``rtol`` (relative to the largest value of that
    output over the segment, for s, sd and sdd separately) is evaluated exactly
    instead. For the shipped smooth trajectories the table agrees with the drive
    to ~1e-15 relative (``tests/test_integrators.py``), far below any
    integration tolerance. ``exact_segments`` counts the fallbacks.
    """

    def __init__(self, drive: Drive, width: float = 1.0 / 16.0, degree: int = 13, rtol: float = 1e-12, checks: int = 2):
        try:  # a weak reference: the shared tables (drive_table) must not keep their drive alive
            self._drive = weakref.ref(drive)
        except TypeError:
            self._drive = lambda: drive
        self.width = float(width)
        self.degree = int(degree)
        self.rtol = float(rtol)
        n = self.degree + 1
        self.nodes = np.cos(np.pi * (np.arange(n) + 0.5) / n)[::-1]
        self.check_points = np.linspace(-1.0, 1.0, checks + 2)[1:-1] + 0.5 / (checks + 1)
        self.segments: dict[int, tuple[float, np.ndarray | None]] = {}  # per segment: its middle, coefficients (None: exact)
        self.exact_segments = 0
        self._to_unit = 2.0 / self.width
        self._low = self._high = math.nan  # the previous call's segment [low, high)
        self._last = None

    def _build(self, k: int):
        half = 0.5 * self.width
        middle = (k + 0.5) * self.width
        drive = self.drive
        samples = np.array([np.concatenate(drive.drive(middle + half * x)) for x in self.nodes])
        m = samples.shape[1] // 3
        if m == 0:  # no motion-driven actuator
            segment = (middle, np.zeros((self.degree + 1, 0)))
            self.segments[k] = segment
            return segment
        coefficients = np.linalg.solve(np.vander(self.nodes, self.degree + 1, increasing=True), samples)
        scale = np.abs(samples).reshape(len(self.nodes), 3, m).max(axis=(0, 2), initial=0.0)  # m = 0: no actuator
        ok = True
        for x in self.check_points:
            exact = np.concatenate(drive.drive(middle + half * x))
            fitted = np.empty(3 * m)
            K.power_series(coefficients, x, fitted)
            error = np.abs(fitted - exact).reshape(3, m).max(axis=1, initial=0.0)
            if not np.all(error <= self.rtol * np.maximum(scale, 1e-300)):
                ok = False
                break
        if not ok:
            self.exact_segments += 1
        segment = (middle, coefficients if ok else None)
        self.segments[k] = segment
        return segment

    @property
    def drive(self) -> Drive:
        return self._drive()

    def polynomial(self, t: float) -> tuple[np.ndarray, float]:
        """``(coefficients, x)``: ``[s, sd, sdd](t) = sum_k coefficients[k] x^k`` (:func:`robot.dynamics.rhs_kernels.power_series`).

        On a segment evaluated exactly: the exact values as the only row, ``x = 0``.
        """
        if not self._low <= t < self._high:  # not the segment of the previous call
            k = math.floor(t / self.width)
            segment = self.segments.get(k)
            if segment is None:
                segment = self._build(k)
            self._last = segment
            self._low, self._high = k * self.width, (k + 1) * self.width
        middle, coefficients = self._last
        if coefficients is None:
            return np.concatenate(self.drive.drive(t))[None, :], 0.0
        return coefficients, (t - middle) * self._to_unit

    def values(self, t: float) -> np.ndarray:
        """``[s, sd, sdd]`` at t as one new array (3 m values)."""
        coefficients, x = self.polynomial(t)
        out = np.empty(coefficients.shape[1])
        K.power_series(coefficients, x, out)
        return out

    def __call__(self, t: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        values = self.values(t)
        m = values.shape[0] // 3
        return values[:m], values[m : 2 * m], values[2 * m :]


_DRIVE_TABLES: "weakref.WeakKeyDictionary[object, DriveTable]" = weakref.WeakKeyDictionary()


def drive_table(drive: Drive) -> DriveTable:
    """The :class:`DriveTable` of ``drive``, shared by every workspace of the same drive object."""
    try:
        table = _DRIVE_TABLES.get(drive)
    except TypeError:  # not weak-referenceable or not hashable: a private table
        return DriveTable(drive)
    if table is None:
        table = DriveTable(drive)
        _DRIVE_TABLES[drive] = table
    return table


def normalise_quaternions(mechanism: Mechanism, q: np.ndarray) -> np.ndarray:
    """A copy of q with every free-flyer quaternion of unit norm (Pinocchio's ``normalize``)."""
    return pin.normalize(mechanism.model, np.asarray(q, dtype=float))


def configuration_rate(dynamics: DynamicsModel, workspace: DynamicsWorkspace, q: np.ndarray, v: np.ndarray) -> np.ndarray:
    """dq/dt from the generalized velocity v (free-flyer: local twist to position and quaternion rates).

    Free-flyer (Pinocchio): position rate ``R v_lin``; quaternion ``(x, y, z, w)``
    rate ``0.5 q (x) (omega, 0)`` with ``omega`` in the body frame. Computed by
    Pinocchio's tangent map (``tangentMapProduct``); ``q`` must have unit quaternions.
    """
    return tangent_map_product(dynamics.mechanism.model, q, v)


@dataclass
class Evaluation:
    """Everything computed at one (t, q, v): accelerations, multipliers, contacts."""

    qdd: np.ndarray
    multipliers: np.ndarray  # paper convention lambda (M qdd + Phi_q^T lambda = Q)
    residual: np.ndarray
    residual_rate: np.ndarray
    contacts: list
    generalized_contact_force: np.ndarray
    applied_force: np.ndarray | None = None  # Q of the force elements and force-driven actuators (None: none)
    force_scalars: np.ndarray | None = None  # each element's scalar force or torque (ForceSet order)

    def driving_force(self, constraints: C.ConstraintSet) -> np.ndarray:
        return -self.multipliers[constraints.driving_rows]


def element_states(data: pin.Data, model: pin.Model, site: ClearanceSite):
    """Rotation, position and twist (world axes) of the outer and inner element frames."""
    outer, inner = data.oMf[site.outer_frame], data.oMf[site.inner_frame]
    outer_twist = pin.getFrameVelocity(model, data, site.outer_frame, LWA).vector
    inner_twist = pin.getFrameVelocity(model, data, site.inner_frame, LWA).vector
    return outer.rotation, outer.translation, outer_twist, inner.rotation, inner.translation, inner_twist


def evaluate(
    dynamics: DynamicsModel,
    workspace: DynamicsWorkspace,
    t: float,
    q: np.ndarray,
    v: np.ndarray,
    onset_rates: np.ndarray,
) -> Evaluation:
    """Solve the stabilised KKT system (paper eq. (24)) at (t, q, v).

    Evaluates every contact law (the full contact state is returned); the
    integrator's right-hand side uses :func:`state_derivative` instead. The drive
    is read from the same verified table as in the right-hand side
    (:class:`DriveTable`, exact to 1e-12 relative; the exact inverse kinematics
    cost ~70 us a call).
    """
    model, data = dynamics.mechanism.model, workspace.data
    kernel = workspace.kernel
    workspace.rhs_calls += 1
    s, sd, sdd = workspace.drive(t)
    pin.computeAllTerms(model, data, q, v)
    pin.updateFramePlacements(model, data)
    phi, gam = kernel.update(q, s, sdd)
    phi_q = kernel.phi_q
    phi_dot = phi_q @ v
    if kernel.driven:
        phi_dot[kernel.n_closure_rows :] -= sd
    gains = dynamics.baumgarte
    rhs = gam - 2.0 * gains.alpha * phi_dot - gains.beta**2 * phi
    tau = np.zeros(model.nv)
    contacts = []
    for contact, views in zip(dynamics.contacts, workspace.sites):
        result = contact.law.evaluate(*views.states(model, data), onset_rates[contact.candidates])
        contacts.append(result)
        if np.any(result.in_contact):
            views.add_generalized_force(model, data, result, tau)
    forces = workspace.forces
    applied = None if forces is None else forces.evaluate(t, q, v).copy()
    qdd = solve_kkt(dynamics, workspace, tau if applied is None else tau + applied, phi_q, -rhs).copy()
    scalars = None if forces is None else forces.scalars.copy()
    return Evaluation(qdd, -workspace.rows.full_multipliers(phi_q, data.lambda_c), phi, phi_dot, contacts, tau, applied, scalars)


def solve_kkt(dynamics: DynamicsModel, workspace: DynamicsWorkspace, tau: np.ndarray, phi_q: np.ndarray, drift: np.ndarray) -> np.ndarray:
    """qdd of the KKT system (paper eq. (24), Pinocchio's signs) on the workspace's independent rows.

    ``data.lambda_c`` then holds Pinocchio's multipliers of those rows (the driving ones
    from ``workspace.rows.n_closure_kept``). The rows are detected on the first call and
    again when a dropped row's equation is not met (:mod:`robot.model.redundancy`);
    without redundant rows this is ``forwardDynamics`` on every row. Needs the joint
    Jacobians and frame placements of the current state on the workspace's data.
    Returns Pinocchio's ``data.ddq`` (overwritten by the next solve).
    """
    model, data = dynamics.mechanism.model, workspace.data
    rows = workspace.rows
    if rows is None:
        rows = workspace.rows = R.detect(dynamics.constraints, model, data, phi_q)
    if rows.full:
        return pin.forwardDynamics(model, data, tau, phi_q, drift)
    qdd = pin.forwardDynamics(model, data, tau, phi_q[rows.independent], drift[rows.independent])
    if not rows.consistent(phi_q, drift, qdd):
        workspace.rank_checks += 1
        fresh = R.detect(dynamics.constraints, model, data, phi_q, previous=rows)
        if not fresh.same_rows(rows):
            workspace.rows = fresh
            independent = fresh.independent
            qdd = pin.forwardDynamics(model, data, tau, phi_q if fresh.full else phi_q[independent], drift if fresh.full else drift[independent])
    return qdd


def state_derivative(
    dynamics: DynamicsModel,
    workspace: DynamicsWorkspace,
    t: float,
    y: np.ndarray,
    onset_rates: np.ndarray,
) -> np.ndarray:
    """dy/dt of the simulation state ``y = [q, v, W_act, W_contact(, W_force)]`` (the integrator's right-hand side).

    The same equations as :func:`evaluate` (plus :func:`configuration_rate` and the
    actuator and contact powers), on the hot path: quaternions normalised in a
    copy of q, the drive through its interpolation table (:class:`DriveTable`).
    Mechanisms whose closures are all spherical or revolute (every closure type a
    mechanism file declares) take the compiled path (:class:`CompiledTerms`, :mod:`robot.dynamics.rhs_kernels`: Pinocchio's
    CRBA, RNEA, joint Jacobians and their rates in C++, the closure rows, frame
    twists, compiled contact laws and ``J^T w`` in numba); others the Python
    path (the constraint kernel's prebound views, a contact law evaluated only
    when its cheap ``penetration()`` shows contact). Raises ``ContactError`` as
    :func:`evaluate` does.
    """
    workspace.rhs_calls += 1
    compiled = workspace.compiled
    if compiled is not None:
        return _compiled_state_derivative(dynamics, workspace, compiled, t, y, onset_rates)
    mechanism = dynamics.mechanism
    model, data = mechanism.model, workspace.data
    kernel = workspace.kernel
    nq, nv = model.nq, model.nv
    q = pin.normalize(model, y[:nq])  # a copy with unit quaternions
    v = y[nq : nq + nv]
    s, sd, sdd = workspace.drive(t)
    pin.computeAllTerms(model, data, q, v)
    pin.updateFramePlacements(model, data)
    gains = dynamics.baumgarte
    # Pinocchio's drift is minus the stabilised right-hand side
    drift = kernel.stabilised_drift(q, v, s, sd, sdd, 2.0 * gains.alpha, gains.beta * gains.beta)
    tau = None
    for contact, views in zip(dynamics.contacts, workspace.sites):
        # a site in contact at the previous call is evaluated directly; otherwise its cheap
        # penetration() decides whether the law is needed at all
        if views.touching or views.maybe_in_contact():
            result = contact.law.evaluate(*views.states(model, data), onset_rates[contact.candidates])
            views.touching = not max(result.penetration.tolist()) <= 0.0
            if views.touching:
                if tau is None:
                    tau = np.zeros(nv)
                views.add_generalized_force(model, data, result, tau)
    out = np.empty(nq + nv + dynamics.n_work)
    total = workspace.zero_tau if tau is None else tau
    if workspace.forces is not None:
        total = total + workspace.forces.evaluate(t, q, v)
    out[nq : nq + nv] = solve_kkt(dynamics, workspace, total, kernel.phi_q, drift)
    out[:nq] = tangent_map_product(model, q, v)
    # actuator power: driving force (= Pinocchio's multiplier of the driving row) times the actuator rate
    out[nq + nv] = data.lambda_c[workspace.rows.n_closure_kept :] @ v[mechanism.actuator_v_index] if kernel.driven else 0.0
    out[nq + nv + 1] = 0.0 if tau is None else tau @ v
    if workspace.forces is not None:
        _add_force_powers(workspace.forces, out, nq + nv)
    return out


def _add_force_powers(forces: BoundForces, out: np.ndarray, offset: int) -> None:
    """Force-driven actuators' power into the actuator power, the elements' power into the force power."""
    out[offset] += forces.powers[0]
    out[offset + 2] = forces.powers[1]


def _compiled_state_derivative(
    dynamics: DynamicsModel,
    workspace: DynamicsWorkspace,
    compiled: CompiledTerms,
    t: float,
    y: np.ndarray,
    onset_rates: np.ndarray,
) -> np.ndarray:
    """:func:`state_derivative` through :mod:`robot.dynamics.rhs_kernels` (same equations)."""
    model, data, nq = compiled.model, workspace.data, compiled.nq
    if not y.flags.c_contiguous:  # a column of a 2-D array (scipy's difference Jacobians): the kernels take contiguous v
        y = np.ascontiguousarray(y)
    q = pin.normalize(model, y[:nq])  # a copy with unit quaternions
    v = y[nq : compiled.nq_nv]
    coefficients, x = workspace.drive.polynomial(t)
    # C++: M (CRBA), h (RNEA at zero acceleration), world joint Jacobians and their rates, frames
    pin.nonLinearEffects(model, data, q, v)
    pin.crba(model, data, q)
    pin.computeJointJacobiansTimeVariation(model, data, q, v)
    pin.updateFramePlacements(model, data)
    work, indices, phi_q, tau = compiled.work, compiled.indices, compiled.phi_q, compiled.tau
    # the drive, closure rows and drift, tau = 0, and every site when all laws are shipped compiled laws
    code = K.rhs_terms(
        work, indices, compiled.placements, compiled.jacobian, compiled.jacobian_rate, q, v, coefficients, x, onset_rates, phi_q
    )
    if code != 0:
        _raise_site_failure(dynamics, workspace, compiled, code, onset_rates, t)
    if not compiled.sites_fused:
        _compiled_sites(dynamics, workspace, compiled, t, v, onset_rates, tau)
    out = np.empty(compiled.state_size)
    # force elements: data.oMi and data.J are at q (computeJointJacobiansTimeVariation)
    forces = workspace.forces
    qdd = solve_kkt(dynamics, workspace, tau if forces is None else tau + forces.evaluate(t, q, v), phi_q, compiled.drift)
    # [q', qdd, actuator power (driving force = Pinocchio's multiplier of the driving row, times the rate), contact power]
    K.finish_derivative(work, indices, data.lambda_c, workspace.rows.n_closure_kept, v, qdd, tangent_map_product(model, q, v), out)
    if forces is not None:
        _add_force_powers(forces, out, compiled.nq_nv)
    return out


def _compiled_sites(
    dynamics: DynamicsModel, workspace: DynamicsWorkspace, compiled: CompiledTerms, t: float, v: np.ndarray, onset_rates: np.ndarray, tau: np.ndarray
) -> None:
    """Evaluate every clearance joint site by site at the kinematics in ``workspace.data``; ``tau += J^T w``.

    The compiled path where not every law is a shipped compiled law (otherwise the
    compiled calls evaluate every site, :func:`robot.dynamics.rhs_kernels.all_sites`):
    each law's outputs in its buffer, a law without a compiled kernel through its ``evaluate``.
    """
    placements, jacobian = compiled.placements, compiled.jacobian
    for index, (law_kernel, parameters, masks, outer, inner, candidates, twists, buffer, w_outer, w_inner) in enumerate(compiled.sites):
        onset = onset_rates[candidates]
        views = workspace.sites[index]
        K.site_twists(placements, jacobian, masks, outer, inner, v, twists)
        if law_kernel is None:
            result = views.law.evaluate(views.outer_rotation, views.outer_position, twists[0], views.inner_rotation, views.inner_position, twists[1], onset)
            buffer = np.concatenate([result.wrench_outer, result.wrench_inner])
        else:
            status = law_kernel(parameters, views.outer_rotation, views.outer_position, twists[0], views.inner_rotation, views.inner_position, twists[1], onset, buffer)
            if status != 0:
                _raise_contact_error(dynamics, workspace, index, twists, onset, t, status)
        K.add_site_wrenches(placements, jacobian, masks, outer, inner, buffer, w_outer, w_inner, tau)


def _raise_site_failure(dynamics: DynamicsModel, workspace: DynamicsWorkspace, compiled: CompiledTerms, code: int, onset_rates, t: float):
    """:func:`robot.dynamics.rhs_kernels.all_sites` returned ``code != 0`` (``16 * (site + 1) + status``): raise its error."""
    index = code // 16 - 1
    site = compiled.sites[index]
    _raise_contact_error(dynamics, workspace, index, site.twists, onset_rates[site.candidates], t, code % 16)


def _raise_contact_error(dynamics: DynamicsModel, workspace: DynamicsWorkspace, index: int, twists, onset, t: float, status: int):
    """A compiled law returned ``status != 0``: raise a ``ContactError`` naming the site and t, with the message
    of the law's ``evaluate`` (its informative error on the same input) when it raises one."""
    views, name = workspace.sites[index], dynamics.contacts[index].site.name
    outer, inner = (views.outer_rotation, views.outer_position, twists[0]), (views.inner_rotation, views.inner_position, twists[1])
    try:
        views.law.evaluate(*outer, *inner, onset)
    except ContactError as exc:
        message = f"contact law of {name!r} failed at t={t!r}: {exc}"
        try:  # the law's own class (ContactParameterError is also a ValueError callers may catch)
            error = type(exc)(message, key=exc.key, value=exc.value)
        except TypeError:  # a subclass with a constructor of its own
            error = ContactError(message, key=exc.key, value=exc.value)
        raise error from exc
    raise ContactError(f"contact law of {name!r} failed (status {status}) at t={t!r}")


_NO_DRIVE = (np.zeros((1, 0)), 0.0)  # the probe's drive polynomial when the residual is not asked for (not read)


def contact_probe(
    dynamics: DynamicsModel, workspace: DynamicsWorkspace, t: float, q: np.ndarray, v: np.ndarray, onset_rates: np.ndarray, residual: bool = True
) -> Probe:
    """Penetration, penetration rate and normal force of every candidate, and max |Phi|, at (t, q, v).

    Kinematics only (no dynamics): what the simulation checks after every step
    (events, failures, force maxima). ``q`` must have unit quaternions.
    ``residual=False`` skips max |Phi| (reported as NaN; the compiled path only).
    """
    model, data = dynamics.mechanism.model, workspace.data
    compiled = workspace.compiled
    n = dynamics.n_candidates if compiled is None else compiled.n_candidates
    pen, rate, force = np.empty(n), np.empty(n), np.empty(n)
    if compiled is not None and compiled.laws_compiled:
        pin.computeJointJacobians(model, data, q)
        pin.updateFramePlacements(model, data)
        # compiled.tau receives the (unused) J^T w: every right-hand side starts by zeroing it
        if compiled.sites_fused:
            coefficients, x = workspace.drive.polynomial(t) if residual else _NO_DRIVE
            code, worst = K.probe_terms(
                compiled.work, compiled.indices, compiled.placements, compiled.jacobian, q, v, coefficients, x, onset_rates,
                pen, rate, force, residual,
            )  # fmt: skip
            if code != 0:
                _raise_site_failure(dynamics, workspace, compiled, code, onset_rates, t)
            return Probe(pen, rate, worst, force)
        worst = math.nan
        if residual:
            worst = K.largest_residual(
                compiled.placements, compiled.frames_a, compiled.frames_b, compiled.closure_rows, q, workspace.drive.values(t), compiled.actuator_q
            )
        _compiled_sites(dynamics, workspace, compiled, t, v, onset_rates, compiled.tau)
        for candidates, penetration, penetration_rate, normal_force in compiled.site_outputs:
            pen[candidates] = penetration
            rate[candidates] = penetration_rate
            force[candidates] = normal_force
        return Probe(pen, rate, worst, force)
    pin.forwardKinematics(model, data, q, v)
    pin.updateFramePlacements(model, data)
    residual = workspace.kernel.residual(q, workspace.drive(t)[0])
    for contact, views in zip(dynamics.contacts, workspace.sites):
        result = contact.law.evaluate(*views.states(model, data), onset_rates[contact.candidates])
        pen[contact.candidates] = result.penetration
        rate[contact.candidates] = result.penetration_rate
        force[contact.candidates] = result.normal_force
    return Probe(pen, rate, (float(np.max(np.abs(residual))) if residual.size else 0.0), force)


class _SiteViews:
    """A contact site's element frames on one ``pin.Data``: rotation and translation views bound once."""

    def __init__(self, contact: ContactSite, data: pin.Data):
        site = contact.site
        self.law = contact.law
        self.outer_frame, self.inner_frame = site.outer_frame, site.inner_frame
        outer, inner = data.oMf[site.outer_frame], data.oMf[site.inner_frame]
        self.outer_rotation, self.outer_position = outer.rotation, outer.translation
        self.inner_rotation, self.inner_position = inner.rotation, inner.translation
        # the spherical law's penetration is |b - s| - c: inline it (exactly the law's formula)
        law = contact.law
        self.sphere_clearance = law.socket_radius - law.ball_radius if type(law) is SphericalClearanceJoint else None
        self.touching = False  # in contact at the previous right-hand side (a hint, never a shortcut to a force)

    def states(self, model: pin.Model, data: pin.Data):
        """Arguments of ``law.evaluate`` but the onset rates (as :func:`element_states`)."""
        return (
            self.outer_rotation,
            self.outer_position,
            pin.getFrameVelocity(model, data, self.outer_frame, LWA).vector,
            self.inner_rotation,
            self.inner_position,
            pin.getFrameVelocity(model, data, self.inner_frame, LWA).vector,
        )

    def maybe_in_contact(self) -> bool:
        """False only if every candidate's penetration is <= 0 (a NaN pose answers True)."""
        if self.sphere_clearance is not None:
            depth = math.dist(self.inner_position.tolist(), self.outer_position.tolist()) - self.sphere_clearance
            return not depth <= 0.0
        depth = max(self.law.penetration(self.outer_rotation, self.outer_position, self.inner_rotation, self.inner_position).tolist())
        return not depth <= 0.0

    def add_generalized_force(self, model: pin.Model, data: pin.Data, result, tau: np.ndarray) -> None:
        """tau += J_outer^T w_outer + J_inner^T w_inner (LOCAL_WORLD_ALIGNED frame Jacobians)."""
        tau += frame_jacobian(model, data, self.outer_frame).T @ result.wrench_outer
        tau += frame_jacobian(model, data, self.inner_frame).T @ result.wrench_inner


def penetrations(dynamics: DynamicsModel, workspace: DynamicsWorkspace, q: np.ndarray) -> np.ndarray:
    """Penetration of every contact candidate at q (positions only; cheap, for event functions)."""
    if not dynamics.contacts:
        return np.zeros(0)
    model, data = dynamics.mechanism.model, workspace.data
    pin.framesForwardKinematics(model, data, q)
    out = np.empty(dynamics.n_candidates)
    for contact, views in zip(dynamics.contacts, workspace.sites):
        out[contact.candidates] = contact.law.penetration(views.outer_rotation, views.outer_position, views.inner_rotation, views.inner_position)
    return out


def inverse_dynamics_driving_forces(
    dynamics: DynamicsModel, workspace: DynamicsWorkspace, q: np.ndarray, v: np.ndarray, qdd: np.ndarray
) -> np.ndarray:
    """Closed-loop inverse dynamics of the ideal mechanism: the multipliers that produce ``qdd``.

    ``Phi_q^T lambda = -h - M qdd`` solved in the least-squares sense (exact for a
    consistent motion); returns the driving forces ``-lambda_drive``. Independent
    of the integrator: used to check the simulated driving forces.
    """
    model, data = dynamics.mechanism.model, workspace.data
    tau = pin.rnea(model, data, q, v, qdd)  # M qdd + h
    pin.computeJointJacobians(model, data, q)
    pin.updateFramePlacements(model, data)
    phi_q = C.jacobian(dynamics.constraints, model, data)
    multipliers, *_ = np.linalg.lstsq(phi_q.T, -tau, rcond=None)
    return -multipliers[dynamics.constraints.driving_rows]


def energy(dynamics: DynamicsModel, workspace: DynamicsWorkspace, q: np.ndarray, v: np.ndarray) -> tuple[float, float]:
    """Kinetic and potential (gravity) energy of the mechanism."""
    model, data = dynamics.mechanism.model, workspace.data
    return float(pin.computeKineticEnergy(model, data, q, v)), float(pin.computePotentialEnergy(model, data, q))

