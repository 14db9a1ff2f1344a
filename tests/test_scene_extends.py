"""Scenes that extend others (merge, names, relative paths) and CSV time tables checked row by row.

docs/scenes.md, "extends": tables merge key by key at every depth (arrays of
tables and tables switching their ``function`` / ``mode`` are replaced whole),
a child inherits every key but ``name``, and every relative path resolves
against the folder of the file that writes it. Each scene here is checked
with ``load_scene`` or ``clearance run --check``: nothing is integrated.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from robot.cli.common import EXIT_BAD_INPUT, EXIT_OK
from robot.cli.main import main
from robot.data import shipped_urdf
from robot.errors import SceneError
from robot.model import time_functions as TF
from robot.scene import load_scene

#: a [[force]] table of a tabulated body force read from FILE
FORCE_FROM_FILE = """
[[force]]
name = "push"
type = "body_force"
link = "forearm"
direction = [0.0, 0.0, 1.0]
function = "tabulated"
file = "{file}"
"""

#: a stand-alone scene (no extends) with that force
ARM = 'name = "arm"\nmechanism = "two_link_arm.urdf"\nduration = 1.0\n' + FORCE_FROM_FILE


def write(path: Path, text: str) -> Path:
    path.parent.mkdir(parents=True, exist_ok=True)
    path.write_text(text, encoding="utf-8")
    return path


def check(capsys, path: Path) -> tuple[int, str]:
    code = main(["run", "--scene", str(path), "--check"])
    return code, capsys.readouterr().err


# --- CSV time tables ---------------------------------------------------------------------


@pytest.mark.parametrize(
    "rows, message",
    [
        ("0,0\n1,nan\n2,0\n", "the value column must hold finite numbers; entry 1 (data row 1.0, nan) is nan"),
        ("0,0\n1,inf\n2,0\n", "the value column must hold finite numbers; entry 1 (data row 1.0, inf) is inf"),
        ("0,0\nnan,1\n2,0\n", "the time column must hold finite numbers; entry 1 (data row nan, 1.0) is nan"),
        ("0,0\n1,1\ninf,0\n", "the time column must hold finite numbers; entry 2 (data row inf, 0.0) is inf"),
        ("0,0\n1,1\n0.5,0\n2,0\n", "the time column must be strictly increasing; entry 2 (0.5) follows 1.0"),
    ],
)
def test_a_csv_table_with_a_bad_row_exits_2_naming_file_row_and_value(tmp_path, capsys, rows, message):
    write(tmp_path / "table.csv", "time,value\n" + rows)
    scene = write(tmp_path / "S.toml", ARM.format(file="table.csv"))
    with pytest.raises(SceneError) as error:
        load_scene(scene)
    assert error.value.key == "file" and error.value.value == "table.csv"
    assert f"file='table.csv': {message}, in {str(tmp_path / 'table.csv')!r}" in str(error.value)
    code, err = check(capsys, scene)
    assert code == EXIT_BAD_INPUT and message in err and "Traceback" not in err


def test_a_good_csv_table_is_read(tmp_path):
    write(tmp_path / "table.csv", "time,value\n# a comment\n0,0\n0.5,2\n1,0\n")
    scene = load_scene(write(tmp_path / "S.toml", ARM.format(file="table.csv")))
    function = scene.forces[0].parameters["function"]
    assert isinstance(function, TF.Tabulated) and list(function.x) == [0.0, 0.5, 1.0] and list(function.y) == [0.0, 2.0, 0.0]


def test_a_csv_path_that_is_a_folder_is_refused(tmp_path, capsys):
    (tmp_path / "table.csv").mkdir()
    code, err = check(capsys, write(tmp_path / "S.toml", ARM.format(file="table.csv")))
    assert code == EXIT_BAD_INPUT and "file='table.csv'" in err and "cannot be read" in err


# --- relative paths with extends ---------------------------------------------------------


def test_a_childs_file_resolves_against_the_childs_folder(tmp_path, capsys):
    """The child extends a shipped scene (in robot/scene/scenes/): its own CSV is beside it."""
    child = write(tmp_path / "fc" / "S.toml", 'extends = "free_two_link_spring"\nduration = 1.0\n' + FORCE_FROM_FILE.format(file="missing.csv"))
    with pytest.raises(SceneError, match="does not exist") as error:
        load_scene(child)
    assert str(tmp_path / "fc" / "missing.csv") in str(error.value)
    write(tmp_path / "fc" / "missing.csv", "0,1\n1,2\n")
    assert check(capsys, child)[0] == EXIT_OK
    assert list(load_scene(child).forces[-1].parameters["function"].y) == [1.0, 2.0]


def test_a_parents_paths_resolve_against_the_parents_folder(tmp_path):
    """Parent in a/ (mechanism and CSV beside it), child in b/ with a CSV of the same name: each file's own."""
    write(tmp_path / "a" / "table.csv", "0,1\n1,1\n")
    shutil.copy(shipped_urdf("two_link_arm.urdf"), tmp_path / "a" / "arm.urdf")
    write(tmp_path / "a" / "parent.toml", ARM.format(file="table.csv").replace("two_link_arm.urdf", "arm.urdf"))
    write(tmp_path / "b" / "table.csv", "0,2\n1,2\n")
    inherits = load_scene(write(tmp_path / "b" / "child.toml", 'extends = "../a/parent.toml"\n'))
    assert inherits.mechanism_path == (tmp_path / "a" / "arm.urdf").resolve()
    assert list(inherits.forces[0].parameters["function"].y) == [1.0, 1.0]
    # the child's own `file` (the whole [[force]] array is replaced) is beside the child
    own = load_scene(write(tmp_path / "b" / "own.toml", 'extends = "../a/parent.toml"\n' + FORCE_FROM_FILE.format(file="table.csv")))
    assert list(own.forces[0].parameters["function"].y) == [2.0, 2.0]
    # a grandchild elsewhere still finds the grandparent's files
    grandchild = load_scene(write(tmp_path / "c" / "d" / "g.toml", 'extends = "../../b/child.toml"\n'))
    assert grandchild.mechanism_path == inherits.mechanism_path
    assert list(grandchild.forces[0].parameters["function"].y) == [1.0, 1.0]


