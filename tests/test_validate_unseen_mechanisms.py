"""``clearance validate`` and its engines on mechanisms other than the 4-UPS/RPS, written here.

* a spatial double pendulum (a hinge, a floating second link held by a spherical
  closure S1; no actuator, so no driving force and no prescribed end-effector
  motion), with links fixed to the ground, to a moving link (with mass) and a
  massless tip link, all on fixed joints;
* a cart on a prismatic rail, its coordinate prescribed, carrying a balanced flywheel;
* a pendulum whose only joint is a revolute clearance joint (no ideal constraint left);
* a joint-driven four-bar and other mechanisms the cross-check engines do not model.

Each simulates at most 0.05 s.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

from robot.cli.common import EXIT_BAD_INPUT, EXIT_OK
from robot.cli.main import main
from robot.validation import newton_euler as NE
from robot.validation import study
from robot.validation.bodies import rpy_matrix

G = 9.81

INERTIAL = '<inertial><origin xyz="{com}" rpy="0 0 0"/><mass value="{mass}"/><inertia ixx="{ixx}" ixy="{ixy}" ixz="0" iyy="{iyy}" iyz="0" izz="{izz}"/></inertial>'
STEEL = "[materials.steel]\nyoungs_modulus = 2.07e11\npoisson_ratio = 0.3\n"


def _inertial(com: str, mass: float, ixx: float, iyy: float, izz: float, ixy: float = 0.0) -> str:
    return INERTIAL.format(com=com, mass=mass, ixx=ixx, iyy=iyy, izz=izz, ixy=ixy)


def _revolute(name: str, parent: str, child: str, xyz: str = "0 0 0", rpy: str = "0 0 0", axis: str = "1 0 0") -> str:
    return (
        f'<joint name="{name}" type="revolute"><parent link="{parent}"/><child link="{child}"/>'
        f'<origin xyz="{xyz}" rpy="{rpy}"/><axis xyz="{axis}"/><limit lower="-1000" upper="1000" effort="100" velocity="1000"/></joint>'
    )


def _fixed(name: str, parent: str, child: str, xyz: str, rpy: str = "0 0 0") -> str:
    return f'<joint name="{name}" type="fixed"><parent link="{parent}"/><child link="{child}"/><origin xyz="{xyz}" rpy="{rpy}"/></joint>'


def _transmission(joint: str) -> str:
    return (
        f'<transmission name="{joint}_tr"><type>transmission_interface/SimpleTransmission</type><joint name="{joint}">'
        "<hardwareInterface>hardware_interface/EffortJointInterface</hardwareInterface></joint>"
        f'<actuator name="{joint}_motor"><mechanicalReduction>1</mechanicalReduction></actuator></transmission>'
    )


def _numbers(values) -> str:
    """A URDF vector attribute: the numbers, space separated, exactly."""
    return " ".join(repr(float(v)) for v in values)


def _write(folder: Path, name: str, urdf: str, scene: str) -> Path:
    (folder / f"{name}.urdf").write_text(f'<?xml version="1.0"?>\n<robot name="{name}">\n{urdf}\n</robot>\n')
    path = folder / f"{name}.toml"
    path.write_text(f'name = "{name}"\nmechanism = "{name}.urdf"\n{scene}')
    return path


def double_pendulum(folder: Path, name: str = "dpend", end_effector: str = "link2", extra: str = "") -> Path:
    """A hinge (link1) and a second link on a floating joint held to link1's end by the spherical closure S1."""
    urdf = "\n".join(
        [
            '<link name="base"/>',
            f'<link name="link1">{_inertial("0 0 -0.25", 1.0, 0.021, 0.021, 0.001)}</link>',
            f'<link name="link2">{_inertial("0.05 0.02 -0.2", 0.8, 0.011, 0.012, 0.002, 0.001)}</link>',
            _revolute("hinge", "base", "link1"),
            '<joint name="link2_free" type="floating"><parent link="base"/><child link="link2"/><origin xyz="0 0 -0.5" rpy="0 0 0"/></joint>',
            '<closures><closure name="S1" type="spherical"><parent link="link1" xyz="0 0 -0.5" rpy="0 0 0"/>'
            '<child link="link2" xyz="0 0 0" rpy="0 0 0"/></closure></closures>',
        ]
    )
    scene = f'end_effector = "{end_effector}"\nduration = 0.1\n{extra}[initial]\npositions = {{ hinge = 0.3 }}\nvelocities = {{ hinge = 2.0 }}\n'
    return _write(folder, name, urdf, scene)


