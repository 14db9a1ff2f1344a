"""Cross-checks of the Lagrange-multiplier model (``robot.dynamics.equations``) against two other formulations.

The seed paper validates its Lagrange model against ADAMS and against the
Newton-Euler method. This package does both:

* :mod:`.newton_euler`: a second formulation of the same mechanism written
  independently of Pinocchio's dynamics algorithms: every body in absolute
  coordinates (centre of mass, quaternion, body angular velocity), the
  Newton-Euler equations of each body, the joint reactions as unknown
  multipliers of constraint equations written out in absolute coordinates
  (:mod:`.absolute_constraints`), solved as an augmented (index-1, Baumgarte)
  system at every right-hand-side evaluation and integrated with the Lagrange
  model's event-driven step loop (:mod:`robot.integration.event_loop`, through
  :mod:`.event_loop`). It shares with the Lagrange model only
  the geometry input (the URDF, read by :mod:`.bodies`), the contact layer
  (``clearance_contact``), the prescribed actuator histories (``robot.model.trajectory``)
  and the initial state (mapped from Pinocchio coordinates to absolute ones).
* :mod:`.exudyn_model`: the same mechanism built in Exudyn (an independent C++
  multibody code, the role ADAMS plays in the paper): rigid bodies with Euler
  parameters, generic joints, the prescribed actuator lengths as distance
  constraints reset at every step, the clearance contact as a user-function
  force element calling ``clearance_contact``; implicit generalized-alpha
  integration.
* :mod:`.comparison` computes the deviations and statistics,
  :mod:`.figures` draws them, :mod:`.study` runs the scenes and writes
  ``validation.json`` and the figures (``scripts/validate.py``).

See ``docs/validation.md`` for the equations, the settings and the numbers.
"""
