"""The subcommands of ``clearance``: name -> module. Adding one is a new module here and one line below.

A subcommand module defines ``HELP`` (one line), ``__doc__`` (the description
with examples, shown by ``clearance NAME --help``), ``add_arguments(parser)``
and ``execute(args) -> int`` (an exit code of :mod:`robot.cli.common`). Modules
are imported only when their command runs (``clearance --help`` stays fast).
"""

from __future__ import annotations

COMMANDS: dict[str, str] = {
    "run": "robot.cli.run",
    "paper": "robot.cli.paper",
    "animate": "robot.cli.animate",
    "validate": "robot.cli.validate",
    "describe": "robot.cli.describe",
    "bench": "robot.cli.bench",
    "bench-run": "robot.cli.bench_run",
    "contact-laws": "robot.cli.contact_laws",
    "work-precision": "robot.cli.work_precision",
    "build-urdf": "robot.cli.build_urdf",
    "sweep": "robot.cli.sweep",
    "bench-sweep": "robot.cli.bench_sweep",
    "build-kernels": "robot.cli.build_kernels",
}

#: commands that call compiled kernels: the kernel library is made ready (built if stale) before
#: their module is imported, so that the command's process loads it instead of numba
#: (robot.dynamics.kernel_build.ensure_library)
KERNEL_COMMANDS: frozenset[str] = frozenset(
    {"run", "paper", "animate", "validate", "bench", "bench-run", "contact-laws", "work-precision", "sweep", "bench-sweep"}
)

#: one-line help of each command, for ``clearance --help`` without importing the modules
SUMMARIES: dict[str, str] = {
    "run": "simulate one scene and write OUT/NAME.npz",
    "paper": "reproduce the seed paper's study (figures 7-10, summary.json, claims.md, animation)",
    "animate": "play a result in meshcat (HTML file or live server)",
    "validate": "cross-check the model against Newton-Euler and Exudyn",
    "describe": "print a mechanism's bodies, joints, closures, mobility and mass",
    "bench": "microseconds per clearance-joint contact evaluation",
    "bench-run": "CPU time of each phase of a whole run, against the floor (JSON and a table)",
    "contact-laws": "tables of the contact laws: rebound of each dissipation model, penetration of each radial law",
    "work-precision": "speed against accuracy of every integrator, stability maps",
    "build-urdf": "regenerate urdf/ups_rps.urdf from the design parameters",
    "sweep": "run a parameter sweep on dask, stored as an xarray dataset in zarr",
    "bench-sweep": "benchmark of the sweep engine: runs per minute, parallel efficiency, overhead",
    "build-kernels": "compile the kernel library ahead of time (runs then load it without numba)",
}
