"""robot: closed-loop mechanisms on Pinocchio with clearance joints (see README.md).

The public API (``docs/api.md``)::

    from robot import load_scene, simulate, load_result, Result, animate, Error

    scene = load_scene("compound_misaligned")                    # by name or path
    scene = scene.with_changes({"clearance.R1.radial_clearance": 2e-4})
    result = simulate(scene, t_end=0.05)                        # -> Result
    result.joint("R1").normal_force, result.success, result.nfev
    result.save("out/run.npz"); again = load_result("out/run.npz")
    animate(again, "out/run.html")

Names are imported lazily: ``import robot`` is cheap, Pinocchio and the
compiled kernels load on first use of :func:`simulate` or :func:`load_result`.

Pipeline (one way): :mod:`robot.scene` -> :mod:`robot.model` ->
:mod:`robot.dynamics` -> :mod:`robot.integration` -> :mod:`robot.io` ->
:mod:`robot.analysis`, :mod:`robot.viz` (``docs/architecture.md``).
"""

import os
from clearance_contact.lazy import lazy_exports

# The matrices here are small (tens of rows): multi-threaded BLAS only adds
# overhead on a loaded 2-core machine (a 90 x 180 product went from 30 to 200 us).
# Effective when robot is imported before numpy, as the scripts do.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

_PUBLIC = {
    "load_scene": "robot.scene.loader",
    "Scene": "robot.scene.loader",
    "simulate": "robot.run",
    "load_result": "robot.io.results",
    "save_result": "robot.io.results",
    "Result": "robot.io.results",
    "animate": "robot.viz.animation",
    "Error": "robot.errors",
    "SceneError": "robot.errors",
}

__all__ = sorted(_PUBLIC)


__getattr__, __dir__ = lazy_exports(__name__, globals(), _PUBLIC)

from robot import compat as _compat  # noqa: E402 (the old flat module paths, as aliases)

_compat.install()
