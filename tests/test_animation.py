"""Animation export (robot.viz.animation, scripts/animate.py): fast checks, no browser.

Results are made here without integrating (poses from the platform inverse
kinematics plus a prescribed motion inside the clearance joints) and written
with robot.io.results.save_result, so these tests do not depend on the
simulator's speed; one test animates a real short simulation.
"""

from __future__ import annotations

import base64
import math
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pinocchio as pin
import pytest
import umsgpack

from clearance_contact import RevoluteClearanceJoint
from robot.errors import ResultFileError
from robot.model.mechanism import build_mechanism
from robot.model.platform_kinematics import PlatformLayout, inverse_kinematics
from robot.io.results import SimulationResult, load_result, mechanism_fingerprint, save_result
from robot.model.trajectory import reference_platform_motion
from robot.viz.animation import (
    AnimationError,
    AnimationOptions,
    _exaggerated_inner,
    export_html,
    external_references,
    frame_count,
    load_for_animation,
)

REPO = Path(__file__).resolve().parents[1]
URDF = REPO / "urdf" / "ups_rps.urdf"
CLEARANCE = 1.0e-4


def synthetic_result(clearance: list[str], duration: float = 0.2, n: int = 41, scene_file: str | None = None) -> SimulationResult:
    """A result of the reference platform motion with the clearance elements orbiting inside their gaps.

    S1: the RPS piston is lengthened by up to 1.2 clearances (ball pressed into
    the socket); R1: the journal-bearing free-flyer moves on a radial circle of
    0.8 clearances with a small tilt. Normal forces are a half-sine pulse.
    """
    mechanism = build_mechanism(URDF, clearance)
    model, data = mechanism.model, mechanism.model.createData()
    layout = PlatformLayout.from_mechanism(mechanism)
    motion = reference_platform_motion(layout, 1.0)
    t = np.linspace(0.0, duration, n)
    q = np.empty((n, model.nq))
    arrays: dict[str, np.ndarray] = {}
    forces = {}
    for i, ti in enumerate(t):
        qi, _ = inverse_kinematics(layout, motion.pose(ti)[0])
        phase = 2 * math.pi * ti / duration
        if "S1" in clearance:
            qi[model.idx_qs[model.getJointId("P5")]] += 1.2 * CLEARANCE * math.sin(phase)
        if "R1" in clearance:
            j = model.getJointId("R1")
            placement = pin.XYZQUATToSE3(qi[model.idx_qs[j] : model.idx_qs[j] + 7])
            offset = 0.8 * CLEARANCE * np.array([math.cos(phase), math.sin(phase), 0.0])
            tilt = pin.exp3(np.array([1.0, 0.0, 0.0]) * 4e-5 * math.sin(phase))
            placement = placement * pin.SE3(tilt, offset)
            qi[model.idx_qs[j] : model.idx_qs[j] + 7] = pin.SE3ToXYZQUAT(placement)
        q[i] = qi
    pulse = np.maximum(np.sin(2 * math.pi * t / duration), 0.0) * 2000.0
    for site in mechanism.clearance_sites:
        if site.kind == "spherical":
            e = np.empty((n, 3))
            for i in range(n):
                pin.framesForwardKinematics(model, data, q[i])
                outer, inner = data.oMf[site.outer_frame], data.oMf[site.inner_frame]
                e[i] = outer.rotation.T @ (inner.translation - outer.translation)
            penetration = (np.linalg.norm(e, axis=1) - CLEARANCE)[:, None]
            arrays[f"{site.name}_eccentricity"] = e
            forces[site.name] = np.where(penetration > 0, pulse[:, None], 0.0)
        else:
            penetration = np.full((n, 4), -CLEARANCE)
            arrays[f"{site.name}_eccentricity"] = np.zeros((n, 2, 3))
            forces[site.name] = np.column_stack([pulse, 0.3 * pulse, 0.5 * pulse[::-1], np.zeros(n)])
        arrays[f"{site.name}_penetration"] = penetration
        arrays[f"{site.name}_normal_force"] = forces[site.name]
        arrays[f"{site.name}_friction_force"] = 0.05 * forces[site.name]
        arrays[f"{site.name}_kind"] = (forces[site.name] > 0).astype(np.int8)
    arrays.update(
        t=t, q=q, v=np.zeros((n, model.nv)), driving_force=np.zeros((n, 5)), ee_position=np.zeros((n, 3)),
        record_kind=np.zeros(n, dtype=np.int8),
    )
    metadata = {
        "mechanism": URDF.name,
        "urdf_sha256": mechanism_fingerprint(URDF.read_text(encoding="utf-8")),
        "clearance": list(clearance),
        "scene_file": scene_file,
        "duration": duration,
    }
    counts = {"n_steps": n, "n_rejected": 0, "n_rhs": 0, "n_events": 0, "n_restarts": 0, "cpu_time": 0.0, "wall_time": 0.0}
    return SimulationResult("synthetic", 0, "made by the animation tests", None, duration, counts, arrays, metadata)


