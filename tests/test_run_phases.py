"""The whole-run benchmark's bookkeeping (robot.analysis.studies.run_phases): exclusive times, tables."""

from __future__ import annotations

import json

from robot.analysis.studies import run_phases as RP


class _Clock:
    """A clock that advances only when the work below says so (deterministic times)."""

    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def test_exclusive_timers_subtract_the_wrapped_calls_inside():
    clock = _Clock()

    class Work:
        @staticmethod
        def inner():
            clock.now += 2.0

        @staticmethod
        def outer():
            clock.now += 1.0
            Work.inner()
            Work.inner()
            clock.now += 0.5

    timers = RP.ExclusiveTimers(clock)
    timers.wrap(Work, "inner", "inner")
    timers.wrap(Work, "outer", "outer")
    Work.outer()
    Work.inner()
    assert timers.spent == {"inner": 6.0, "outer": 1.5}
    assert timers.calls == {"inner": 3, "outer": 1}
    timers.restore()
    assert "timed" not in Work.inner.__qualname__ and "timed" not in Work.outer.__qualname__


def test_tables_name_every_phase_and_the_floor_ratio():
    phases = {name: 0.1 * (i + 1) for i, name in enumerate(RP.RUN_PHASES)}
    report = {
        "scene": "s", "repeats": 5, "load_average": (1.0, 1.0, 1.0), "cpus": 2,
        "process": {"wall_s": 3.0, "cpu_s": 2.5, "peak_mib": 250.0},
        "phases": {
            "phases": phases, "step_loop": {"rhs": 0.5, "probe": 0.2}, "step_loop_calls": {"rhs": 100, "probe": 50},
            "floor": {"n_rhs": 100, "rhs_us": 5000.0, "n_jacobians": 0, "jacobian_us": float("nan"), "floor_s": 0.5},
            "integration_over_floor": phases["integrate"] / 0.5, "records": 10, "file_bytes": 1e6,
        },
    }
    text = RP.table(report)
    assert all(f"| {name} |" in text for name in RP.RUN_PHASES)
    assert f"{phases['integrate'] / 0.5:.2f} x floor" in text
    after = json.loads(json.dumps(report))
    after["phases"]["phases"]["outputs"] = phases["outputs"] / 4
    compared = RP.comparison_table(report, after)
    assert f"| outputs, CPU s | {phases['outputs']:.3f} | {phases['outputs'] / 4:.3f} | 0.25 |" in compared
    assert "integration / floor" in compared


def test_table_lists_the_rounding_band_when_measured():
    phases = {name: 0.1 for name in RP.RUN_PHASES}
    report = {
        "scene": "s", "repeats": 1, "load_average": (1.0, 1.0, 1.0), "cpus": 2,
        "process": {"wall_s": 3.0, "cpu_s": 2.5, "peak_mib": 250.0},
        "phases": {
            "phases": phases, "step_loop": {}, "step_loop_calls": {},
            "floor": {"n_rhs": 1, "rhs_us": 1.0, "n_jacobians": 0, "jacobian_us": float("nan"), "floor_s": 0.1},
            "integration_over_floor": 1.0, "records": 1, "file_bytes": 1.0,
        },
    }
    assert "rounding band" not in RP.table(report)
    variants = {f"v{i}": {"peak S1": 0.0, "steps": 0.0} for i in range(6)}
    report["rounding_band"] = {"band": {"peak S1": 1.2e-5, "steps": 3.5e-3}, "variants": variants, "moved": 5}  # rounding_band()'s shape
    text = RP.table(report)
    assert "| peak S1 | 1.2e-05 |" in text and "| steps | 3.5e-03 |" in text and "5 of 6 variants moved the run" in text


def test_bytecode_is_written_before_timing(tmp_path):
    """The benchmark times what an installed package costs: the project's modules compiled and cached."""
    import importlib.util
    from pathlib import Path

    import robot.run

    cached = Path(importlib.util.cache_from_source(robot.run.__file__))
    cached.unlink(missing_ok=True)
    RP.compile_bytecode()
    assert cached.is_file() and cached.stat().st_mtime >= Path(robot.run.__file__).stat().st_mtime