def double_pendulum_with_fixed_links(folder: Path) -> Path:
    """The double pendulum with its hinge on a link fixed to the ground ("mount"), a mass fixed to link1
    ("weight", offset and tilted, the closure's frame given on it) and a massless tip fixed to link2 (the end effector)."""
    weight_xyz, weight_rpy = np.array([0.05, 0.0, -0.3]), (0.3, 0.0, 0.0)
    s1_on_weight = rpy_matrix(weight_rpy).T @ (np.array([0.0, 0.0, -0.5]) - weight_xyz)  # link1's (0, 0, -0.5)
    urdf = "\n".join(
        [
            '<link name="base"/>',
            '<link name="mount"/>',
            f'<link name="link1">{_inertial("0 0 -0.25", 1.0, 0.021, 0.021, 0.001)}</link>',
            f'<link name="weight">{_inertial("0 0.01 0", 0.4, 0.001, 0.002, 0.0015, 0.0002)}</link>',
            f'<link name="link2">{_inertial("0.05 0.02 -0.2", 0.8, 0.011, 0.012, 0.002, 0.001)}</link>',
            '<link name="tip"/>',
            _fixed("mount_joint", "base", "mount", "0 0 0.1", "0 0 0.2"),
            _revolute("hinge", "mount", "link1", "0 0 -0.1", "0 0 -0.2"),
            _fixed("weight_joint", "link1", "weight", _numbers(weight_xyz), _numbers(weight_rpy)),
            '<joint name="link2_free" type="floating"><parent link="base"/><child link="link2"/><origin xyz="0 0 -0.5" rpy="0 0 0"/></joint>',
            _fixed("tip_joint", "link2", "tip", "0.1 0 -0.4"),
            f'<closures><closure name="S1" type="spherical"><parent link="weight" xyz="{_numbers(s1_on_weight)}" rpy="0 0 0"/>'
            '<child link="link2" xyz="0 0 0" rpy="0 0 0"/></closure></closures>',
        ]
    )
    scene = 'end_effector = "tip"\nduration = 0.1\n[initial]\npositions = { hinge = 0.3 }\nvelocities = { hinge = 2.0 }\n'
    return _write(folder, "dpend_fixed", urdf, scene)


def cart_on_rail(folder: Path, name: str, offset: float, phase: float = 0.0) -> Path:
    """A cart (1.5 kg) on a prismatic rail along x, driven ``s = offset + 0.05 sin(4 pi t + phase)``, carrying a flywheel
    (0.5 kg, centre of mass on its axis y) that spins freely at 3 rad/s."""
    urdf = "\n".join(
        [
            '<link name="base"/>',
            f'<link name="cart">{_inertial("0 0 0", 1.5, 0.01, 0.01, 0.01)}</link>',
            f'<link name="wheel">{_inertial("0 0 0", 0.5, 0.002, 0.004, 0.002)}</link>',
            '<joint name="rail" type="prismatic"><parent link="base"/><child link="cart"/><origin xyz="0 0 0" rpy="0 0 0"/>'
            '<axis xyz="1 0 0"/><limit lower="-2" upper="2" effort="100" velocity="100"/></joint>',
            _revolute("spin", "cart", "wheel", "0 0 0.1", axis="0 1 0"),
            _transmission("rail"),
        ]
    )
    scene = (
        'end_effector = "wheel"\nduration = 0.1\n[trajectory]\ntype = "joints"\nperiod = 0.5\n'
        f"rail = {{ offset = {offset!r}, amplitudes = [0.05], harmonics = [1.0], phases = [{phase!r}] }}\n"
        "[initial]\nvelocities = { spin = 3.0 }\n"
    )
    return _write(folder, name, urdf, scene)


