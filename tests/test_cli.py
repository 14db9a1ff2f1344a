"""The ``clearance`` program (robot.cli): help, exit codes, bad input, safe paths, writes, interrupts.

Commands run in-process through ``robot.cli.main.main`` (fast); runs use the
ideal scene over a few milliseconds.
"""

from __future__ import annotations

import importlib
import json
import os
import re
import signal
import stat
import subprocess
import sys
from contextlib import contextmanager
from pathlib import Path

import numpy as np
import pytest

from robot.cli import interrupts
from robot.cli.common import EXIT_BAD_INPUT, EXIT_OK, EXIT_RUN_FAILED, count_text
from robot.cli.main import main
from robot.cli.registry import COMMANDS, SUMMARIES
from robot.io.atomic import atomic_write
from robot.io.results import load_result

ROOT = Path(__file__).resolve().parents[1]


def scene_file(tmp_path: Path, text: str, name: str = "scene.toml") -> str:
    path = tmp_path / name
    path.write_text(text)
    return str(path)


def run_cli(capsys, *argv: str) -> tuple[int, str, str]:
    code = main([str(a) for a in argv])
    captured = capsys.readouterr()
    return code, captured.out, captured.err


# --- the program and its registry ---------------------------------------------------------


def test_registry_modules_define_the_subcommand_interface():
    assert set(COMMANDS) == set(SUMMARIES)
    for name, module_name in COMMANDS.items():
        module = importlib.import_module(module_name)
        assert callable(module.add_arguments) and callable(module.execute), name
        assert "examples:" in module.__doc__, f"{name}: the help shows no examples"


@pytest.mark.parametrize("command", sorted(COMMANDS))
def test_every_command_has_help_with_examples_and_exit_codes(capsys, command):
    code, out, err = run_cli(capsys, command, "--help")
    assert code == EXIT_OK, err
    assert "examples:" in out and "exit status:" in out and "2    bad input" in out


def test_run_help_names_every_shipped_scene(capsys):
    from robot.scene.loader import shipped_scenes

    code, out, _ = run_cli(capsys, "run", "--help")
    assert code == EXIT_OK
    listed = " ".join(out.split())  # argparse rewraps the text
    assert [name for name in shipped_scenes() if not re.search(rf"(?<!\w){name}(?!\w)", listed)] == []


def test_top_level_help_lists_every_command(capsys):
    code, out, _ = run_cli(capsys, "--help")
    assert code == EXIT_OK
    assert all(name in out for name in COMMANDS)


def test_scripts_are_shims_of_the_program():
    for script in (ROOT / "scripts").glob("*.py"):
        text = script.read_text()
        assert "from robot.cli.main import main" in text and len(text.splitlines()) < 15, script.name


# --- bad input: exit 2, one message naming the culprit, no traceback ------------------------

BAD_ARGUMENTS = [
    (("run", "--scene", "ideal", "--t-end", "inf"), "--t-end"),
    (("run", "--scene", "ideal", "--t-end", "-1"), "--t-end"),
    (("run", "--scene", "ideal", "--t-end", "abc"), "--t-end"),
    (("run", "--scene", "no_such_scene"), "no_such_scene"),
    (("paper", "--workers", "0"), "--workers"),
    (("validate", "--scenes", "nosuch"), "nosuch"),
    (("validate", "--scenes", "ideal", "--duration", "ideal=abc"), "--duration"),
    (("work-precision", "--tolerances", "abc"), "--tolerances"),
    (("work-precision", "--methods", "RK99"), "RK99"),
    (("work-precision", "--candidates", "LSODA:x"), "--candidates"),
    (("animate", "no_such_result.npz", "--html", "a.html"), "no_such_result.npz"),
    (("describe", "--clearance", "Q9"), "Q9"),
    (("bench", "--repeats", "3"), "--repeats"),
    (("no-such-command",), "no-such-command"),
]


@pytest.mark.parametrize("argv, culprit", BAD_ARGUMENTS, ids=lambda v: " ".join(v) if isinstance(v, tuple) else None)
def test_bad_arguments_exit_2_with_a_message(capsys, tmp_path, monkeypatch, argv, culprit):
    monkeypatch.chdir(tmp_path)
    code, _, err = run_cli(capsys, *argv)
    assert code == EXIT_BAD_INPUT
    assert culprit in err and "Traceback" not in err