def test_a_childs_mechanism_resolves_against_the_childs_folder(tmp_path):
    write(tmp_path / "a" / "parent.toml", 'extends = "free_two_link_spring"\nname = "p"\nmechanism = "sub/arm.urdf"\n')
    (tmp_path / "a" / "sub").mkdir()
    shutil.copy(shipped_urdf("two_link_arm.urdf"), tmp_path / "a" / "sub" / "arm.urdf")
    (tmp_path / "b" / "sub").mkdir(parents=True)
    shutil.copy(shipped_urdf("two_link_arm.urdf"), tmp_path / "b" / "sub" / "arm.urdf")
    inherited = load_scene(write(tmp_path / "b" / "inherits.toml", 'extends = "../a/parent.toml"\n'))
    assert inherited.mechanism_path == (tmp_path / "a" / "sub" / "arm.urdf").resolve()
    own = load_scene(write(tmp_path / "b" / "own.toml", 'extends = "../a/parent.toml"\nmechanism = "sub/arm.urdf"\n'))
    assert own.mechanism_path == (tmp_path / "b" / "sub" / "arm.urdf").resolve()


def test_a_shipped_parents_bare_mechanism_stays_the_shipped_one(tmp_path):
    """A file named like the parent's shipped mechanism beside the child does not replace it."""
    shutil.copy(shipped_urdf("ups_rps.urdf"), tmp_path / "two_link_arm.urdf")
    scene = load_scene(write(tmp_path / "S.toml", 'extends = "free_two_link_spring"\n'))
    assert scene.mechanism_path == shipped_urdf("two_link_arm.urdf")


# --- merging -----------------------------------------------------------------------------