def cart_rail_acceleration(t: np.ndarray, phase: float = 0.0) -> np.ndarray:
    """s''(t) of :func:`cart_on_rail`'s drive."""
    omega = 4.0 * math.pi
    return -0.05 * omega**2 * np.sin(omega * t + phase)


def four_bar(folder: Path, name: str, *, crank_actuated: bool, clearance: bool) -> Path:
    """A spatial crank-rocker four-bar (axes along z) closed by the revolute closure B; optionally the crank driven."""
    urdf = "\n".join(
        [
            '<link name="ground"/>',
            f'<link name="crank">{_inertial("0.03 0.004 0", 0.25, 6e-6, 5.7e-5, 6e-5)}</link>',
            f'<link name="coupler">{_inertial("0.09 -0.01 0", 0.4, 1.2e-4, 1.14e-3, 1.2e-3)}</link>',
            f'<link name="rocker">{_inertial("0.07 0.005 0", 0.35, 6e-5, 5.7e-4, 6e-4)}</link>',
            _revolute("crank", "ground", "crank", rpy="0 0 1.0471975511965976", axis="0 0 1"),
            _revolute("coupler", "crank", "coupler", "0.06 0 0", "0 0 -0.555", "0 0 1"),
            _revolute("rocker", "ground", "rocker", "0.16 0 0", "0 0 1.365", "0 0 1"),
            '<closures><closure name="B" type="revolute"><parent link="coupler" xyz="0.18 0 0" rpy="0 0 0"/>'
            '<child link="rocker" xyz="0.14 0 0" rpy="0 0 0"/><axis xyz="0 0 1"/></closure></closures>',
            _transmission("crank") if crank_actuated else "",
        ]
    )
    scene = 'end_effector = "rocker"\nduration = 0.1\ngravity = [0.0, -9.81, 0.0]\n'
    scene += '[trajectory]\ntype = "joints"\ncrank = { offset = 0.0, rate = 20.0 }\n' if crank_actuated else "[initial]\nvelocities = { crank = 20.0 }\n"
    if clearance:
        scene += STEEL + (
            '[[clearance]]\njoint = "B"\ntype = "revolute"\nouter_on = "parent"\njournal_radius = 0.005\nradial_clearance = 1.0e-4\n'
            "bearing_outer_radius = 0.008\nbearing_length = 0.01\naxial_clearance = 1.0e-4\nrestitution = 0.9\n"
        )
    return _write(folder, name, urdf, scene)


def pendulum_in_a_bearing(folder: Path) -> Path:
    """A pendulum (2 kg) whose only joint, the hinge, is a revolute clearance joint: no ideal constraint is left."""
    urdf = "\n".join(
        ['<link name="base"/>', f'<link name="bob">{_inertial("0 0 -0.5", 2.0, 0.01, 0.02, 0.01)}</link>', _revolute("hinge", "base", "bob", axis="0 1 0")]
    )
    scene = 'end_effector = "bob"\nduration = 0.1\n' + STEEL + (
        '[[clearance]]\njoint = "hinge"\ntype = "revolute"\nouter_on = "parent"\njournal_radius = 0.01\nradial_clearance = 1.0e-4\n'
        "bearing_outer_radius = 0.015\nbearing_length = 0.02\naxial_clearance = 1.0e-4\nrestitution = 0.9\n"
    )
    return _write(folder, "pendulum_bearing", urdf, scene)


def validate(capsys, *argv) -> tuple[int, str, str]:
    code = main(["validate", *(str(a) for a in argv)])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


def quiet(message: str) -> None:
    """The study's progress lines, not printed."""


