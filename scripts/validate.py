"""Cross-check the Lagrange model against Newton-Euler and Exudyn (docs/validation.md).

    python scripts/validate.py [--out DIR] [--scenes ideal compound ...] [--duration compound=1.0 ...]
                               [--engines newton_euler exudyn] [--exudyn-step H] [--no-figures]
                               [--method RK45] [--rtol 1e-7] [--atol 1e-9] [--max-step 1e-3] [--first-step H]

Writes DIR/validation.json (maximum deviations per quantity and scene, statistics,
wall time of each engine, the solver settings used) and DIR/validation_<scene>.png,
DIR/deviation_<scene>.png.

The Lagrange and Newton-Euler runs use the validation's own pinned integrator,
``robot.validation.settings.VALIDATION_SOLVER`` (RK45, rtol 1e-7, atol 1e-9,
max_step 1e-3 s), for both engines and every scene, never the scenes' ``[solver]``
tables; ``--method/--rtol/--atol/--max-step/--first-step`` override it (with the
Newton-Euler engine: RK45, RK23 or DOP853 only). See docs/validation.md.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from robot.validation.study import main  # noqa: E402

if __name__ == "__main__":
    raise SystemExit(main())