BAD_SCENES = {
    "negative Coulomb coefficient": (
        'extends = "spherical"\n[[clearance]]\njoint = "S1"\ntype = "spherical"\nball_radius = 0.015\nclearance = 1e-4\n'
        'friction = { law = "coulomb", coefficient = -0.1 }\n',
        ["coefficient", "-0.1"],
    ),
    "Brown-McPhee static below dynamic": (
        'extends = "spherical"\n[[clearance]]\njoint = "S1"\ntype = "spherical"\nball_radius = 0.015\nclearance = 1e-4\n'
        'friction = { law = "brown_mcphee", static = 0.03, dynamic = 0.05, transition_velocity = 5e-3 }\n',
        ["static", "0.03", "0.05"],
    ),
    "revolute type on S1": (
        'extends = "spherical"\n[[clearance]]\njoint = "S1"\ntype = "revolute"\njournal_radius = 0.02\nradial_clearance = 1e-4\n'
        "bearing_outer_radius = 0.035\nbearing_length = 0.04\naxial_clearance = 1e-4\n",
        ["type", "'revolute'", "S1", "spherical"],
    ),
    "spherical type on R1": (
        'extends = "revolute"\n[[clearance]]\njoint = "R1"\ntype = "spherical"\nball_radius = 0.015\nclearance = 1e-4\n',
        ["type", "'spherical'", "R1", "revolute"],
    ),
    "misalignment beyond the clearances": (
        'extends = "compound_misaligned"\n[initial]\nmisalignment_deg = { R1 = 0.5 }\n',
        ["misalignment_deg", "R1", "0.5", "at most 0.06"],
    ),
    "unknown array to keep": ('extends = "ideal"\n[output]\nkeep = ["q", "S1_normal_force"]\n', ["keep", "S1_normal_force"]),
    "bad precision": ('extends = "ideal"\n[output]\nprecision = "float16"\n', ["precision", "float16"]),
    "missing mechanism file": ('extends = "ideal"\nmechanism = "nowhere/else.urdf"\n', ["mechanism", "nowhere/else.urdf"]),
    "name not a string": ('extends = "ideal"\nname = 3\n', ["name", "3"]),
}


@pytest.mark.parametrize("case", sorted(BAD_SCENES))
def test_bad_scenes_exit_2_naming_key_and_value(capsys, tmp_path, case):
    text, words = BAD_SCENES[case]
    code, _, err = run_cli(capsys, "run", "--scene", scene_file(tmp_path, text), "--out", tmp_path / "out")
    assert code == EXIT_BAD_INPUT, err
    assert "Traceback" not in err
    for word in words:
        assert word in err, f"{word!r} not in {err!r}"
    assert not (tmp_path / "out").exists() or not any((tmp_path / "out").iterdir())


def test_out_that_is_a_file_is_refused_before_the_run(capsys, tmp_path):
    blocker = tmp_path / "file"
    blocker.write_text("x")
    for argv in (("run", "--scene", "ideal", "--out", blocker), ("paper", "--out", blocker), ("validate", "--out", blocker)):
        code, _, err = run_cli(capsys, *argv)
        assert code == EXIT_BAD_INPUT and "--out" in err and "is a file" in err


def test_html_or_urdf_target_that_is_a_folder_is_refused(capsys, tmp_path):
    code, _, err = run_cli(capsys, "build-urdf", "--out", tmp_path)
    assert code == EXIT_BAD_INPUT and "is a folder" in err
    code, _, err = run_cli(capsys, "animate", tmp_path / "x.npz", "--html", tmp_path)
    assert code == EXIT_BAD_INPUT and "--html" in err


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_read_only_out_is_refused_before_the_run(capsys, tmp_path):
    out = tmp_path / "ro"
    out.mkdir()
    out.chmod(0o500)
    try:
        code, _, err = run_cli(capsys, "run", "--scene", "ideal", "--out", out)
    finally:
        out.chmod(0o700)
    assert code == EXIT_BAD_INPUT and "cannot be written" in err


# --- runs: safe names, permissions, counters, write failures --------------------------------


@pytest.mark.parametrize("name, stem", [("../escaped", "escaped"), ("/tmp/absolute", "tmp_absolute"), ("", "scene"), (".hidden", "hidden")])
def test_output_file_name_is_the_sanitised_scene_name_inside_out(capsys, tmp_path, name, stem):
    scene = scene_file(tmp_path, f'extends = "ideal"\nname = "{name}"\n')
    out = tmp_path / "deep" / "out"
    code, stdout, err = run_cli(capsys, "run", "--scene", scene, "--t-end", "0.002", "--out", out)
    assert code == EXIT_OK, err
    assert [p.name for p in out.iterdir()] == [f"{stem}.npz"]
    assert sorted(p.name for p in tmp_path.rglob("*.npz")) == [f"{stem}.npz"]
    assert load_result(out / f"{stem}.npz").scene == name