def write_result(tmp_path: Path, clearance: list[str], **kwargs) -> Path:
    return save_result(synthetic_result(clearance, **kwargs), tmp_path / f"{'_'.join(clearance) or 'ideal'}.npz")


def commands(page: str) -> list[dict]:
    """The meshcat commands embedded in an exported page, decoded."""
    return [umsgpack.unpackb(base64.b64decode(b)) for b in re.findall(r'meshcatCommand\("([A-Za-z0-9+/=]+)"\)', page)]


def animation_tracks(page: str) -> dict[str, dict]:
    (animation,) = [c for c in commands(page) if c["type"] == "set_animation"]
    return {a["path"]: {t["name"]: t for t in a["clip"]["tracks"]} for a in animation["animations"]}


@pytest.fixture(scope="module")
def compound_result(tmp_path_factory) -> Path:
    return write_result(tmp_path_factory.mktemp("results"), ["S1", "R1"])


def test_html_is_self_contained_and_has_the_expected_frames(compound_result, tmp_path):
    html = tmp_path / "out" / "anim.html"
    summary = export_html(compound_result, html, exaggerate=200, speed=0.05, fps=30)
    page = html.read_text(encoding="utf-8")
    assert external_references(page) == []
    # nothing fetched: no script/link/img tags with a source, no absolute URL with a host
    assert not re.search(r"<script[^>]*\bsrc\s*=", page, re.IGNORECASE)
    assert not re.search(r"<(link|img|iframe)\b", page, re.IGNORECASE)
    assert not re.search(r"(https?|wss?)://(?!www\.w3\.org/)[A-Za-z0-9]", page)
    assert "MeshCat.Viewer" in page  # the viewer bundle is inlined
    expected = frame_count(0.0, 0.2, 0.05, 30)
    assert expected == 121 == summary.n_frames
    tracks = animation_tracks(page)
    platform = tracks["/meshcat/mechanism/links/visuals/platform_0"]
    assert len(platform[".position"]["keys"]) == expected
    assert platform[".position"]["keys"][-1]["time"] == expected - 1
    # every clearance element and force arrow is animated; revolute joints have four candidates
    for path in ("S1/outer", "S1/inner", "R1/outer", "R1/inner", "S1/force0/shaft", "R1/force3/head"):
        assert f"/meshcat/mechanism/clearance/{path}" in tracks
    assert summary.html_bytes < 5_000_000
    assert {s.kind for s in summary.sizes.values()} == {"spherical", "revolute"}


def test_exaggeration_scales_the_gap_and_the_relative_displacement(compound_result, tmp_path):
    k = 150.0
    page = (export_html(compound_result, tmp_path / "a.html", exaggerate=k, speed=0.2).html_path).read_text()
    objects = {c["path"]: c["object"] for c in commands(page) if c["type"] == "set_object"}
    socket = objects["/meshcat/mechanism/clearance/S1/outer/socket"]["geometries"][0]["radius"]
    ball = objects["/meshcat/mechanism/clearance/S1/inner/ball"]["geometries"][0]["radius"]
    assert ball == pytest.approx(0.015)
    assert socket - ball == pytest.approx(k * CLEARANCE)
    tracks = animation_tracks(page)
    mechanism, result = load_for_animation(compound_result)
    data = mechanism.model.createData()
    site = mechanism.site("S1")
    outer_keys = tracks["/meshcat/mechanism/clearance/S1/outer"][".position"]["keys"]
    inner_keys = tracks["/meshcat/mechanism/clearance/S1/inner"][".position"]["keys"]
    frame = 10  # speed 0.2 at 30 fps: one frame every 1/150 s; records every 0.005 s
    tk = frame * 0.2 / 30
    i = int(np.searchsorted(result["t"], tk)) - 1
    alpha = (tk - result["t"][i]) / (result["t"][i + 1] - result["t"][i])
    pin.framesForwardKinematics(mechanism.model, data, pin.interpolate(mechanism.model, result["q"][i], result["q"][i + 1], alpha))
    true = data.oMf[site.inner_frame].translation - data.oMf[site.outer_frame].translation
    drawn = np.array(inner_keys[frame]["value"]) - np.array(outer_keys[frame]["value"])
    np.testing.assert_allclose(drawn, k * true, atol=1e-9)