# --- 1: joint-driven and undriven scenes finish; no "deviation from the ideal motion" without a platform-pose drive ----------
def test_an_undriven_scene_is_validated_and_has_no_ideal_motion_statistic(capsys, tmp_path):
    scene = double_pendulum(tmp_path)
    out = tmp_path / "out"
    code, stdout, err = validate(capsys, "--scenes", scene, "--duration", f"{scene}=0.03", "--engines", "newton_euler", "--out", out)
    assert code == EXIT_OK, err
    results = json.loads((out / "validation.json").read_text())
    metrics = results["scenes"][str(scene)]
    for name in ("lagrange", "newton_euler"):
        statistics = metrics["engines"][name]["statistics"]
        assert statistics["rms_ee_deviation_from_ideal_m"] is None and statistics["max_ee_deviation_from_ideal_m"] is None
        assert statistics["mean_driving_force_N"] == []  # no actuator
    pointwise = metrics["engines"]["newton_euler"]["pointwise_whole_run"]
    assert pointwise["driving_force_max_abs_N"] is None
    assert pointwise["body_position_max_m"] < 1e-9 and pointwise["ee_position_max_m"] < 1e-9
    assert "EE rms dev" not in stdout and "dBodies" in stdout
    # the figures are named after the scene file, not its path
    assert {"validation_dpend.png", "deviation_dpend.png"} <= {p.name for p in out.iterdir()}


def test_a_joint_driven_cart_pushes_with_mass_times_acceleration_in_every_engine(tmp_path):
    """Cart + balanced flywheel on a prescribed rail: F = (m_cart + m_wheel) s''(t) (gravity is normal to the rail)."""
    scene = cart_on_rail(tmp_path, "cart", offset=0.3)
    engines = ("lagrange", "newton_euler", "exudyn") if _has_exudyn() else ("lagrange", "newton_euler")
    metrics, series = study.compare_scene(str(scene), 0.05, engines, progress=quiet)
    assert metrics["engines"]["lagrange"]["statistics"]["rms_ee_deviation_from_ideal_m"] is None
    total_mass = 1.5 + 0.5
    for name in engines:
        s = series[name]
        keep = s.t > (1e-3 if name == "exudyn" else 0.0)  # past generalized-alpha's start-up (and its undefined first force)
        expected = total_mass * cart_rail_acceleration(s.t[keep])
        tolerance = 1e-3 if name == "exudyn" else 1e-7
        assert np.max(np.abs(s.driving_force[keep, 0] - expected)) <= tolerance * np.max(np.abs(expected)), name
    for name in engines[1:]:
        assert metrics["engines"][name]["pointwise_before_first_impact"]["body_position_max_m"] < 1e-9, name


def _has_exudyn() -> bool:
    import importlib.util

    return importlib.util.find_spec("exudyn") is not None


# --- 2, 3, 7: what an engine does not model is refused before any run, naming scene, engine and feature ----------------------
def _massless_cross(folder: Path) -> Path:
    """A universal joint whose cross has no <inertial> (a moving body without mass)."""
    urdf = "\n".join(
        [
            '<link name="base"/>',
            '<link name="cross"/>',
            f'<link name="arm">{_inertial("0 0 -0.3", 1.0, 0.03, 0.03, 0.001)}</link>',
            _revolute("ux", "base", "cross", axis="1 0 0"),
            _revolute("uy", "cross", "arm", axis="0 1 0"),
        ]
    )
    return _write(folder, "massless_cross", urdf, 'end_effector = "arm"\nduration = 0.1\n[initial]\nvelocities = { ux = 1.0 }\n')