@contextmanager
def umask(mask: int):
    previous = os.umask(mask)
    try:
        yield
    finally:
        os.umask(previous)


@pytest.mark.parametrize("mask", [0o022, 0o077, 0o002])
def test_written_files_follow_the_umask(tmp_path, mask):
    with umask(mask):
        path = atomic_write(tmp_path / "a.bin", lambda tmp: tmp.write_bytes(b"1"))
    assert stat.S_IMODE(path.stat().st_mode) == 0o666 & ~mask


def test_run_result_is_readable_by_others_with_the_usual_umask(capsys, tmp_path):
    with umask(0o022):
        code, stdout, err = run_cli(capsys, "run", "--scene", "ideal", "--t-end", "0.002", "--out", tmp_path)
    assert code == EXIT_OK, err
    assert stat.S_IMODE((tmp_path / "ideal.npz").stat().st_mode) == 0o644
    assert "compiling the kernels" in stdout  # compilation reported apart from the run's CPU time
    assert "rejected" in stdout and "rejected -1" not in stdout  # (the tmp path may hold "-1")


def test_counters_print_n_a_when_unknown():
    assert count_text(-1) == "n/a" and count_text(None) == "n/a" and count_text(0) == "0" and count_text(2.5, ".1f") == "2.5"


def test_the_setup_is_spared_by_the_collector_and_the_caller_gets_its_collector_back():
    import gc

    from robot.cli.common import collector_spared_setup

    assert gc.isenabled() and gc.get_freeze_count() == 0
    with collector_spared_setup() as set_up:
        assert not gc.isenabled()
        kept = [[] for _ in range(1000)]  # objects of the setup
        set_up()
        assert gc.isenabled() and gc.get_freeze_count() >= len(kept)
    assert gc.isenabled() and gc.get_freeze_count() == 0
    gc.disable()
    try:
        with pytest.raises(KeyError), collector_spared_setup():
            raise KeyError("a failed setup")
        assert not gc.isenabled() and gc.get_freeze_count() == 0  # the caller's state, whatever happened
    finally:
        gc.enable()
    gc.freeze()  # a caller that froze its own objects keeps them frozen
    try:
        frozen = gc.get_freeze_count()
        with collector_spared_setup() as set_up:
            set_up()
        assert gc.get_freeze_count() >= frozen > 0
    finally:
        gc.unfreeze()


def test_the_process_exit_keeps_the_exit_status_the_buffered_output_and_atexit():
    import subprocess
    import sys

    code = (
        "import atexit, sys; from robot.cli.main import exit_process; atexit.register(lambda: sys.stderr.write(' atexit'));"
        "print('buffered', end=''); sys.stderr.write('err'); exit_process(3)"
    )
    environment = {key: value for key, value in os.environ.items() if key != "PYTHONUNBUFFERED"}  # stdout block-buffered
    done = subprocess.run([sys.executable, "-c", code], cwd=ROOT, env=environment, capture_output=True, text=True, timeout=60)
    assert (done.returncode, done.stdout, done.stderr) == (3, "buffered", "err atexit")


def test_a_failed_write_saves_the_result_to_a_temporary_folder_named_in_the_message(capsys, tmp_path):
    from robot.cli.outputs import save_or_fallback
    from robot.run import build_run, run_scene

    run = build_run("ideal", duration=0.002)
    result = run_scene(run)
    blocker = tmp_path / "file"
    blocker.write_text("x")
    path, where_asked = save_or_fallback(result, blocker / "ideal.npz", run.scene.output)  # parent is a file
    err = capsys.readouterr().err
    assert not where_asked and str(path) in err and "could not write" in err
    from robot.io.results import select_records

    assert np.array_equal(load_result(path)["driving_force"], select_records(result, run.scene.output)["driving_force"])


# --- interrupts -----------------------------------------------------------------------------


def _send_at(t_stop: float, signum: int):
    """A progress callback that signals this process once the integration passes ``t_stop``."""
    sent = []

    @contextmanager
    def bar(total, description, enabled=None):
        def update(t):
            if t >= t_stop and not sent:
                sent.append(t)
                os.kill(os.getpid(), signum)

        yield update

    return bar