def test_revolute_tilt_is_magnified_through_its_tangent():
    outer = pin.SE3(pin.exp3(np.array([0.1, -0.2, 0.3])), np.array([0.1, 0.2, 0.3]))
    tilt, spin = 1e-3, 0.7
    relative = pin.SE3(pin.exp3(np.array([0.0, tilt, 0.0])) @ pin.exp3(np.array([0.0, 0.0, spin])), np.array([1e-5, 0.0, 2e-5]))
    inner = outer * relative
    drawn = outer.actInv(_exaggerated_inner(outer, inner, RevoluteClearanceJoint, 100.0))
    assert math.acos(drawn.rotation[2, 2]) == pytest.approx(math.atan(100 * math.tan(tilt)), rel=1e-9)
    np.testing.assert_allclose(drawn.translation, 100 * relative.translation, atol=1e-12)
    unchanged = outer.actInv(_exaggerated_inner(outer, inner, RevoluteClearanceJoint, 1.0))
    np.testing.assert_allclose(unchanged.rotation, relative.rotation, atol=1e-12)


def test_ideal_result_animates_without_clearance_elements(tmp_path):
    path = write_result(tmp_path, [], n=5, duration=0.1)
    page = export_html(path, tmp_path / "ideal.html", speed=0.1).html_path.read_text()
    assert not any("/clearance/" in c.get("path", "") for c in commands(page))


def test_missing_result_file(tmp_path):
    with pytest.raises(ResultFileError, match="does not exist"):
        export_html(tmp_path / "nothing.npz", tmp_path / "a.html")
    assert not (tmp_path / "a.html").exists()


def test_malformed_result_files(tmp_path):
    garbage = tmp_path / "garbage.npz"
    garbage.write_bytes(b"this is not an npz archive")
    with pytest.raises(ResultFileError, match=r"not a result file \(.npz\) of `clearance run`"):
        export_html(garbage, tmp_path / "a.html")
    headless = tmp_path / "headless.npz"
    np.savez(headless, t=np.zeros(3))
    with pytest.raises(ResultFileError, match="no header"):
        export_html(headless, tmp_path / "a.html")
    result = synthetic_result(["S1"], n=5)
    result.arrays["q"] = result.arrays["q"][:, :-1]
    with pytest.raises(ResultFileError, match="'q' has shape"):
        export_html(save_result(result, tmp_path / "short_q.npz"), tmp_path / "a.html")
    result = synthetic_result(["S1"], n=5)
    del result.arrays["S1_normal_force"]
    with pytest.raises(ResultFileError, match="S1_normal_force"):
        export_html(save_result(result, tmp_path / "no_force.npz"), tmp_path / "a.html")
    result = synthetic_result(["S1"], n=5)
    del result.metadata["mechanism"]
    with pytest.raises(ResultFileError, match="does not name its mechanism"):
        export_html(save_result(result, tmp_path / "anonymous.npz"), tmp_path / "a.html")


def test_result_from_another_mechanism(tmp_path):
    result = synthetic_result(["S1"], n=5)
    result.metadata["urdf_sha256"] = mechanism_fingerprint("<robot name='other'/>")
    path = save_result(result, tmp_path / "foreign.npz")
    with pytest.raises(ResultFileError, match="fingerprint differs"):
        export_html(path, tmp_path / "a.html")
    # an explicit mechanism file that is not the result's
    other = tmp_path / "other.urdf"
    other.write_text(URDF.read_text(encoding="utf-8").replace("ups_rps", "ups_rps_copy"), encoding="utf-8")
    with pytest.raises(ResultFileError, match="fingerprint differs"):
        export_html(write_result(tmp_path, ["S1"], n=5), tmp_path / "a.html", urdf=other)
    result = synthetic_result(["S1"], n=5)
    result.metadata["mechanism"] = "no_such_mechanism.urdf"
    with pytest.raises(ResultFileError, match="does not exist"):
        export_html(save_result(result, tmp_path / "lost.npz"), tmp_path / "a.html")


