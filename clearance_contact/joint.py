"""What every clearance joint type shares: :class:`ClearanceJoint`, its output layout and drawing shapes.

A clearance joint type is a subclass of :class:`ClearanceJoint` registered with
:func:`clearance_contact.registry.register_joint_type`.  The subclass says what it
is (class attributes) and computes its contact law (a kernel); the base class does
everything else, once for all types:

* **Output layout**: from ``N_CANDIDATES`` (k), ``N_ECCENTRICITY`` (r) and
  ``EXTRA_OUTPUTS`` (names of internal sections of k values each) the offsets of the
  flat output array (:func:`output_layout`, ``docs/contact-api.md``) are set as
  class attributes (``PENETRATION`` ... ``KIND``, the extras, ``output_size``).
* **Friction wiring** (:meth:`ClearanceJoint._wire_friction`): validation of the law
  (:func:`~clearance_contact.friction.require_friction_law`: a user-defined law's signatures
  and sample values too) and its kernel encoding; a user-defined law is applied in Python
  by the type's ``_apply_external_friction`` through the checked calls of
  :func:`~clearance_contact.friction.user_friction` (one place for every type).
* **Evaluation and status handling**: :meth:`ClearanceJoint.evaluate` validates the
  state, runs ``kernel`` into a fresh output array and turns a nonzero status into
  :class:`~clearance_contact.errors.ContactError` (a type adds its own codes through
  :meth:`ClearanceJoint._status_error`); :meth:`ClearanceJoint.penetration` the same
  with ``penetration_kernel``.
* **Parameters as given**: a joint built from its scene keys
  (:meth:`ClearanceJoint.from_scene`) keeps them as given (``scene_parameters``), so
  that a clearance of ``1e-4`` is reported as ``1e-4`` even when the law stores a
  radius ``r + 1e-4`` internally; ``scene_parameters["friction"]`` names the friction law
  (its scene table: ``{"law": NAME, key: value, ...}``).
* **Results, failure check, drawing**: per-joint result arrays (:meth:`result_arrays`,
  :meth:`record`: also the inner element's centre in the outer frame and the resultant
  normal force of each group of candidates, ``FORCE_GROUPS``), the clearance of each candidate (:meth:`candidate_clearances`, the
  scale of the simulator's penetration bound), and what an animation draws
  (:meth:`drawing`: :class:`Shape` s in the element frames, true or magnified gaps).

The kernel of a type is any callable with the signature
``kernel(parameters, outer_rotation, outer_position, outer_twist, inner_rotation,
inner_position, inner_twist, onset_rates, out) -> status``: numba-compiled for the
shipped types (then ``KERNEL_ID`` names it to the simulator's compiled dispatcher,
``robot.dynamics.rhs_kernels.law_kernel``), or plain Python for a type defined
elsewhere (``KERNEL_ID = None``: the simulator then calls :meth:`evaluate`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Any, ClassVar, Mapping

import numpy as np
from numpy.typing import ArrayLike

from .compiled import STATUS_EXTERNAL_FRICTION, STATUS_MESSAGES, STATUS_NONFINITE_INPUT, STATUS_OK
from .errors import (
    ROTATION_SHAPE,
    STATE_NAMES,
    VECTOR_SHAPE,
    ContactError,
    joint_state,
    nonfinite_state_message,
    state_array,
)
from .friction import FRICTION_EXTERNAL, FrictionLaw, friction_encoding, friction_scene_table, require_friction_law
from .materials import Material
from .result import JointContact

__all__ = ["ClearanceJoint", "Shape", "output_layout", "COMMON_OUTPUTS"]

_NOTHING_GIVEN: dict = {}
_ROTATION_UNUSED = np.eye(3)

#: the sections every law writes, in order, with their size in units of (k, r)
COMMON_OUTPUTS = (
    ("PENETRATION", 1, 0),
    ("PENETRATION_RATE", 1, 0),
    ("NORMAL_FORCE", 1, 0),
    ("NORMAL", 3, 0),
    ("POINT_OUTER", 3, 0),
    ("POINT_INNER", 3, 0),
    ("FRICTION_FORCE", 3, 0),
    ("ECCENTRICITY", 0, 3),
    ("WRENCH_OUTER", 0, 0),
    ("WRENCH_INNER", 0, 0),
    ("KIND", 1, 0),
)


def output_layout(n_candidates: int, n_eccentricity: int, extra: tuple[str, ...] = ()) -> dict[str, int]:
    """Offsets of a law's flat output (``docs/contact-api.md``): name -> offset, plus ``OUTPUT_SIZE``.

    Sections in the order of :data:`COMMON_OUTPUTS` (k values per candidate times 1 or 3,
    3 per eccentricity row, 6 per wrench), then each ``extra`` section (k values).
    """
    layout, offset = {}, 0
    for name, per_candidate, per_row in COMMON_OUTPUTS:
        layout[name] = offset
        offset += per_candidate * n_candidates + per_row * n_eccentricity + (6 if name.startswith("WRENCH") else 0)
    for name in extra:
        layout[name] = offset
        offset += n_candidates
    layout["OUTPUT_SIZE"] = offset
    return layout


@dataclass(frozen=True)
class Shape:
    """A solid of a clearance joint's drawing, in its element's frame (m).

    ``kind``: ``"sphere"`` (``radius``), ``"cylinder"`` (``radius``, ``length``, axis =
    local z), ``"tube"`` (hollow cylinder along z: ``inner_radius``, ``radius``,
    ``length``) or ``"box"`` (``size`` = (x, y, z) edge lengths); centred at ``centre``.
    ``element``: ``"outer"`` or ``"inner"`` (the frame it moves with); ``opacity`` in (0, 1].
    """

    element: str
    name: str
    kind: str
    radius: float = 0.0
    length: float = 0.0
    inner_radius: float = 0.0
    size: tuple[float, float, float] = (0.0, 0.0, 0.0)
    centre: tuple[float, float, float] = (0.0, 0.0, 0.0)
    opacity: float = 1.0

    @property
    def extent(self) -> float:
        """Half the largest dimension of the solid (m): sets the camera distance of a close-up."""
        return max(self.radius, 0.5 * self.length, 0.5 * max(self.size))


class ClearanceJoint:
    """Base class of the clearance joint types (module docstring).

    Class attributes a type sets
    ----------------------------
    ``type_name``: its name in scenes (``type = "..."``) and in result files.
    ``N_CANDIDATES`` (k), ``N_ECCENTRICITY`` (r), ``EXTRA_OUTPUTS``: its output layout.
    ``SITE_KINDS``: the kinds of mechanism joint it can replace (``"spherical"``,
    ``"revolute"``; a revolute tree joint becomes a free joint, so any type fits it).
    ``SCENE_KEYS``: its own scene keys, ``REQUIRED_KEYS`` the ones without default;
    ``NAME_KEYS``: those of them whose values are names (text: a model chosen from a
    registry, e.g. ``dissipation``), the others are numbers.
    ``GEOMETRY_KEYS``: the keys that size its elements (result metadata, animation);
    ``GAP_KEYS``: the clearances among them (magnified in an animation);
    ``DEFAULT_GEOMETRY``: sizes drawn when a result does not record them.
    ``KERNEL_ID``: its id in the compiled dispatcher, None for a type evaluated in Python.
    ``FORCE_GROUPS``: name -> candidate indices; each group's resultant normal force
    |sum_k F_N,k n_k| is the result array ``<name>_force`` (e.g. ``radial``, ``axial``).
    ``EXAGGERATE_TILT``: an animation magnifies the inner element's axis tilt too.
    ``PENETRATION_USES_ROTATIONS``: False if ``penetration_kernel`` reads positions only
    (the rotations are then not converted: event functions call :meth:`penetration` often).
    ``kernel``, ``penetration_kernel``: its law (signatures in the module docstring).

    Instances hold ``kernel_parameters`` (float64 array for the kernels) and call
    :meth:`_wire_friction` in their ``__init__`` and set ``_restitution`` and ``_dissipation``
    (the name of a :mod:`~clearance_contact.dissipation` model, encoded into their parameters).
    """

    __slots__ = ("_friction", "_friction_code", "_restitution", "_dissipation", "_given", "_friction_table", "kernel_parameters")

    type_name: ClassVar[str] = ""
    N_CANDIDATES: ClassVar[int] = 0
    N_ECCENTRICITY: ClassVar[int] = 0
    EXTRA_OUTPUTS: ClassVar[tuple[str, ...]] = ()
    SITE_KINDS: ClassVar[tuple[str, ...]] = ("spherical", "revolute")
    SCENE_KEYS: ClassVar[tuple[str, ...]] = ()
    REQUIRED_KEYS: ClassVar[tuple[str, ...]] = ()
    NAME_KEYS: ClassVar[tuple[str, ...]] = ()
    GEOMETRY_KEYS: ClassVar[tuple[str, ...]] = ()
    FORCE_GROUPS: ClassVar[Mapping[str, tuple[int, ...]]] = {}
    GAP_KEYS: ClassVar[tuple[str, ...]] = ()
    DEFAULT_GEOMETRY: ClassVar[Mapping[str, float]] = {}
    KERNEL_ID: ClassVar[int | None] = None
    EXAGGERATE_TILT: ClassVar[bool] = False
    PENETRATION_USES_ROTATIONS: ClassVar[bool] = True  # False: ``penetration_kernel`` reads positions only
    kernel: Any = None
    penetration_kernel: Any = None
    n_candidates: ClassVar[int] = 0
    output_size: ClassVar[int] = 0
    kernel_function: Any = None  # set per type: the kernel even where ``kernel`` hides it (KernelAttribute)

    def __init_subclass__(cls, **kwargs) -> None:
        super().__init_subclass__(**kwargs)
        layout = output_layout(cls.N_CANDIDATES, cls.N_ECCENTRICITY, cls.EXTRA_OUTPUTS)
        for name, offset in layout.items():
            setattr(cls, name, offset)
        cls.output_size = layout["OUTPUT_SIZE"]
        cls.n_candidates = cls.N_CANDIDATES  # lower-case alias of the contract
        # the kernel as a plain function, also where ``kernel`` is a KernelAttribute that hides it
        cls.kernel_function = staticmethod(cls.kernel) if cls.kernel is not None else None

    # -- what the subclass' __init__ calls -------------------------------------------
    def _wire_friction(self, friction: FrictionLaw) -> tuple[int, np.ndarray]:
        """Validate and keep the friction law; return its kernel encoding (code, parameters).

        ContactParameterError for an object that is not a :class:`FrictionLaw`, or a
        user-defined law with wrong signatures or values (:func:`require_friction_law`).
        """
        require_friction_law(friction)
        self._friction = friction
        code, parameters = friction_encoding(friction)
        self._friction_code = code
        return code, parameters

    # -- parameters ------------------------------------------------------------------
    @property
    def dissipation(self) -> str:
        """Name of the normal dissipation model (:mod:`~clearance_contact.dissipation`)."""
        return self._dissipation

    @property
    def friction(self) -> FrictionLaw:
        return self._friction

    @property
    def friction_in_kernel(self) -> bool:
        """True if ``kernel`` applies the friction law (a built-in law); False for a user-defined one."""
        return self._friction_code != FRICTION_EXTERNAL

    @property
    def restitution(self) -> float:
        return self._restitution

    @classmethod
    def from_scene(
        cls,
        parameters: Mapping[str, float],
        outer_material: Material,
        inner_material: Material,
        restitution: float,
        friction: FrictionLaw,
        *,
        friction_table: Mapping[str, Any] | None = None,
    ) -> "ClearanceJoint":
        """The joint from its scene keys (``SCENE_KEYS``), kept as given (:attr:`scene_parameters`).

        ``friction_table``: the scene's friction table ``friction`` was built from (recorded
        as ``scene_parameters["friction"]``); None: described from the law itself
        (:func:`~clearance_contact.friction.friction_scene_table`).  A ``"friction"`` entry of
        ``parameters`` (what :attr:`scene_parameters` reports) is not a type's key and is
        ignored: the law is ``friction``.
        """
        given = {key: value for key, value in parameters.items() if key != "friction"}
        joint = cls._from_scene(dict(given), outer_material, inner_material, restitution, friction)
        joint._given = given
        joint._friction_table = None if friction_table is None else dict(friction_table)
        return joint

    @classmethod
    def _from_scene(cls, parameters: dict, outer_material: Material, inner_material: Material, restitution: float, friction: FrictionLaw):
        """Construct from scene keys (a type whose constructor takes other arguments overrides this)."""
        return cls(**parameters, outer_material=outer_material, inner_material=inner_material, restitution=restitution, friction=friction)

    def given(self, key: str, derived: float) -> float:
        """The value of scene key ``key`` as the user gave it, else ``derived`` (computed from the law)."""
        return self._given_parameters().get(key, derived)

    def _given_parameters(self) -> dict:
        return getattr(self, "_given", _NOTHING_GIVEN)

    @property
    def scene_parameters(self) -> dict[str, float | str]:
        """Every scene key of the type that has a value: as given, or the law's own value.

        A name key (``NAME_KEYS``) reports the name: its attribute is either the name or
        the registry's object, which carries it as ``name``.  ``"friction"``: the friction
        law as a scene table (``{"law": NAME, key: value, ...}``: the scene's, or
        :func:`~clearance_contact.friction.friction_scene_table` of the law).
        """
        out = {}
        for key in self.SCENE_KEYS:
            value = self._given_parameters().get(key, getattr(self, key, None))
            if key in self.NAME_KEYS and value is not None and not isinstance(value, str):
                value = value.name
            if value is not None:
                out[key] = value
        table = getattr(self, "_friction_table", None)
        out["friction"] = dict(table) if table is not None else friction_scene_table(self._friction)
        return out

    @property
    def geometry(self) -> dict[str, float]:
        """The element sizes (``GEOMETRY_KEYS``), as given: what results record and animations draw."""
        parameters = self.scene_parameters
        return {key: float(parameters[key]) for key in self.GEOMETRY_KEYS}

    def candidate_clearances(self) -> np.ndarray:
        """(k,) the clearance each candidate's penetration is measured against (m)."""
        raise NotImplementedError(f"{type(self).__name__} does not define candidate_clearances")

    # -- evaluation ------------------------------------------------------------------
    def evaluate(
        self,
        outer_rotation: ArrayLike,
        outer_position: ArrayLike,
        outer_twist: ArrayLike,
        inner_rotation: ArrayLike,
        inner_position: ArrayLike,
        inner_twist: ArrayLike,
        onset_rates: ArrayLike,
    ) -> JointContact:
        """Contact state and wrenches: ``kernel`` on the validated state (see the type's docstring).

        ``outer_*`` / ``inner_*``: rotations (3, 3) frame -> world, positions (3,), twists
        (6,) = [v, w] of the frame origin in world axes; ``onset_rates`` (k,) the approach
        rates at the onset of each candidate's current impact.  Returns views of one fresh
        output array.  ValueError for wrong shapes, :class:`ContactError` for NaN / inf
        input or any other failure status of the kernel.
        """
        state = joint_state(outer_rotation, outer_position, outer_twist, inner_rotation, inner_position, inner_twist, onset_rates, self.N_CANDIDATES)
        out = np.empty(self.output_size)
        status = self.kernel_function(self.kernel_parameters, *state, out)
        if status != STATUS_OK:
            if status == STATUS_EXTERNAL_FRICTION:  # user-defined friction law, applied here
                self._apply_external_friction(state, out)
            elif status == STATUS_NONFINITE_INPUT:
                raise ContactError(nonfinite_state_message(STATE_NAMES, state))
            else:
                raise self._status_error(status, state, out)
        return JointContact.from_output(self, out)

    def penetration(
        self, outer_rotation: ArrayLike, outer_position: ArrayLike, inner_rotation: ArrayLike, inner_position: ArrayLike
    ) -> np.ndarray:
        """(k,) deepest penetration (m) of each candidate, > 0 in contact.  Cheap (no velocities): events."""
        if self.PENETRATION_USES_ROTATIONS:
            outer_rotation = state_array("outer_rotation", outer_rotation, ROTATION_SHAPE)
            inner_rotation = state_array("inner_rotation", inner_rotation, ROTATION_SHAPE)
        else:  # not read by the kernel: not converted (event functions call this often)
            outer_rotation = inner_rotation = _ROTATION_UNUSED
        outer_position = state_array("outer_position", outer_position, VECTOR_SHAPE)
        inner_position = state_array("inner_position", inner_position, VECTOR_SHAPE)
        out = np.empty(self.N_CANDIDATES)
        status = self.penetration_kernel(self.kernel_parameters, outer_rotation, outer_position, inner_rotation, inner_position, out)
        if status != STATUS_OK:
            raise self._status_error(status, (outer_rotation, outer_position, None, inner_rotation, inner_position, None, None), out)
        return out

    def _status_error(self, status: int, state: tuple, out: np.ndarray) -> ContactError:
        """The error of a failure ``status`` (``state``: the kernel's inputs, None where not given).

        A type with its own status codes extends this; the default names the status and
        the positions (NaN / inf input or overflow are the usual causes).
        """
        what = STATUS_MESSAGES.get(status, f"status {status}")
        penetration = out[self.PENETRATION : self.PENETRATION + self.N_CANDIDATES].tolist()
        return ContactError(
            f"{type(self).__name__}: {what} (penetration {penetration!r}): check the poses (NaN or inf input, or overflow): "
            f"outer_position={state[1].tolist()!r}, inner_position={state[4].tolist()!r}"
        )

    def _apply_external_friction(self, state: tuple, out: np.ndarray) -> None:
        """Finish a ``STATUS_EXTERNAL_FRICTION`` output with the user's friction law (types with friction)."""
        raise NotImplementedError(f"{type(self).__name__} does not apply user-defined friction laws")

    # -- results -----------------------------------------------------------------------
    @property
    def eccentricity_shape(self) -> tuple[int, ...]:
        """Shape of one record of the ``eccentricity`` result array: (3,) for one row, else (r, 3)."""
        return (3,) if self.N_ECCENTRICITY == 1 else (self.N_ECCENTRICITY, 3)

    def result_arrays(self, n: int) -> dict[str, np.ndarray]:
        """Empty per-joint result arrays for ``n`` records (result file keys ``NAME_<key>``).

        ``centre_in_outer`` (n, 3): the inner element's frame origin in the outer
        element's frame (ball in socket, journal midpoint in the bearing frame, slider
        centre in the guide frame); ``<group>_force`` (n,) per ``FORCE_GROUPS``.
        """
        k = self.N_CANDIDATES
        arrays = {
            "eccentricity": np.empty((n, *self.eccentricity_shape)),
            "centre_in_outer": np.empty((n, 3)),
            "penetration": np.empty((n, k)),
            "normal_force": np.empty((n, k)),
            "friction_force": np.empty((n, k)),
            "kind": np.empty((n, k), dtype=np.int8),
        }
        for group in self.FORCE_GROUPS:
            arrays[f"{group}_force"] = np.empty(n)
        return arrays

    @classmethod
    def result_keys(cls) -> tuple[str, ...]:
        """The keys of :meth:`result_arrays` (result file arrays ``NAME_<key>``)."""
        return ("eccentricity", "centre_in_outer", "penetration", "normal_force", "friction_force", "kind") + tuple(
            f"{group}_force" for group in cls.FORCE_GROUPS
        )

    def record(
        self,
        arrays: dict[str, np.ndarray],
        i: int,
        contact: JointContact,
        outer_rotation: ArrayLike,
        outer_position: ArrayLike,
        inner_position: ArrayLike,
    ) -> None:
        """Write record ``i`` of :meth:`result_arrays` from one evaluation at these element poses.

        Friction: its magnitude per candidate; group forces: the magnitude of the
        resultant of the group's normal forces ``sum_k F_N,k n_k`` (friction excluded).
        """
        arrays["eccentricity"][i] = contact.eccentricity.reshape(self.eccentricity_shape)
        arrays["centre_in_outer"][i] = np.asarray(outer_rotation).T @ (np.asarray(inner_position) - np.asarray(outer_position))
        arrays["penetration"][i] = contact.penetration
        arrays["normal_force"][i] = contact.normal_force
        arrays["friction_force"][i] = np.linalg.norm(contact.friction_force, axis=1)
        arrays["kind"][i] = contact.kind
        for group, candidates in self.FORCE_GROUPS.items():
            members = list(candidates)
            resultant = contact.normal_force[members] @ contact.normal[members]
            arrays[f"{group}_force"][i] = math.sqrt(float(resultant @ resultant))

    def record_outputs(
        self,
        arrays: dict[str, np.ndarray],
        rows: np.ndarray,
        outputs: np.ndarray,
        outer_rotation: np.ndarray,
        outer_position: np.ndarray,
        inner_position: np.ndarray,
    ) -> None:
        """Write the records ``rows`` of :meth:`result_arrays` from the kernel's flat outputs (m, ``output_size``).

        The same values as :meth:`record` of ``JointContact.from_output(self, outputs[j])`` at
        the poses ``outer_rotation[j]`` (m, 3, 3), ``outer_position[j]``, ``inner_position[j]``
        (m, 3) for each row, in a few vectorised operations (the simulator's compiled outputs).
        """
        k, r = self.N_CANDIDATES, self.N_ECCENTRICITY
        m = outputs.shape[0]
        vectors = outputs[:, self.NORMAL : self.NORMAL + 3 * (4 * k + r)].reshape(m, -1, 3)
        normal_force = outputs[:, self.NORMAL_FORCE : self.NORMAL_FORCE + k]
        arrays["eccentricity"][rows] = vectors[:, 4 * k : 4 * k + r].reshape(m, *self.eccentricity_shape)
        arrays["centre_in_outer"][rows] = np.einsum("mji,mj->mi", outer_rotation, inner_position - outer_position)
        arrays["penetration"][rows] = outputs[:, self.PENETRATION : self.PENETRATION + k]
        arrays["normal_force"][rows] = normal_force
        arrays["friction_force"][rows] = np.linalg.norm(vectors[:, 3 * k : 4 * k], axis=2)
        arrays["kind"][rows] = outputs[:, self.KIND : self.KIND + k].astype(np.int64)
        for group, candidates in self.FORCE_GROUPS.items():
            members = list(candidates)
            resultant = np.einsum("mk,mkj->mj", normal_force[:, members], vectors[:, members])
            arrays[f"{group}_force"][rows] = np.sqrt(np.einsum("mj,mj->m", resultant, resultant))

    # -- drawing -----------------------------------------------------------------------
    @classmethod
    def magnified(cls, geometry: Mapping[str, float], factor: float) -> dict[str, float]:
        """The geometry with its gaps (``GAP_KEYS``) times ``factor`` (animation exaggeration)."""
        return {key: float(value) * factor if key in cls.GAP_KEYS else float(value) for key, value in geometry.items()}

    @classmethod
    def exaggerated_offset(cls, offset: np.ndarray, factor: float) -> np.ndarray:
        """The inner element's offset in the outer frame as an animation draws it: times ``factor``.

        A type whose elements also move freely (the slide of a translational joint)
        magnifies only the offset the clearance bounds.
        """
        return factor * np.asarray(offset, dtype=float)

    @classmethod
    def drawing(cls, geometry: Mapping[str, float]) -> tuple[Shape, ...]:
        """The solids an animation draws for these element sizes (none by default: arrows only)."""
        return ()

    @classmethod
    def inner_radius(cls, geometry: Mapping[str, float]) -> float:
        """Size of the inner element (m): scales the marker of its centre in an animation."""
        return 0.01

    @classmethod
    def geometry_from_result(cls, eccentricity: np.ndarray, penetration: np.ndarray) -> dict[str, float]:
        """Element sizes measured from a result's own arrays (checks the recorded sizes); none by default."""
        return {}