@pytest.mark.parametrize("signum", [signal.SIGTERM, signal.SIGINT])
def test_a_signal_during_the_run_saves_the_partial_result(capsys, tmp_path, monkeypatch, signum):
    import robot.cli.run as run_command

    monkeypatch.setattr(run_command, "progress_bar", _send_at(0.01, signum))
    code, stdout, err = run_cli(capsys, "run", "--scene", "ideal", "--t-end", "0.5", "--out", tmp_path)
    assert code == EXIT_RUN_FAILED
    assert "stopping the integration" in err and "saving the result to" in err
    result = load_result(tmp_path / "ideal.npz")
    assert result.cause == "interrupted" and 0.01 <= result.t_end < 0.5
    assert [p.name for p in tmp_path.iterdir()] == ["ideal.npz"]  # no temporary file left
    assert signal.getsignal(signal.SIGTERM) is signal.SIG_DFL  # handlers restored


def test_signals_during_a_write_neither_stop_nor_corrupt_it(capsys, tmp_path):
    payload = np.arange(200_000, dtype=float)

    def write(tmp: Path) -> None:
        with open(tmp, "wb") as handle:
            np.save(handle, payload[:1000])
            os.kill(os.getpid(), signal.SIGTERM)
            os.kill(os.getpid(), signal.SIGINT)  # a second, impatient one
            np.save(handle, payload)

    with interrupts.clean_stops("saving the test file") as stops:
        stops.phase = interrupts.Phase.SAVING
        path = atomic_write(tmp_path / "data.npy", write)
    err = capsys.readouterr().err
    assert stops.received == ["SIGTERM", "SIGINT"]
    assert "finishing: saving the test file" in err and "again: still saving" in err
    with open(path, "rb") as handle:
        np.load(handle)
        assert np.array_equal(np.load(handle), payload)
    assert [p.name for p in tmp_path.iterdir()] == ["data.npy"]


def test_a_signal_before_any_run_stops_at_once(tmp_path):
    with interrupts.clean_stops() as stops:
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGTERM)
    assert stops.requested


def test_an_interrupted_write_leaves_no_temporary_file(tmp_path):
    def write(tmp: Path) -> None:
        tmp.write_bytes(b"x" * 1000)
        raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        atomic_write(tmp_path / "a.bin", write)
    assert list(tmp_path.iterdir()) == []


def test_bench_times_every_radial_law_and_dissipation_model(capsys, tmp_path):
    """`clearance bench` (= scripts/bench_contact.py): a JSON row per radial law and per dissipation model,
    each a positive time in microseconds (a smoke test of the benchmark, not a timed test)."""
    from clearance_contact.dissipation import DISSIPATION_MODELS
    from clearance_contact.radial_laws import RADIAL_LAWS

    out = tmp_path / "bench.json"
    code, printed, _ = run_cli(capsys, "bench", "--repeats", "7", "--number", "5", "--out", str(out))
    assert code == 0
    report = json.loads(out.read_text())
    assert report["unit"] == "microseconds per call"
    for name in [*RADIAL_LAWS, *DISSIPATION_MODELS]:
        case = report["cases"][f"revolute_skew_in_contact_{name}"]
        assert case["median_us"] > 0 and case["kernel"]["median_us"] > 0
        assert f"revolute_skew_in_contact_{name}" in printed


def test_check_shows_the_scene_description(capsys, tmp_path):
    """docs/scenes.md: a scene's ``description`` is shown by ``clearance run --scene NAME --check``."""
    path = scene_file(tmp_path, 'extends = "ideal"\nname = "described"\ndescription = "a note for the user"\n')
    assert main(["run", "--scene", path, "--check"]) == EXIT_OK
    assert "  a note for the user" in capsys.readouterr().out.splitlines()


def test_warnings_are_one_line_without_the_source_echo(tmp_path):
    """A warning of a command is 'warning: CLASS: message' (Python would add the file, line and source line)."""
    done = subprocess.run(
        [sys.executable, "-m", "robot.cli", "run", "--scene", "four_bar", "--t-end", "0.002", "--out", str(tmp_path)],
        cwd=ROOT, capture_output=True, text=True, timeout=600,
    )  # fmt: skip
    assert done.returncode == 0, done.stderr[-2000:]
    lines = [line for line in done.stderr.splitlines() if "RedundantConstraintWarning" in line]
    assert lines and all(line.startswith("warning: RedundantConstraintWarning: mechanism 'four_bar'") for line in lines)
    assert "solve_kkt(" not in done.stderr and ".py:" not in done.stderr
