"""The sweep tool's exception: a bad sweep file or store, found before any run starts."""

from __future__ import annotations

from robot.errors import RobotError


class SweepError(RobotError, ValueError):
    """A sweep file is malformed (unknown key path, empty axis, bad sample count, a value the
    scene refuses, an unknown analysis) or its output store belongs to another sweep.

    ``key`` names the offending entry (a sweep-file key such as ``sweep.samples`` or a scene
    key path such as ``clearance.R1.radial_clearance``) and ``value`` its value.
    """
