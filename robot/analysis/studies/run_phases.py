"""Where the time of a whole run goes: each phase of ``clearance run --scene NAME``, against the floor.

Two measurements, each repeated in fresh processes (medians over the repeats):

* **process**: the command itself (``python scripts/simulate.py --scene NAME
  --out TMP``) in a subprocess: wall time, CPU time (user + system) and peak
  resident memory of that child (``os.wait4``);
* **phases**: a worker process (:func:`worker`) that does what the command does,
  phase by phase, and times each with ``time.process_time`` (CPU, robust on a
  loaded machine): ``imports`` (the modules the command imports), ``build``
  (scene, mechanism, initial state), ``compile`` (the kernels' first call: the library's, or numba's cache load),
  ``integrate`` (the step loop), ``outputs`` (:func:`robot.io.results.make_result`),
  ``write`` (the result file). Then the same integration again with timers around
  the step loop's parts (exclusive CPU time of each: the right-hand side, the
  Jacobian, the contact probe, the onset root-finding's penetrations, the solver's
  step itself, onset location, restarts, peak location, failure checks,
  acceptance, solver (re)starts); the timers' own cost is calibrated and
  subtracted. Finally the **floor**: the right-hand side and the Jacobian replayed
  in a tight loop at the run's recorded step states, their per-call costs times the
  run's counts of calls. ``integration / floor`` is the ratio of the (untimed)
  integration's CPU time to that floor, both from the same process.

No profiler is used (``cProfile`` roughly doubles the cost of small calls).
"""

from __future__ import annotations

import gc
import inspect
import json
import os
import statistics
import subprocess
import sys
import tempfile
import time
import warnings
from pathlib import Path
from typing import Any, Callable

#: the step loop's parts timed by the instrumented integration: (module, class or None, attribute, phase)
STEP_LOOP_PARTS = (
    ("robot.integration.simulation", "LagrangeSystem", "derivative", "rhs"),
    ("robot.integration.simulation", "LagrangeSystem", "_jacobian", "jacobian"),
    ("robot.integration.simulation", "LagrangeSystem", "probe", "probe"),
    ("robot.integration.simulation", "LagrangeSystem", "penetrations", "onset penetrations"),
    ("robot.integration.simulation", "LagrangeSystem", "normalise", "normalise"),
    ("robot.integration.event_loop", "EventDrivenIntegrator", "advance", "solver step"),
    ("robot.integration.event_loop", "EventDrivenIntegrator", "find_onsets", "find onsets"),
    ("robot.integration.event_loop", "EventDrivenIntegrator", "restart_at_onset", "restart at onset"),
    ("robot.integration.event_loop", "EventDrivenIntegrator", "check_failures", "check failures"),
    ("robot.integration.event_loop", "EventDrivenIntegrator", "locate_peaks", "locate peaks"),
    ("robot.integration.event_loop", "EventDrivenIntegrator", "accept", "accept"),
    ("robot.integration.event_loop", "EventDrivenIntegrator", "start_solver", "start solver"),
    ("robot.integration.event_loop", "EventDrivenIntegrator", "end_solver", "start solver"),
    ("robot.integration.event_loop", "EventDrivenIntegrator", "dense_output", "dense output"),
    ("robot.integration.event_loop", "EventDrivenIntegrator", "step", "loop rest"),
)
#: the whole-run phases of the worker, in order
RUN_PHASES = ("imports", "build", "compile", "integrate", "outputs", "write")


