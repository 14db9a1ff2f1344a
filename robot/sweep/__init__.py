"""Parameter sweeps: many runs of one scene over scene keys, on dask.distributed, into one zarr store.

From Python::

    from robot.sweep import load_sweep, run_sweep, open_sweep

    spec = load_sweep("robot/sweep/examples/ups_rps_r1_clearance.toml")   # validated, no run yet
    outcome = run_sweep(spec, "out/sweeps/r1", workers=2)                   # or scheduler="tcp://..."
    dataset = open_sweep(outcome.store)                                     # xarray.Dataset
    dataset.R1_force_peak.plot()

From the shell: ``python scripts/sweep.py SWEEP.toml [--scheduler ADDRESS]
[--workers N] [--out DIR]`` (``clearance sweep`` once the command registers
:func:`robot.sweep.cli.main`). Modules: :mod:`.spec` (the sweep file),
:mod:`.design` (grids, Latin hypercube, Sobol), :mod:`.signals` (signal names),
:mod:`.task` (one run on a worker), :mod:`.store` (the zarr layout),
:mod:`.engine` (dask), :mod:`.figures` and :mod:`.report` (PNG, HTML),
:mod:`.cli`. Documentation: ``docs/sweep.md``.
"""

from clearance_contact.lazy import lazy_exports

_PUBLIC = {
    "load_sweep": "robot.sweep.spec",
    "SweepSpec": "robot.sweep.spec",
    "run_sweep": "robot.sweep.engine",
    "SweepOutcome": "robot.sweep.engine",
    "open_sweep": "robot.sweep.store",
    "SweepError": "robot.sweep.errors",
    "main": "robot.sweep.cli",
}

__all__ = sorted(_PUBLIC)


__getattr__, __dir__ = lazy_exports(__name__, globals(), _PUBLIC)
