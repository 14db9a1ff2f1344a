"""Cross-check the Lagrange model against Newton-Euler and Exudyn (docs/validation.md).

    python scripts/validate.py [--out DIR] [--scenes ideal compound ...] [--duration compound=1.0 ...]
                               [--engines newton_euler exudyn] [--no-figures]

Writes DIR/validation.json (maximum deviations per quantity and scene, statistics,
wall time of each engine) and DIR/validation_<scene>.png, DIR/deviation_<scene>.png.
"""

from __future__ import annotations

import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parents[1]))

from robot.validation.study import main  # noqa: E402

if __name__ == "__main__":
    raise SystemExit(main())
