"""The names of a result's arrays, and which of them are bulk (Pinocchio-free, for scene checks).

A result (:mod:`robot.io.results`) has one row per record in every *record
array*; per clearance joint ``J`` the *site arrays* ``J_<suffix>``; with contact
events the *event arrays*. ``[output] keep`` of a scene may name any of them
(:func:`result_array_names`); ``t`` and ``record_kind`` are always written.

*Bulk* arrays hold most of a file's bytes and tolerate single precision when the
scene asks for it (``[output] precision = "float32"``, relative error 6e-8:
3e-8 m on a 0.5 m position, 6e-12 m on a 0.1 mm eccentricity): the state ``q``,
``v``, the end-effector kinematics, the eccentricities, the onset rates and the
constraint residual. Time, forces, penetrations, driving forces, energies and
works always stay in double precision (forces and penetrations are the numbers
a clearance study is about; energies are compared by differences).
"""

from __future__ import annotations

from typing import Mapping, Sequence

RECORD_ARRAYS = (
    "t", "q", "v", "record_kind", "onset_rates", "driving_force", "ee_position", "ee_velocity", "ee_acceleration",
    "constraint_residual", "kinetic_energy", "potential_energy", "actuator_power", "contact_power", "actuator_work",
    "contact_work",
)
SITE_SUFFIXES = ("eccentricity", "centre_in_outer", "penetration", "normal_force", "friction_force", "kind")
EVENT_ARRAYS = ("event_t", "event_candidate", "event_is_onset", "event_kind", "event_value")
ALWAYS_KEPT = ("t", "record_kind")
BULK_ARRAYS = ("q", "v", "onset_rates", "ee_position", "ee_velocity", "ee_acceleration", "constraint_residual")
BULK_SITE_SUFFIXES = ("eccentricity", "centre_in_outer")


def result_array_names(clearance_joints: tuple[str, ...] | list[str] | Mapping[str, Sequence[str]]) -> tuple[str, ...]:
    """Every array a result of a scene with these clearance joints can hold.

    ``clearance_joints``: joint names (the suffixes every type writes, ``SITE_SUFFIXES``),
    or joint name -> the suffixes its type writes (``ClearanceJoint.result_keys()``).
    """
    if isinstance(clearance_joints, Mapping):
        sites = tuple(f"{joint}_{suffix}" for joint, suffixes in clearance_joints.items() for suffix in suffixes)
    else:
        sites = tuple(f"{joint}_{suffix}" for joint in clearance_joints for suffix in SITE_SUFFIXES)
    return RECORD_ARRAYS + sites + (EVENT_ARRAYS if clearance_joints else ())


def is_bulk(name: str) -> bool:
    """Whether array ``name`` may be stored in single precision."""
    return name in BULK_ARRAYS or any(name.endswith(f"_{suffix}") for suffix in BULK_SITE_SUFFIXES)
