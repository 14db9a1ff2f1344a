"""clearance_contact: contact forces of 3-D clearance joints (numpy; numba optional).

Poses and velocities in, wrenches out (SI units, world axes); the interface
contract is ``docs/contact-api.md``.  The laws are compiled with numba when it is
installed (``CLEARANCE_CONTACT_JIT=0`` disables it); without it the same code runs
as plain Python.

* :mod:`.compiled`: ``jit``, ``JIT_ENABLED``, the kernels' ``STATUS_*`` codes;

* :mod:`.errors`: ``ContactError``, ``ContactParameterError``;
* :mod:`.materials`: ``Material`` and Hertz-type stiffnesses;
* :mod:`.normal_force`: Lankarani-Nikravesh law, ``ONSET_RATE_FLOOR``, Hertz impact peak;
* :mod:`.friction`: Brown-McPhee, Coulomb, no friction;
* :mod:`.result`: ``JointContact``;
* :mod:`.joint`: ``ClearanceJoint`` (base class of the joint types), ``Shape``, ``output_layout``;
* :mod:`.registry`: ``register_joint_type``, ``joint_type``, ``joint_types``;
* :mod:`.spherical`: ``SphericalClearanceJoint``;
* :mod:`.revolute`: ``RevoluteClearanceJoint``;
* :mod:`.translational`: ``TranslationalClearanceJoint``, ``PlanarTranslationalClearanceJoint``.
"""

from .errors import ContactError, ContactParameterError
from .friction import BrownMcPheeFriction, CoulombFriction, FrictionLaw, NoFriction, ScalarFrictionLaw
from .materials import (
    STEEL,
    Material,
    combined_modulus,
    cylinder_line_stiffness,
    flat_punch_stiffness,
    hertz_sphere_stiffness,
    sphere_plane_stiffness,
)
from .normal_force import (
    EXPONENT_RANGE,
    ONSET_RATE_FLOOR,
    HertzImpactMaximum,
    hertz_impact_maximum,
    hysteresis_factor,
    lankarani_nikravesh,
    validate_normal_law,
)
from .result import KIND_LINE, KIND_NONE, KIND_PLANE, KIND_POINT, JointContact
from .joint import ClearanceJoint, Shape, output_layout
from .registry import joint_type, joint_types, register_joint_type
from .spherical import SphericalClearanceJoint
from .revolute import RevoluteClearanceJoint
from .translational import PlanarTranslationalClearanceJoint, TranslationalClearanceJoint

__all__ = [
    "ContactError",
    "ContactParameterError",
    "Material",
    "STEEL",
    "combined_modulus",
    "hertz_sphere_stiffness",
    "cylinder_line_stiffness",
    "flat_punch_stiffness",
    "ONSET_RATE_FLOOR",
    "EXPONENT_RANGE",
    "lankarani_nikravesh",
    "hysteresis_factor",
    "validate_normal_law",
    "HertzImpactMaximum",
    "hertz_impact_maximum",
    "FrictionLaw",
    "ScalarFrictionLaw",
    "BrownMcPheeFriction",
    "CoulombFriction",
    "NoFriction",
    "JointContact",
    "KIND_NONE",
    "KIND_POINT",
    "KIND_LINE",
    "KIND_PLANE",
    "ClearanceJoint",
    "Shape",
    "output_layout",
    "register_joint_type",
    "joint_type",
    "joint_types",
    "SphericalClearanceJoint",
    "RevoluteClearanceJoint",
    "TranslationalClearanceJoint",
    "PlanarTranslationalClearanceJoint",
    "sphere_plane_stiffness",
]
