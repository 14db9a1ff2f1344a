"""clearance_contact: contact forces of 3-D clearance joints (numpy; numba optional).

Poses and velocities in, wrenches out (SI units, world axes); the interface
contract is ``docs/contact-api.md``.  The laws are compiled with numba when it is
installed, ahead of time into the kernel library when it has been built
(``CLEARANCE_CONTACT_JIT=numba`` uses numba's JIT, ``=0`` disables both); without
either the same code runs as plain Python.

* :mod:`.compiled`: the kernels' ``STATUS_*`` codes; ``jit``, ``JIT_ENABLED``, ``KERNEL_MODE`` (from :mod:`.kernel_mode`);
* :mod:`.kernel_mode`: how the kernels run (the kernel library, numba's JIT, plain Python);
* :mod:`.kernel_library`: the kernels compiled ahead of time, loaded without numba;

* :mod:`.errors`: ``ContactError``, ``ContactLawError``, ``ContactParameterError``;
* :mod:`.materials`: ``Material`` and Hertz-type stiffnesses;
* :mod:`.normal_force`: Lankarani-Nikravesh law, ``ONSET_RATE_FLOOR``, Hertz impact peak;
* :mod:`.dissipation`: normal dissipation models (L-N, Hunt-Crossley, Gonthier, Flores, Hu-Guo),
  ``register_dissipation_model``, ``DISSIPATION_MODELS`` (read-only);
* :mod:`.radial_laws`, :mod:`.radial_profile`: the revolute joint's radial laws and exact-profile wrench;
* :mod:`.friction`: Brown-McPhee, Coulomb, no friction; the registry of laws by name
  (``register_friction_law``, ``FrictionKey``, ``friction_law_from_scene``);
* :mod:`.result`: ``JointContact``;
* :mod:`.joint`: ``ClearanceJoint`` (base class of the joint types), ``Shape``, ``output_layout``;
* :mod:`.registry`: ``register_joint_type``, ``joint_type``, ``joint_types``;
* :mod:`.spherical`: ``SphericalClearanceJoint``;
* :mod:`.revolute`: ``RevoluteClearanceJoint``;
* :mod:`.translational`: ``TranslationalClearanceJoint``, ``PlanarTranslationalClearanceJoint``.

The names are imported lazily (on first use): ``import clearance_contact.errors``
(what the ``robot`` package's exceptions need) loads neither numba nor the laws,
and the shipped joint types register on the registry's first look-up.
"""

from .lazy import lazy_exports

#: public name -> the submodule that defines it
_PUBLIC = {
    "ClearanceMechanismsError": ".errors",
    "ContactError": ".errors",
    "ContactLawError": ".errors",
    "ContactParameterError": ".errors",
    "BrownMcPheeFriction": ".friction",
    "CoulombFriction": ".friction",
    "FrictionKey": ".friction",
    "FrictionLaw": ".friction",
    "friction_law_from_scene": ".friction",
    "friction_law_names": ".friction",
    "register_friction_law": ".friction",
    "NoFriction": ".friction",
    "ScalarFrictionLaw": ".friction",
    "STEEL": ".materials",
    "Material": ".materials",
    "combined_modulus": ".materials",
    "cylinder_line_stiffness": ".materials",
    "flat_punch_stiffness": ".materials",
    "hertz_sphere_stiffness": ".materials",
    "sphere_plane_stiffness": ".materials",
    "EXPONENT_RANGE": ".normal_force",
    "ONSET_RATE_FLOOR": ".normal_force",
    "HertzImpactMaximum": ".normal_force",
    "hertz_impact_maximum": ".normal_force",
    "hysteresis_factor": ".normal_force",
    "lankarani_nikravesh": ".normal_force",
    "validate_normal_law": ".normal_force",
    "DISSIPATION_MODELS": ".dissipation",
    "register_dissipation_model": ".dissipation",
    "rebound_ratio": ".dissipation",
    "RADIAL_LAWS": ".radial_laws",
    "KIND_LINE": ".result",
    "KIND_NONE": ".result",
    "KIND_PLANE": ".result",
    "KIND_POINT": ".result",
    "JointContact": ".result",
    "ClearanceJoint": ".joint",
    "Shape": ".joint",
    "output_layout": ".joint",
    "joint_type": ".registry",
    "joint_types": ".registry",
    "register_joint_type": ".registry",
    "SphericalClearanceJoint": ".spherical",
    "RevoluteClearanceJoint": ".revolute",
    "TranslationalClearanceJoint": ".translational",
    "PlanarTranslationalClearanceJoint": ".translational",
}

__all__ = sorted(_PUBLIC)


__getattr__, __dir__ = lazy_exports(__name__, globals(), _PUBLIC)
