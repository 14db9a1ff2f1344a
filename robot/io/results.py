"""Simulation results: derived outputs, the result object and the ``.npz`` result file.

:func:`compute_outputs` evaluates the equations of motion once more at every
recorded state (integration steps, contact onsets and penetration maxima), or
only at those a scene's ``[output]`` table keeps, and returns the arrays users
look at (:mod:`robot.io.record_outputs`: through the compiled right-hand side
where it applies). :class:`Result` holds them with the run's
status, message and counts (like ``scipy.integrate.solve_ivp``'s ``OdeResult``),
in memory and loaded from a file alike.
:func:`save_result` writes one ``.npz`` atomically; :func:`load_result` reads it
back and checks it.

Arrays (n records): ``t``; ``q`` (n x nq), ``v`` (n x nv); ``driving_force``
(n x motion-driven actuators; N on a prismatic joint, N m on a revolute one, positive
in the direction of increasing coordinate: the actuator pushes); ``ee_position``,
``ee_velocity``, ``ee_acceleration`` (n x 3, world, of the end-effector frame
origin); ``constraint_residual`` (n, max |Phi|); ``kinetic_energy``,
``potential_energy``, ``actuator_power``, ``contact_power``, ``actuator_work``,
``contact_work`` (n; works integrated with the motion: actuators, motion- and
force-driven, and contact); with force elements (``robot.dynamics.forces``) also
``force_work`` (n, their integrated work), ``force_energy`` (n, energy stored in them) and per
element ``force_NAME`` (n, its scalar force, N, or torque, N m); ``record_kind`` (n, what
each record is, below); ``onset_rates`` (n x candidates, the Lankarani-Nikravesh
approach rate in use at each record); per clearance joint
J: ``J_eccentricity`` (n x 3 spherical; n x 2 x 3 revolute, top and bottom ring;
n x 2 x 3 translational, front and rear end of the slider), ``J_centre_in_outer``
(n x 3, the ball / journal / slider centre in the socket / bearing / guide frame),
``J_penetration``, ``J_normal_force``, ``J_friction_force`` (magnitude),
``J_kind`` (n x candidates), and per group of candidates of the type
(``ClearanceJoint.FORCE_GROUPS``) the magnitude of the resultant normal force:
``J_radial_force`` (spherical, revolute), ``J_axial_force`` (revolute),
``J_lateral_force`` (translational). With contact events also ``event_t``,
``event_candidate``, ``event_is_onset``, ``event_kind`` (the record kind each
event wrote: 1 onset, 2 penetration maximum, 5 force maximum) and ``event_value``
(the event log: onsets with their approach rate, penetration maxima with their
depth, force maxima with the force in N).

Record kinds (``record_kind``; constants ``robot.integration.simulation.RECORD_*``; records
are sorted by time, so kinds 1, 2, 4 and 5 fall between step ends and the spacing
is not uniform):

* 0 ``RECORD_STEP``: the end of an accepted integration step (spacing at most
  ``max_step``);
* 1 ``RECORD_ONSET``: a contact onset located on the step's dense output; the
  step was cut there and the solver restarted from this state;
* 2 ``RECORD_PEAK``: a penetration maximum inside a step (penetration rate
  crossing zero while in contact);
* 3 ``RECORD_START``: the initial state (one record, the first);
* 4 ``RECORD_OUTPUT``: a point of the regular output grid ``k * output_step``
  (``SolverOptions.output_step``: a scene's ``[output] step``, 2e-4 s unless
  the scene sets another, none with ``step = 0``; sweeps and work-precision
  runs set their own, the validation study none), from the dense output of the
  step containing it; select them with ``result["record_kind"] == 4`` to
  compare runs at common times;
* 5 ``RECORD_FORCE_PEAK``: a candidate's normal-force maximum over the
  compression phase ending at a penetration maximum (``dF/dt = 0``, located on
  the dense output; with damping it precedes the penetration maximum), so the
  maximum of ``J_normal_force`` over the records is the located peak force, not
  a sampled value.

Status: ``status`` 0 and ``cause`` ``None`` for a run that reached the end;
``status`` -1 for a run stopped on divergence, with ``message`` (starting with
the time) and ``cause``, one of ``non-finite state``, ``penetration beyond
physical bound``, ``constraint drift``, ``step size collapse``, ``event
chattering``, ``wall time``, ``unphysical pose``, ``Newton divergence``,
``solver error``, ``contact law error``, ``interrupted``: what triggers each and what to do is in
``docs/dynamics.md`` ("Failure causes"). The arrays then hold every record up to
the stop.
"""

from __future__ import annotations

import dataclasses
import hashlib
import json
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np