REFUSED = {
    # case: (scene builder, engines, words the message must contain)
    "actuated revolute joint": (lambda f: four_bar(f, "four_bar_driven", crank_actuated=True, clearance=False), "newton_euler", ["actuated joint 'crank' is revolute", "prismatic"]),
    "revolute closure without clearance": (lambda f: four_bar(f, "four_bar_free", crank_actuated=False, clearance=False), "exudyn", ["closure 'B'", "revolute", "spherical closures"]),
    "massless moving link": (_massless_cross, "newton_euler", ["'cross'", "no mass", "fixed joints"]),
    "force element": (
        lambda f: double_pendulum(f, "dpend_spring", extra='[[force]]\nname = "hinge_spring"\ntype = "joint_spring_damper"\njoint = "hinge"\nstiffness = 20.0\nrest_position = 0.0\n'),
        "newton_euler",
        ["'hinge_spring' (joint_spring_damper)", "no force elements"],
    ),
    "force-driven actuator": (
        lambda f: double_pendulum(f, "dpend_torque", extra='[actuators]\nhinge = { mode = "force", function = "constant", value = 1.0 }\n'),
        "exudyn",
        ["force-driven actuator(s) 'hinge'", "prescribed-motion actuators"],
    ),
    "actuator length starting at 0": (lambda f: cart_on_rail(f, "cart_at_zero", offset=0.0), "exudyn", ["actuator 'rail'", "0 m at t = 0 s", "> 0"]),
    "actuator length crossing 0": (lambda f: cart_on_rail(f, "cart_crossing", offset=0.02, phase=math.pi), "exudyn", ["actuator 'rail'", "> 0", "--engines newton_euler"]),
}


@pytest.mark.parametrize("case", list(REFUSED))
def test_what_an_engine_does_not_model_is_refused_before_any_run(capsys, tmp_path, monkeypatch, case):
    build, engine, words = REFUSED[case]
    scene = build(tmp_path)
    runs = []
    monkeypatch.setattr(study, "run_scene", lambda *args, **kwargs: runs.append(args))
    out = tmp_path / "out"
    code, _, err = validate(capsys, "--scenes", scene, "--duration", f"{scene}=0.05", "--engines", engine, "--out", out)
    assert code == EXIT_BAD_INPUT, err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1
    for word in [str(scene), f"the {engine} engine", *words]:
        assert word in err, (word, err)
    assert runs == [] and not out.exists()  # refused before the Lagrange run and before anything was written


def test_the_other_engine_still_takes_a_scene_only_one_refuses(capsys, tmp_path):
    """The rail coordinate crossing 0 is refused by Exudyn only: Newton-Euler models a signed coordinate."""
    scene = cart_on_rail(tmp_path, "cart_crossing", offset=0.02, phase=math.pi)
    code, _, err = validate(capsys, "--scenes", scene, "--duration", f"{scene}=0.05", "--engines", "newton_euler", "--no-figures", "--out", tmp_path / "out")
    assert code == EXIT_OK, err
    metrics = json.loads((tmp_path / "out" / "validation.json").read_text())["scenes"][str(scene)]
    assert metrics["engines"]["newton_euler"]["pointwise_whole_run"]["driving_force_max_rel"] < 1e-6


# --- fixed joints: links merged into their carriers, as in Pinocchio ----------------------------------------------------------
def test_links_on_fixed_joints_are_merged_into_their_carriers(tmp_path):
    """Mount fixed to the ground, a tilted mass fixed to link1 carrying the closure, a massless tip as end effector."""
    scene = double_pendulum_with_fixed_links(tmp_path)
    engines = ("lagrange", "newton_euler", "exudyn") if _has_exudyn() else ("lagrange", "newton_euler")
    metrics, series = study.compare_scene(str(scene), 0.03, engines, progress=quiet)
    lagrange = series["lagrange"]
    assert np.linalg.norm(lagrange.ee_position[-1] - lagrange.ee_position[0]) > 1e-3  # the tip moves: the check means something
    newton_euler = metrics["engines"]["newton_euler"]["pointwise_whole_run"]
    assert newton_euler["ee_position_max_m"] < 1e-9 and newton_euler["body_position_max_m"] < 1e-9
    if "exudyn" in engines:
        exudyn = metrics["engines"]["exudyn"]["pointwise_before_first_impact"]
        assert exudyn["ee_position_max_m"] < 1e-7 and exudyn["body_position_max_m"] < 1e-7