def test_a_nested_table_merges_key_by_key(tmp_path, capsys):
    child = write(tmp_path / "S.toml", 'extends = "compound"\nname = "x"\n[materials.steel]\npoisson_ratio = 0.29\n')
    assert check(capsys, child)[0] == EXIT_OK
    parent_steel = load_scene("compound").document["materials"]["steel"]
    assert load_scene(child).document["materials"]["steel"] == {**parent_steel, "poisson_ratio": 0.29}


JOINTS_PARENT = """
name = "legs"
mechanism = "ups_rps.urdf"
duration = 1.0

[trajectory]
type = "joints"
P1 = { function = "harmonic", amplitude = 0.01, frequency = 2.0, offset = 1.2 }
P2 = { offset = 1.2, amplitudes = [0.01], harmonics = [1.0], phases = [0.0] }
"""


def test_an_inline_trajectory_table_merges_key_by_key(tmp_path):
    write(tmp_path / "parent.toml", JOINTS_PARENT)
    child = load_scene(write(tmp_path / "child.toml", 'extends = "parent.toml"\n[trajectory]\nP1 = { amplitude = 0.02 }\n'))
    assert child.trajectory.functions["P1"] == TF.Harmonic(amplitude=0.02, frequency=2.0, phase=0.0, offset=1.2)
    assert child.document["trajectory"]["P2"] == {"offset": 1.2, "amplitudes": [0.01], "harmonics": [1.0], "phases": [0.0]}


def test_a_table_switching_its_function_or_mode_replaces_the_parents(tmp_path):
    write(tmp_path / "parent.toml", JOINTS_PARENT)
    child = load_scene(write(tmp_path / "child.toml", 'extends = "parent.toml"\n[trajectory]\nP1 = { function = "constant", value = 1.2 }\n'))
    assert child.document["trajectory"]["P1"] == {"function": "constant", "value": 1.2}
    arm = load_scene(write(tmp_path / "arm.toml", 'extends = "free_two_link_spring"\n[actuators]\nshoulder = { mode = "none" }\n'))
    assert arm.actuators["shoulder"].mode == "none" and arm.document["actuators"]["shoulder"] == {"mode": "none"}


def test_an_array_of_tables_is_replaced_whole(tmp_path):
    write(tmp_path / "push.csv", "0,1\n2,1\n")
    scene = load_scene(write(tmp_path / "S.toml", 'extends = "free_two_link_spring"\n' + FORCE_FROM_FILE.format(file="push.csv")))
    assert [spec.name for spec in scene.forces] == ["push"]


# --- names -------------------------------------------------------------------------------


def test_a_child_without_name_is_named_after_its_file(tmp_path, capsys):
    child = write(tmp_path / "sc" / "noname.toml", 'extends = "compound"\n')
    scene = load_scene(child)
    assert scene.name == "noname" and scene.file_stem == "noname" and "name" not in scene.document
    grandchild = load_scene(write(tmp_path / "sc" / "deeper.toml", 'extends = "noname.toml"\n'))
    assert grandchild.name == "deeper"
    named = load_scene(write(tmp_path / "sc" / "named.toml", 'extends = "compound"\nname = "mine"\n'))
    assert named.name == "mine" and load_scene(write(tmp_path / "sc" / "below.toml", 'extends = "named.toml"\n')).name == "below"
    assert check(capsys, child)[0] == EXIT_OK


def test_a_folder_named_like_a_shipped_scene_does_not_hide_it(tmp_path, monkeypatch):
    """``--out ideal`` leaves a folder ``ideal`` in the working directory: ``ideal`` (and ``extends = "ideal"``) stay the shipped scene."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "ideal").mkdir()
    assert load_scene("ideal").name == "ideal"
    child = write(tmp_path / "child.toml", 'extends = "ideal"\nname = "child"\nduration = 0.1\n')
    assert load_scene(child).name == "child"
    (tmp_path / "mine").mkdir()
    with pytest.raises(SceneError, match="'mine' is a folder, not a scene file or a shipped scene"):
        load_scene("mine")
    (tmp_path / "folder.toml").mkdir()
    with pytest.raises(SceneError, match="is a folder, not a scene file"):
        load_scene("folder.toml")