from robot.dynamics import equations as D
from robot.io.array_names import ALWAYS_KEPT, is_bulk
from robot.io.atomic import atomic_write
from robot.io.npz_writer import write_npz
from robot.io.record_outputs import derived_outputs
from robot.errors import ResultFileError
from robot.integration.simulation import RECORD_FORCE_PEAK, RECORD_ONSET, RECORD_OUTPUT, RECORD_PEAK, RECORD_STEP, Trajectory
from robot.scene.loader import OutputSpec

FORMAT_VERSION = 1
#: event log kind -> the record kind it wrote (``event_kind``)
_EVENT_KINDS = {"onset": RECORD_ONSET, "peak": RECORD_PEAK, "force_peak": RECORD_FORCE_PEAK}


class JointSeries:
    """The arrays of one clearance joint of a :class:`Result` (``result.joint("R1")``).

    Attributes are the result's arrays ``NAME_*`` without the prefix:
    ``penetration``, ``normal_force``, ``friction_force``, ``kind`` (n x candidates),
    ``eccentricity`` and whatever else the joint type writes; ``keys()`` lists them.
    """

    def __init__(self, name: str, arrays: dict[str, np.ndarray]):
        self.name = name
        self._arrays = arrays

    def keys(self) -> list[str]:
        return sorted(self._arrays)

    def __getattr__(self, key: str) -> np.ndarray:
        arrays = self.__dict__.get("_arrays", {})
        if key in arrays:
            return arrays[key]
        raise AttributeError(f"clearance joint {self.__dict__.get('name')!r} has no array {key!r}; it has {sorted(arrays)}")

    def __getitem__(self, key: str) -> np.ndarray:
        return getattr(self, key)

    def __repr__(self) -> str:
        return f"JointSeries({self.name!r}, keys={self.keys()})"


#: counter names of :attr:`Result.counts` and their scipy ``OdeResult`` names
COUNT_ALIASES = {"nfev": "n_rhs", "njev": "n_jacobians", "nsteps": "n_steps", "nrejected": "n_rejected", "nevents": "n_events"}


@dataclass
class Result:
    """One run, finished or stopped, in memory or loaded from a file (one type for both).

    Follows :class:`scipy.integrate.OdeResult`: ``t``, the state (``q``, ``v``;
    ``y`` stacks them as (nq + nv, n) like ``solve_ivp``), ``status`` (0 reached
    the end, -1 stopped: see ``cause``), ``message``, ``success``, counts
    ``nfev`` (right-hand-side calls), ``njev`` (Jacobians; ``None`` when the method
    has none or does not count them), ``nsteps``, ``nrejected`` (``None`` when
    unknown), ``nevents``. Per clearance joint: ``result.joint("R1").normal_force``.
    Every array is also ``result["KEY"]`` (the module docstring lists them).
    """

    scene: str
    status: int
    message: str
    cause: str | None
    t_end: float
    counts: dict[str, float]
    arrays: dict[str, np.ndarray]
    metadata: dict[str, Any] = field(default_factory=dict)

    @property
    def success(self) -> bool:
        return self.status == 0

    def __getitem__(self, key: str) -> np.ndarray:
        try:
            return self.arrays[key]
        except KeyError:
            raise KeyError(f"result of scene {self.scene!r} has no array {key!r}; it has {sorted(self.arrays)}") from None

    def keys(self) -> list[str]:
        return sorted(self.arrays)

    @property
    def t(self) -> np.ndarray:
        return self.arrays["t"]

    @property
    def q(self) -> np.ndarray:
        return self.arrays["q"]

    @property
    def v(self) -> np.ndarray:
        return self.arrays["v"]

    @property
    def y(self) -> np.ndarray:
        return np.hstack([self.q, self.v]).T

    def __getattr__(self, name: str):
        if name in COUNT_ALIASES:
            value = self.__dict__["counts"].get(COUNT_ALIASES[name])
            return None if value is None or value < 0 else int(value)
        raise AttributeError(f"{type(self).__name__!r} object has no attribute {name!r}")

    @property
    def clearance_joints(self) -> list[str]:
        return list(self.metadata.get("clearance", []))

    def joint(self, name: str) -> JointSeries:
        """The arrays of clearance joint ``name`` (one of :attr:`clearance_joints`)."""
        if name not in self.clearance_joints:
            raise ResultFileError(
                f"joint={name!r} is not a clearance joint of scene {self.scene!r}; its clearance joints are {self.clearance_joints}"
            )
        prefix = f"{name}_"
        return JointSeries(name, {k[len(prefix):]: v for k, v in self.arrays.items() if k.startswith(prefix)})

    def save(self, path: str | Path, output: "OutputSpec | None" = None) -> Path:
        """Write the result file (:func:`save_result`; ``output``: a scene's ``[output]`` selection)."""
        return save_result(self, path, output)

    def __repr__(self) -> str:
        n = len(self.arrays.get("t", ()))
        return (
            f"Result(scene={self.scene!r}, status={self.status}, success={self.success}, t_end={self.t_end:g}, "
            f"records={n}, nfev={self.nfev}, nsteps={self.nsteps}, clearance_joints={self.clearance_joints}, message={self.message!r})"
        )