class ExclusiveTimers:
    """CPU time spent in wrapped functions, each call's time minus that of the wrapped calls inside it."""

    def __init__(self, clock: Callable[[], float] = time.process_time):
        self.clock = clock
        self.spent: dict[str, float] = {}
        self.calls: dict[str, int] = {}
        self._stack: list[float] = []  # per active call: the time of wrapped calls inside it
        self._restore: list[tuple[Any, str, Any]] = []

    def wrap(self, owner: Any, attribute: str, phase: str) -> None:
        original = getattr(owner, attribute)
        clock, stack, spent, calls = self.clock, self._stack, self.spent, self.calls
        spent.setdefault(phase, 0.0)
        calls.setdefault(phase, 0)

        def timed(*args, **kwargs):
            stack.append(0.0)
            start = clock()
            try:
                return original(*args, **kwargs)
            finally:
                elapsed = clock() - start
                inner = stack.pop()
                spent[phase] += elapsed - inner
                calls[phase] += 1
                if stack:
                    stack[-1] += elapsed

        self._restore.append((owner, attribute, original))
        setattr(owner, attribute, timed)

    def restore(self) -> None:
        for owner, attribute, original in reversed(self._restore):
            setattr(owner, attribute, original)
        self._restore.clear()

    def overhead_per_call(self, calls: int = 20000) -> float:
        """CPU seconds one wrapped call adds (timer calls and bookkeeping), measured on an empty function."""

        class Empty:
            @staticmethod
            def nothing():
                return None

        bare = Empty.nothing
        start = self.clock()
        for _ in range(calls):
            bare()
        bare_time = self.clock() - start
        probe = ExclusiveTimers(self.clock)
        probe.wrap(Empty, "nothing", "empty")
        wrapped = Empty.nothing
        start = self.clock()
        for _ in range(calls):
            wrapped()
        wrapped_time = self.clock() - start
        probe.restore()
        return max(wrapped_time - bare_time, 0.0) / calls


def _import_owner(module: str, owner: str | None):
    import importlib

    target = importlib.import_module(module)
    return target if owner is None else getattr(target, owner)