def test_bad_options(compound_result, tmp_path):
    with pytest.raises(AnimationError, match="exaggerate"):
        export_html(compound_result, tmp_path / "a.html", exaggerate=0.5)
    with pytest.raises(AnimationError, match="speed"):
        export_html(compound_result, tmp_path / "a.html", speed=0.0)
    with pytest.raises(AnimationError, match="raise the speed"):
        export_html(compound_result, tmp_path / "a.html", speed=1e-5)
    with pytest.raises(TypeError):
        AnimationOptions(no_such_option=1)  # type: ignore[call-arg]


def test_script_writes_html_and_reports_errors(compound_result, tmp_path):
    script = REPO / "scripts" / "animate.py"
    html = tmp_path / "script.html"
    run = subprocess.run(
        [sys.executable, str(script), str(compound_result), "--html", str(html), "--speed", "0.1", "--exaggerate", "100"],
        capture_output=True, text=True, timeout=120,
    )
    assert run.returncode == 0, run.stderr
    assert html.is_file() and "frames" in run.stdout
    run = subprocess.run([sys.executable, str(script), str(tmp_path / "missing.npz"), "--html", str(html)], capture_output=True, text=True, timeout=120)
    assert run.returncode == 2
    assert "does not exist" in run.stderr and "Traceback" not in run.stderr


def test_real_short_simulation_animates(tmp_path):
    from robot.run import build_run, run_scene

    run = build_run("spherical", duration=0.02)
    result = run_scene(run)
    path = save_result(result, tmp_path / "spherical.npz")
    summary = export_html(path, tmp_path / "spherical.html", speed=0.01, exaggerate=100)
    assert summary.n_frames == frame_count(0.0, float(load_result(path)["t"][-1]), 0.01, 30)
    assert summary.sizes["S1"].source == "result metadata"
    assert summary.sizes["S1"].values["clearance"] == 1.0e-4  # as the scene gave it, not R_s - R_b


def test_arrows_sit_at_the_contact_law_points():
    from clearance_contact import STEEL, RevoluteClearanceJoint

    from robot.viz.animation import ElementSizes, _drawing_law, _law_contacts

    geometry = {"journal_radius": 0.02, "radial_clearance": 1e-4, "bearing_outer_radius": 0.035, "bearing_length": 0.04, "axial_clearance": 1e-4}
    size = ElementSizes("revolute", geometry)
    law = _drawing_law(size, 1.0)
    assert isinstance(law, RevoluteClearanceJoint) and law.journal_length == pytest.approx(0.0401)
    outer = pin.SE3(pin.exp3(np.array([0.1, 0.2, 0.3])), np.array([0.1, 0.2, 0.3]))
    inner = outer * pin.SE3(pin.exp3(np.array([2e-3, 0.0, 0.0])), np.array([1.2e-4, 0.0, 0.0]))
    reference = RevoluteClearanceJoint(0.02, 0.0201, 0.035, 0.0401, 0.04, STEEL, STEEL).evaluate(
        outer.rotation, outer.translation, np.zeros(6), inner.rotation, inner.translation, np.zeros(6), np.zeros(4)
    )
    drawn = _law_contacts(law, outer, inner)
    for j in range(4):
        np.testing.assert_allclose(drawn[j][0], 0.5 * (reference.point_inner[j] + reference.point_outer[j]), atol=1e-12)
        np.testing.assert_allclose(drawn[j][1], -reference.normal[j], atol=1e-12)
    # magnified by k: the gaps grow k-fold, the bearing wall keeps its true thickness
    magnified = _drawing_law(size, 7.0)
    assert magnified.radial_clearance == pytest.approx(7e-4) and magnified.axial_clearance == pytest.approx(7e-4)
    assert magnified.bearing_outer_radius - magnified.bearing_inner_radius == pytest.approx(0.035 - 0.0201)


def test_live_server_serves_the_scene():
    import urllib.request

    from robot.viz.animation import serve_live

    vis, summary = serve_live(synthetic_result(["S1"], n=5), speed=0.1)
    try:
        with urllib.request.urlopen(summary.url, timeout=10) as reply:
            assert reply.status == 200 and b"MeshCat" in reply.read()
    finally:
        process = vis.window.server_proc
        process.kill()
        process.wait()