#: the former name of :class:`Result` (kept as an alias)
SimulationResult = Result


def kept_rows(kind: np.ndarray, output: OutputSpec | None) -> np.ndarray | None:
    """The records a scene's ``[output]`` table keeps (bool mask over time-sorted records), None for all.

    With an output grid (``output.step``, when the run recorded it: record kind 4
    present) the ends of integration steps are dropped; the grid, every located
    record (start, onsets, penetration and force maxima) and the last record
    (where a failed run stopped) stay. None also when every record stays (the
    outputs were computed at the kept records only): saving then copies no array.
    """
    if output is None or output.step is None or not np.any(kind == RECORD_OUTPUT):
        return None
    rows = kind != RECORD_STEP
    rows[-1] = True
    return None if rows.all() else rows


def compute_outputs(dynamics: D.DynamicsModel, trajectory: Trajectory, output: OutputSpec | None = None) -> dict[str, np.ndarray]:
    """Evaluate the recorded states; arrays sorted by time (events are interleaved).

    ``output``: evaluate only the records this ``[output]`` selection keeps
    (:func:`kept_rows`; what the result file will hold), None: every record. The
    derived arrays come from :func:`robot.io.record_outputs.derived_outputs`.
    """
    nq, nv = dynamics.nq, dynamics.nv
    order = np.argsort(trajectory.t, kind="stable")
    rows = kept_rows(trajectory.kind[order], output)
    if rows is not None:
        order = order[rows]
    t = trajectory.t[order]
    y = trajectory.y[order]
    onset = trajectory.onset_rates[order]
    out: dict[str, np.ndarray] = {
        "t": t,
        "q": y[:, :nq],
        "v": y[:, nq : nq + nv],
        "record_kind": trajectory.kind[order],
        "onset_rates": onset,
        "actuator_work": y[:, nq + nv],
        "contact_work": y[:, nq + nv + 1],
    }
    if dynamics.forces is not None:
        out["force_work"] = y[:, nq + nv + 2]  # the force elements' (the force-driven actuators' is in actuator_work)
    out.update(derived_outputs(dynamics, t, y, onset))
    return out


def make_result(
    scene_name: str, dynamics: D.DynamicsModel, trajectory: Trajectory, metadata: dict[str, Any], output: OutputSpec | None = None
) -> Result:
    """The :class:`Result` of a trajectory (``output``: evaluate only the records it keeps, :func:`compute_outputs`)."""
    counts = {
        "n_steps": trajectory.n_steps,
        "n_rejected": trajectory.n_rejected,
        "n_rhs": trajectory.n_rhs,
        "n_events": trajectory.n_events,
        "n_restarts": trajectory.n_restarts,
        "n_jacobians": trajectory.n_jacobians,
        "cpu_time": trajectory.cpu_time,
        "wall_time": trajectory.wall_time,
    }
    arrays = compute_outputs(dynamics, trajectory, output)
    if trajectory.events:
        arrays["event_t"] = np.array([e[0] for e in trajectory.events])
        arrays["event_candidate"] = np.array([e[1] for e in trajectory.events], dtype=int)
        arrays["event_is_onset"] = np.array([e[2] == "onset" for e in trajectory.events])
        arrays["event_kind"] = np.array([_EVENT_KINDS[e[2]] for e in trajectory.events], dtype=np.int8)
        arrays["event_value"] = np.array([e[3] for e in trajectory.events])
    return Result(scene_name, trajectory.status, trajectory.message, trajectory.cause, trajectory.t_end, counts, arrays, metadata)


def select_records(result: Result, output: OutputSpec) -> Result:
    """The result as a scene's ``[output]`` table asks to keep it (a new object; arrays not copied when unchanged).

    With an output grid (``output.step``, when the run recorded it: record kind 4
    present), the ends of integration steps are dropped; the grid and every
    located record (start, onsets, penetration and force maxima) and the last
    record (where a failed run stopped) stay, so the peaks keep their exact
    values. ``output.keep`` selects arrays (``t``, ``record_kind`` always stay);
    ``output.precision = "float32"`` casts the bulk arrays (:mod:`robot.io.array_names`).
    """
    kind = result.arrays["record_kind"]
    n = kind.shape[0]
    rows = kept_rows(kind, output)
    wanted = None if output.keep is None else set(output.keep) | set(ALWAYS_KEPT)
    arrays = {}
    for key, value in result.arrays.items():
        if wanted is not None and key not in wanted:
            continue
        if rows is not None and not key.startswith("event_") and value.ndim and value.shape[0] == n:
            value = value[rows]
        if output.precision == "float32" and value.dtype == np.float64 and is_bulk(key):
            value = value.astype(np.float32)
        arrays[key] = value
    metadata = dict(result.metadata, output={"step": output.step, "keep": output.keep and list(output.keep), "precision": output.precision})
    return dataclasses.replace(result, arrays=arrays, metadata=metadata)


