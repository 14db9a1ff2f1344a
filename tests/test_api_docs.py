"""The public API: docs/api.md's examples run as written; Result is one type in memory and on disk."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

import robot
from robot.errors import Error, RobotError, SceneError
from clearance_contact.errors import ContactError

DOC = Path(__file__).resolve().parents[1] / "docs" / "api.md"


def test_api_doc_examples_run(tmp_path, monkeypatch):
    blocks = re.findall(r"```python\n(.*?)```", DOC.read_text(encoding="utf-8"), flags=re.S)
    assert len(blocks) >= 4
    monkeypatch.chdir(tmp_path)
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, str(DOC), "exec"), namespace)  # noqa: S102 - the documentation's own examples
    assert (tmp_path / "out" / "compound_misaligned.npz").is_file()
    assert (tmp_path / "out" / "compound_misaligned.html").is_file()
    assert namespace["again"].joint("R1").normal_force.max() > 0.0


def test_one_exception_root_with_key_and_value():
    assert issubclass(RobotError, Error) and issubclass(ContactError, Error)
    with pytest.raises(Error) as info:
        robot.load_scene("spherical", {"clearance.S1.restitution": 1.5})
    assert info.value.key == "restitution" and info.value.value == 1.5
    with pytest.raises(SceneError) as info:
        robot.load_scene("spherical", {"solver.rtol": float("nan")})
    assert info.value.key == "rtol"
    with pytest.raises(SceneError, match="no \\[\\[clearance\\]\\] entry with joint = 'Q7'"):
        robot.load_scene("spherical", {"clearance.Q7.restitution": 0.5})


def test_overrides_equal_the_same_change_in_a_file(tmp_path):
    """A key path set from Python gives the scene that the edited file gives."""
    changed = robot.load_scene("revolute", {"clearance.R1.restitution": 0.7, "solver.rtol": 3e-7, "trajectory.period": 1.25})
    text = 'extends = "revolute"\n[solver]\nrtol = 3e-7\n[trajectory]\nperiod = 1.25\n'
    base = robot.load_scene("revolute")
    entry = dict(base.document["clearance"][0], restitution=0.7)
    lines = [f"{k} = {v!r}".replace("'", '"') for k, v in entry.items() if not isinstance(v, dict)]
    lines += [f"{k} = {{ {', '.join(f'{a} = {b!r}'.replace(chr(39), chr(34)) for a, b in v.items())} }}" for k, v in entry.items() if isinstance(v, dict)]
    path = tmp_path / "edited.toml"
    path.write_text(text + "[[clearance]]\n" + "\n".join(lines) + "\n")
    edited = robot.load_scene(path)
    assert changed.solver == edited.solver and changed.trajectory == edited.trajectory
    assert changed.clearances[0].law.restitution == edited.clearances[0].law.restitution == 0.7


def test_result_counts_follow_oderesult():
    result = robot.simulate("spherical", t_end=0.01)
    assert result.success and result.status == 0
    assert result.nfev == result.counts["n_rhs"] > result.nsteps > 0
    assert result.t[0] == 0.0 and result.t[-1] == pytest.approx(0.01)
    assert result.y.shape == (result.q.shape[1] + result.v.shape[1], len(result.t))
    with pytest.raises(robot.Error, match="not a clearance joint"):
        result.joint("R1")
    with pytest.raises(AttributeError, match="has no array 'nothing'"):
        result.joint("S1").nothing
    s1 = result.joint("S1")
    assert np.all(s1.normal_force[s1.penetration <= 0.0] == 0.0)  # no force out of contact
    assert np.all(s1.normal_force[s1.penetration > 0.0] >= 0.0)  # no adhesion


def test_simulate_refuses_a_bad_horizon():
    with pytest.raises(SceneError) as info:
        robot.simulate("ideal", t_end=-1.0)
    assert info.value.key == "t_end"