# --- 4: the bodies' positions are compared, so a wrong engine is caught when the end effector stands still ------------------
def test_a_wrong_engine_is_caught_by_the_body_positions_when_the_end_effector_stands_still(tmp_path, monkeypatch):
    scene = double_pendulum(tmp_path, "dpend_hinge_ee", end_effector="link1")  # link1's origin is the fixed hinge
    correct, _ = study.compare_scene(str(scene), 0.03, ("lagrange", "newton_euler"), progress=quiet)
    assert correct["engines"]["newton_euler"]["pointwise_whole_run"]["body_position_max_m"] < 1e-9
    build_model = NE.build_model

    def upside_down(run):
        model = build_model(run)
        model.gravity = -model.gravity
        return model

    monkeypatch.setattr(NE, "build_model", upside_down)
    wrong, series = study.compare_scene(str(scene), 0.03, ("lagrange", "newton_euler"), progress=quiet)
    pointwise = wrong["engines"]["newton_euler"]["pointwise_whole_run"]
    assert pointwise["ee_position_max_m"] < 1e-12  # the end effector alone sees no difference
    # gravity reversed: relative acceleration up to 2 g, i.e. millimetres after 0.03 s
    assert pointwise["body_position_max_m"] > 1e-3
    table = study.summary_table({"scenes": {"dpend": wrong}})
    assert "dBodies" in table


# --- 5: a scene's own duration when --duration does not name it ----------------------------------------------------------------
def test_a_scene_runs_over_its_own_duration_unless_told_otherwise(capsys, tmp_path):
    scene = double_pendulum(tmp_path)
    text = scene.read_text().replace("duration = 0.1", "duration = 0.02")
    scene.write_text(text)
    code, _, err = validate(capsys, "--scenes", scene, "--engines", "newton_euler", "--no-figures", "--out", tmp_path / "out")
    assert code == EXIT_OK, err
    metrics = json.loads((tmp_path / "out" / "validation.json").read_text())["scenes"][str(scene)]
    assert metrics["duration_s"] == 0.02
    assert metrics["engines"]["lagrange"]["t_last_record_s"] == pytest.approx(0.02, abs=1e-12)
    args = study.parse_args(["--scenes", "ideal", str(scene), "--duration", f"{scene}=0.01"])
    assert study.scene_durations(args) == {"ideal": study.DEFAULT_DURATIONS["ideal"], str(scene): 0.01}


# --- 6: Newton-Euler with no ideal constraint left ----------------------------------------------------------------------------
def test_newton_euler_runs_a_mechanism_without_ideal_constraints(tmp_path):
    """The pendulum's journal is centred in its bearing: it falls freely until the first impact, as in the Lagrange model."""
    run = study.build_run(str(pendulum_in_a_bearing(tmp_path)), duration=0.012)
    from robot.validation.settings import with_solver

    run = with_solver(run)
    result = NE.simulate(run)
    assert result.success, result.run.message
    assert np.all(result.arrays["constraint_residual"] == 0.0)  # nothing to violate
    lagrange = study.lagrange_series(run)
    first = lagrange.first_onset
    newton_euler_first = min(t for t, _, kind in result.run.events if kind == "onset")
    assert abs(newton_euler_first - first) < 1e-8
    # before the impact: free fall, the origin drops by g t^2 / 2
    t, origins = result.arrays["t"], result.arrays["body_origins"][:, 0]
    before = t < first
    drop = origins[0, 2] - origins[before, 2]
    assert np.max(np.abs(drop - 0.5 * G * t[before] ** 2)) < 1e-9
    assert np.max(np.abs(origins[before, :2] - origins[0, :2])) < 1e-12
    # the radial clearance (1e-4 m) is closed at the impact: after 0.5 g t^2 = 1e-4 m
    assert first == pytest.approx(math.sqrt(2 * 1e-4 / G), rel=1e-3)