def save_result(result: Result, path: str | Path, output: OutputSpec | None = None) -> Path:
    """Write the result as one ``.npz`` file, atomically (header as JSON in ``__meta__``; :mod:`robot.io.npz_writer`).

    ``output``: the scene's ``[output]`` table (:func:`select_records`); ``None`` writes every array as it is.
    """
    if output is not None:
        result = select_records(result, output)
    header = {
        "format_version": FORMAT_VERSION,
        "scene": result.scene,
        "status": result.status,
        "message": result.message,
        "cause": result.cause,
        "t_end": result.t_end,
        "counts": result.counts,
        "metadata": result.metadata,
    }
    payload = dict(result.arrays)
    payload["__meta__"] = np.array(json.dumps(header))
    for key, value in result.counts.items():
        payload[key] = np.array(value)

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as handle:
            write_npz(handle, payload)

    return atomic_write(path, write)


#: the first bytes of a zip archive, hence of every .npz file
ZIP_SIGNATURE = b"PK\x03\x04"


def _read_archive(path: Path) -> dict[str, np.ndarray]:
    """The arrays of the .npz file ``path``; a message fit for the user when it is none.

    numpy's own messages are not quoted for a file that is no archive: for any other file
    it suggests loading it with pickle (``allow_pickle``), i.e. running code from the file.
    """
    if path.is_dir():
        raise ResultFileError(f"result file {str(path)!r} is a folder; give a result file (.npz) written by `clearance run`")
    if not path.is_file():
        raise ResultFileError(f"result file {str(path)!r} does not exist; run `clearance run` first")
    try:
        with open(path, "rb") as handle:
            signature = handle.read(len(ZIP_SIGNATURE))
    except OSError as exc:
        raise ResultFileError(f"result file {str(path)!r} cannot be read ({exc.strerror or exc})") from None
    if signature != ZIP_SIGNATURE:
        raise ResultFileError(f"result file {str(path)!r} is not a result file (.npz) of `clearance run`; give a file it wrote (OUT/NAME.npz)")
    try:
        with np.load(path, allow_pickle=False) as archive:
            return {key: archive[key] for key in archive.files}
    except Exception as exc:  # noqa: BLE001 - any reading failure of a zip file means a damaged archive
        raise ResultFileError(
            f"result file {str(path)!r} is not a readable .npz archive ({exc}): it is incomplete or damaged; "
            "write it again with `clearance run`"
        ) from None


def load_result(path: str | Path, *, urdf_text: str | None = None) -> Result:
    """Read a result file written by :func:`save_result`.

    Raises :class:`ResultFileError` if the file is missing or malformed, or (when
    ``urdf_text`` is given) if it was produced with another mechanism.
    """
    path = Path(path)
    arrays = _read_archive(path)
    if "__meta__" not in arrays:
        raise ResultFileError(f"result file {str(path)!r} has no header: it was not written by this simulator")
    try:
        header = json.loads(str(arrays.pop("__meta__")))
    except json.JSONDecodeError as exc:
        raise ResultFileError(f"result file {str(path)!r} has a corrupt header ({exc})") from None
    if header.get("format_version") != FORMAT_VERSION:
        raise ResultFileError(f"result file {str(path)!r} has format version {header.get('format_version')}, expected {FORMAT_VERSION}")
    for key in ALWAYS_KEPT:
        if key not in arrays:
            raise ResultFileError(f"result file {str(path)!r} lacks the array {key!r}")
    metadata = header.get("metadata", {})
    if urdf_text is not None and metadata.get("urdf_sha256") != mechanism_fingerprint(urdf_text):
        raise ResultFileError(
            f"result file {str(path)!r} was computed with mechanism {metadata.get('mechanism')!r}, "
            "not with the mechanism file given"
        )
    for key in header.get("counts", {}):
        arrays.pop(key, None)
    return Result(
        header["scene"], header["status"], header["message"], header["cause"], header["t_end"], header["counts"], arrays, metadata
    )


def mechanism_fingerprint(urdf_text: str) -> str:
    """SHA-256 of the mechanism file text (stored in results to match them to mechanisms)."""
    return hashlib.sha256(urdf_text.encode("utf-8")).hexdigest()