def _floor(run, trajectory, sample_every: int = 4) -> dict:
    """Per-call CPU cost of the right-hand side and the Jacobian replayed at the run's step states, and the floor."""
    import numpy as np

    from robot.integration.records import RECORD_STEP
    from robot.integration.simulation import LagrangeSystem, penetration_bounds

    dynamics = run.dynamics
    system = LagrangeSystem(dynamics, penetration_bounds(dynamics, run.scene.limits), structured_jacobian=True)
    rows = np.flatnonzero(trajectory.kind == RECORD_STEP)[::sample_every]
    states = [(float(trajectory.t[i]), trajectory.y[i], trajectory.onset_rates[i]) for i in rows]
    derivative = system.derivative
    start = time.process_time()
    for t, y, onset in states:
        derivative(t, y, onset)
    rhs_cost = (time.process_time() - start) / len(states)
    jacobian_cost = float("nan")
    if system.jacobian is not None:
        out = np.empty((system.size, system.size))
        subset = states[:: max(1, len(states) // 500)]
        start = time.process_time()
        for t, y, onset in subset:
            system.jacobian(t, y, onset, out)
        jacobian_cost = (time.process_time() - start) / len(subset)
    n_jac = max(int(trajectory.n_jacobians), 0)
    floor = trajectory.n_rhs * rhs_cost + (n_jac * jacobian_cost if n_jac else 0.0)
    return {"rhs_us": rhs_cost * 1e6, "jacobian_us": jacobian_cost * 1e6, "n_rhs": trajectory.n_rhs, "n_jacobians": n_jac, "floor_s": floor, "states": len(states)}


#: what the command imports (timed by the worker's launcher before anything else is imported)
COMMAND_MODULES = ("robot.cli.main", "robot.cli.run", "robot.run", "robot.cli.outputs")
#: the worker's launcher: times the command's imports first (importing this module loads numpy, and numba without the kernel library)
_LAUNCHER = (
    "import gc; gc.disable()\n"  # as the command: the collector off during the imports and the build
    "import time, json; start = time.process_time()\n"
    "for name in {modules!r}: __import__(name)\n"
    "imports = time.process_time() - start\n"
    "import robot.analysis.studies.run_phases as m\n"
    "print(json.dumps(m.worker({scene!r}, {out!r}, imports)))"
)


def worker(scene: str, out_dir: str, imports: float) -> dict:
    """One fresh process's measurement (module docstring): run phases, step-loop parts, floor.

    ``imports``: CPU seconds of the command's imports, timed by the launcher (:func:`measure_phases`).
    """
    phases: dict[str, float] = {"imports": imports}
    clock = time.process_time
    from robot.io.results import save_result  # what the command's save_or_fallback calls
    from robot.run import build_run, compile_kernels
    import robot.run as run_module

    start = clock()
    run = build_run(scene)
    phases["build"] = clock() - start
    gc.freeze()  # as the command (robot.cli.common.collector_spared_setup): the setup out of the collector's walks
    gc.enable()
    phases["compile"] = compile_kernels(run)
    # run_scene's two parts, timed through the names robot.run calls
    timers = ExclusiveTimers()
    timers.wrap(run_module, "integrate", "integrate")
    timers.wrap(run_module, "make_result", "outputs")
    # as the command does: the outputs at the records the file keeps (a tree older than that option: at all)
    keeps = "output" in inspect.signature(run_module.run_scene).parameters
    result = run_module.run_scene(run, progress=lambda t: None, **({"output": run.scene.output} if keeps else {}))
    timers.restore()
    phases["integrate"], phases["outputs"] = timers.spent["integrate"], timers.spent["outputs"]
    start = clock()
    path = save_result(result, Path(out_dir) / f"{run.scene.file_stem}.npz", run.scene.output)
    phases["write"] = clock() - start
    file_bytes = path.stat().st_size

    # the step loop's parts: the same integration, instrumented
    from robot.integration.simulation import integrate

    parts = ExclusiveTimers()
    for module, owner, attribute, phase in STEP_LOOP_PARTS:
        parts.wrap(_import_owner(module, owner), attribute, phase)
    start = clock()
    trajectory = integrate(run.dynamics, run.y0, run.t_span, run.scene.solver, run.scene.limits)
    instrumented = clock() - start
    parts.restore()
    overhead = parts.overhead_per_call()
    step_loop = {phase: max(spent - overhead * parts.calls[phase], 0.0) for phase, spent in parts.spent.items()}
    step_loop["timers (subtracted)"] = overhead * sum(parts.calls.values())
    floor = _floor(run, trajectory)
    from clearance_contact import compiled

    return {
        "scene": scene,
        "kernels": compiled.KERNEL_MODE,
        "switched_by": compiled.SWITCHED_BY,
        "phases": phases,
        "run_cpu": sum(phases.values()),
        "step_loop": step_loop,
        "step_loop_calls": parts.calls,
        "instrumented_integrate": instrumented,
        "floor": floor,
        "integration_over_floor": phases["integrate"] / floor["floor_s"],
        "counts": {k: result.counts.get(k) for k in ("n_steps", "n_rhs", "n_jacobians", "n_events", "n_restarts")},
        "records": int(len(result.arrays["t"])),
        "file_bytes": file_bytes,
    }


KERNEL_MODES = ("library", "numba")
"""What ``kernels`` may ask for: the kernel library (the default of a run), or numba's just-in-time kernels."""


def _child_env(kernels: str = "library") -> dict:
    from clearance_contact.kernel_library import child_environment

    return child_environment(kernels)


def measure_process(scene: str, python: str = sys.executable, kernels: str = "library") -> dict:
    """Wall, CPU and peak memory of one ``python scripts/simulate.py --scene NAME`` (fresh process)."""
    root = Path(__file__).resolve().parents[3]
    with tempfile.TemporaryDirectory(prefix="bench-run-") as out:
        command = [python, str(root / "scripts" / "simulate.py"), "--scene", scene, "--out", out]
        start = time.perf_counter()
        process = subprocess.Popen(command, env=_child_env(kernels), stdout=subprocess.PIPE, stderr=subprocess.PIPE)
        _, status, usage = os.wait4(process.pid, 0)
        wall = time.perf_counter() - start
        stdout, stderr = process.stdout.read().decode(), process.stderr.read().decode()
        process.stdout.close()
        process.stderr.close()
        process.returncode = os.waitstatus_to_exitcode(status)
    if process.returncode != 0:
        raise RuntimeError(f"{' '.join(command)} exited with {process.returncode}:\n{stdout}\n{stderr}")
    return {"wall_s": wall, "cpu_s": usage.ru_utime + usage.ru_stime, "peak_mib": usage.ru_maxrss / 1024.0, "stdout": stdout.strip()}


def measure_phases(scene: str, python: str = sys.executable, kernels: str = "library") -> dict:
    """:func:`worker` in a fresh process."""
    with tempfile.TemporaryDirectory(prefix="bench-run-") as out:
        command = [python, "-c", _LAUNCHER.format(modules=COMMAND_MODULES, scene=scene, out=out)]
        done = subprocess.run(command, env=_child_env(kernels), capture_output=True, text=True)
    if done.returncode != 0:
        raise RuntimeError(f"phase worker failed ({done.returncode}):\n{done.stderr}")
    return json.loads(done.stdout.strip().splitlines()[-1])


def _median_tree(samples: list) -> Any:
    """Medians of the numbers of a list of equally-shaped dicts (other values from the first)."""
    first = samples[0]
    if isinstance(first, dict):
        return {key: _median_tree([s[key] for s in samples if key in s]) for key in first}
    if isinstance(first, (int, float)) and not isinstance(first, bool):
        return statistics.median(samples)
    return first


def compile_bytecode(python: str = sys.executable) -> None:
    """Write the project's bytecode (``__pycache__``), as installing a package does, before anything is timed.

    pip compiles a package's modules when it installs it, and Python caches them on
    first import; where ``PYTHONDONTWRITEBYTECODE`` is set (some shared and CI
    machines) and the project is an editable checkout, every run would instead
    compile the project's ~150 modules again (~0.1 s of the imports), which is not
    what a user's run costs.
    """
    root = Path(__file__).resolve().parents[3]
    folders = [str(root / name) for name in ("robot", "clearance_contact", "scripts") if (root / name).is_dir()]
    done = subprocess.run([python, "-m", "compileall", "-q", *folders], capture_output=True, text=True)
    if done.returncode != 0:  # e.g. a read-only checkout: the timings then include compiling the sources
        warnings.warn(f"bench-run: could not write the project's bytecode, imports are timed with compilation ({done.stderr.strip()[:200]})", stacklevel=2)


def benchmark(
    scene: str, repeats: int = 5, python: str = sys.executable, progress: Callable[[str], None] | None = None, kernels: str = "library"
) -> dict:
    """``repeats`` fresh-process runs of the command and of the phase worker, alternated; medians and samples.

    The project's bytecode is written first (:func:`compile_bytecode`). ``kernels``: one
    of :data:`KERNEL_MODES` (the processes' ``CLEARANCE_CONTACT_JIT``); the report's
    ``phases.kernels`` says what the worker ran.
    """
    compile_bytecode(python)
    process, phases = [], []
    for i in range(repeats):
        process.append(measure_process(scene, python, kernels))
        phases.append(measure_phases(scene, python, kernels))
        if progress is not None:
            progress(f"repeat {i + 1}/{repeats}: process wall {process[-1]['wall_s']:.2f} s, cpu {process[-1]['cpu_s']:.2f} s, "
                     f"integration/floor {phases[-1]['integration_over_floor']:.2f}")
    load = os.getloadavg()
    return {
        "scene": scene,
        "repeats": repeats,
        "load_average": load,
        "cpus": os.cpu_count(),
        "process": _median_tree([{k: v for k, v in p.items() if k != "stdout"} for p in process]),
        "phases": _median_tree(phases),
        "samples": {"process": process, "phases": phases},
    }


def table(report: dict) -> str:
    """The medians as a Markdown table (CPU seconds per phase, shares, the floor)."""
    phases, process = report["phases"], report["process"]
    run_cpu = sum(phases["phases"].values())
    lines = [
        f"scene {report['scene']}, kernels {phases.get('kernels', 'numba')}, medians of {report['repeats']} fresh processes "
        f"(load average {report['load_average'][0]:.1f} on {report['cpus']} CPUs)",
        "",
        f"whole process: wall {process['wall_s']:.2f} s, CPU {process['cpu_s']:.2f} s, peak memory {process['peak_mib']:.0f} MiB",
        "",
        "| phase | CPU s | share |",
        "|---|---:|---:|",
    ]
    for name in RUN_PHASES:
        value = phases["phases"][name]
        lines.append(f"| {name} | {value:.3f} | {100 * value / run_cpu:.0f} % |")
    lines.append(f"| **sum** | {run_cpu:.3f} | |")
    lines += ["", "step loop (instrumented integration, exclusive CPU s):", "", "| part | CPU s | calls |", "|---|---:|---:|"]
    for name, value in sorted(phases["step_loop"].items(), key=lambda item: -item[1]):
        lines.append(f"| {name} | {value:.3f} | {phases['step_loop_calls'].get(name, '')} |")
    floor = phases["floor"]
    lines += [
        "",
        f"floor: {floor['n_rhs']:.0f} right-hand sides x {floor['rhs_us']:.1f} us + {floor['n_jacobians']:.0f} Jacobians x "
        f"{floor['jacobian_us']:.0f} us = {floor['floor_s']:.3f} s; integration {phases['phases']['integrate']:.3f} s = "
        f"{phases['integration_over_floor']:.2f} x floor",
        f"records in memory {phases['records']:.0f}, file {phases['file_bytes'] / 1e6:.2f} MB",
    ]
    if "rounding_band" in report:
        measured = report["rounding_band"]
        band, moved = measured["band"], f"{measured['moved']} of {len(measured['variants'])} variants moved the run"
        lines += ["", f"rounding band (largest relative change under rounding-level perturbations of the initial state and the tolerances; {moved}):", ""]
        lines += ["| quantity | band |", "|---|---:|"] + [f"| {name} | {value:.1e} |" for name, value in band.items()]
    return "\n".join(lines)


def comparison_table(before: dict, after: dict) -> str:
    """Two reports of :func:`benchmark` (medians) side by side: CPU seconds per phase and part, and their ratio."""
    rows = ["| | before | after | after / before |", "|---|---:|---:|---:|"]

    def row(name: str, a: float, b: float, digits: int = 3) -> None:
        rows.append(f"| {name} | {a:.{digits}f} | {b:.{digits}f} | {b / a if a else float('nan'):.2f} |")

    row("whole process, CPU s", before["process"]["cpu_s"], after["process"]["cpu_s"], 2)
    row("whole process, wall s (loaded machine)", before["process"]["wall_s"], after["process"]["wall_s"], 2)
    row("peak memory, MiB", before["process"]["peak_mib"], after["process"]["peak_mib"], 0)
    for name in RUN_PHASES:
        row(f"{name}, CPU s", before["phases"]["phases"][name], after["phases"]["phases"][name])
    parts = sorted(set(before["phases"]["step_loop"]) | set(after["phases"]["step_loop"]), key=lambda p: -before["phases"]["step_loop"].get(p, 0.0))
    for name in parts:
        row(f"step loop: {name}", before["phases"]["step_loop"].get(name, 0.0), after["phases"]["step_loop"].get(name, 0.0))
    row("floor (rhs + Jacobian), CPU s", before["phases"]["floor"]["floor_s"], after["phases"]["floor"]["floor_s"])
    row("integration / floor", before["phases"]["integration_over_floor"], after["phases"]["integration_over_floor"], 2)
    return "\n".join(rows)
