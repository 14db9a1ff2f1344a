"""The library's exceptions. Each message says what is wrong and how to fix it.

One root for the whole project: :class:`Error` (``clearance_contact``'s
``ClearanceMechanismsError``), with ``key`` and ``value`` fields naming the
offending input. ``RobotError`` (this package) and ``ContactError`` (the contact
layer) derive from it.
"""

from __future__ import annotations

from clearance_contact.errors import ClearanceMechanismsError

#: the root of every error of this project
Error = ClearanceMechanismsError


class RobotError(ClearanceMechanismsError):
    """Base class of every error raised by the ``robot`` package."""


class MechanismFileError(RobotError, ValueError):
    """A URDF file or its closure declarations are malformed or inconsistent."""


class ClearanceChoiceError(RobotError, ValueError):
    """A clearance joint names a joint that does not exist or cannot carry clearance."""


class KinematicsError(RobotError):
    """Base class of kinematic failures (pose, assembly, singularity, stroke)."""


class UnreachablePoseError(KinematicsError, ValueError):
    """A platform pose cannot be reached by the limbs (or the assembly did not converge)."""


class SingularConfigurationError(KinematicsError):
    """The constraint or actuation Jacobian is (numerically) rank deficient."""


class StrokeLimitError(KinematicsError, ValueError):
    """An actuator length lies outside its stroke limits."""


class SceneError(RobotError, ValueError):
    """A scene file is malformed: unknown key, wrong type or value out of range."""


class RegistrationError(RobotError, ValueError, TypeError):
    """An extension (a force element type, an integration method) does not meet its registry's contract.

    Raised when it is registered (or, for a solver given as ``"module:attribute"``,
    when the method is first looked up), naming the extension and what is missing
    or wrong. Also a ``ValueError`` and a ``TypeError``: what the registries raised
    before they checked the contract.
    """


class ResultFileError(RobotError, ValueError):
    """A result file is missing, malformed or from another mechanism."""


class DriveError(RobotError, ValueError):
    """A drive (the prescribed motion of the actuators) does not fit the mechanism it drives."""


class InitialStateError(KinematicsError, ValueError):
    """The initial positions or velocities a scene asks for cannot be met by the mechanism."""


class RobotWarning(UserWarning):
    """Base class of the warnings issued by the ``robot`` package."""


class RedundantConstraintWarning(RobotWarning):
    """Some constraint equations are linearly dependent on the others (an overconstrained mechanism).

    The motion is exact (solved on the independent equations); the multipliers of
    the redundant set are not unique and are reported by a convention
    (``docs/dynamics.md``, "Redundant constraints").
    """


class InitialStateWarning(RobotWarning):
    """A given initial coordinate had to be corrected to satisfy the constraints."""


class InertiaWarning(RobotWarning):
    """A link's inertia breaks the triangle inequalities: no rigid body has those moments (used as given)."""


class ClosureDeclarationWarning(RobotWarning):
    """A part of a ``<closure>`` declaration is not used as written (the message says what is used instead)."""
