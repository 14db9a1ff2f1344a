"""Journal / ball orbits in the bearing / socket frame: recovery and rigid-motion invariance."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.spatial.transform import Rotation

from robot.analysis import ANALYSES, AnalysisError
from robot.analysis.orbits import orbit, relative_position

N = 400


def poses(seed: int):
    """A tumbling outer element, a relative orbit e(t) on a tilted ellipse, and the inner centre."""
    rng = np.random.default_rng(seed)
    t = np.linspace(0.0, 2.0, N)
    rotvec = np.column_stack([np.sin(1.3 * t + 0.2), 0.7 * np.cos(2.1 * t), 0.4 * t]) * rng.uniform(0.5, 1.5, 3)
    outer_rotation = Rotation.from_rotvec(rotvec).as_matrix()
    outer_position = rng.normal(size=3) + np.column_stack([np.sin(t), t**2, np.cos(3 * t)])
    e = 1e-4 * np.column_stack([np.cos(5 * t), 0.6 * np.sin(5 * t), 0.2 * np.sin(7 * t)])
    inner_position = outer_position + np.einsum("nij,nj->ni", outer_rotation, e)
    return t, outer_rotation, outer_position, inner_position, e


def test_relative_orbit_is_recovered():
    _, rotation, outer, inner, e = poses(10)
    np.testing.assert_allclose(relative_position(rotation, outer, inner), e, atol=1e-15)


@pytest.mark.parametrize("seed", [11, 12])
def test_rigid_motion_of_both_bodies_leaves_the_orbit_invariant(seed):
    t, rotation, outer, inner, e = poses(seed)
    rng = np.random.default_rng(seed + 100)
    # a time-varying rigid motion G(t), d(t) applied to the whole mechanism
    motion = Rotation.from_rotvec(np.outer(np.sin(0.9 * t) + 2.0, rng.normal(size=3))).as_matrix()
    shift = np.outer(t, rng.normal(size=3)) + rng.normal(size=3)
    moved_rotation = np.einsum("nij,njk->nik", motion, rotation)
    moved_outer = np.einsum("nij,nj->ni", motion, outer) + shift
    moved_inner = np.einsum("nij,nj->ni", motion, inner) + shift
    assert np.max(np.abs(moved_inner - inner)) > 0.1  # the world positions did change
    np.testing.assert_allclose(relative_position(moved_rotation, moved_outer, moved_inner), e, atol=1e-15)


def test_eccentricity_ratio_about_the_bearing_axis_and_spherical():
    t = np.linspace(0, 1, N)
    clearance = 2.5e-5
    rotation = Rotation.from_rotvec(np.outer(t, [0.3, -1.0, 0.5])).as_matrix()
    axis = np.array([1.0, 1.0, 0.0]) / np.sqrt(2)  # bearing axis in the outer frame, not z
    radial = np.column_stack([axis[1] * np.ones(N), -axis[0] * np.ones(N), np.zeros(N)])  # unit, normal to the axis
    e = 0.8 * clearance * radial + np.outer(3e-3 * np.sin(9 * t), axis)  # axial motion does not count
    outer = np.zeros((N, 3))
    inner = np.einsum("nij,nj->ni", rotation, e)
    out = orbit(rotation, outer, inner, clearance=clearance, axis=axis)
    np.testing.assert_allclose(out["eccentricity_ratio"], 0.8, rtol=1e-9)
    spherical = ANALYSES["orbit"](outer_rotation=rotation, outer_position=outer, inner_position=inner, clearance=clearance, axis=None)
    np.testing.assert_allclose(spherical["eccentricity_ratio"], np.linalg.norm(e, axis=1) / clearance, rtol=1e-12)
    assert float(spherical["max_eccentricity_ratio"]) == pytest.approx(np.max(np.linalg.norm(e, axis=1)) / clearance)


def test_bad_inputs_raise():
    _, rotation, outer, inner, _ = poses(13)
    with pytest.raises(AnalysisError, match="must hold rotation matrices"):
        relative_position(2.0 * rotation, outer, inner)
    with pytest.raises(AnalysisError, match="inner_position has 3 rows but the time grid has 400 points"):
        relative_position(rotation, outer, inner[:3])
    with pytest.raises(AnalysisError, match="clearance=0.0 must be positive"):
        orbit(rotation, outer, inner, clearance=0.0)
    with pytest.raises(AnalysisError, match="axis must be a non-zero 3-vector"):
        orbit(rotation, outer, inner, clearance=1e-4, axis=[0.0, 0.0, 0.0])
