"""Saving results so that a finished run is never lost to a failed write."""

from __future__ import annotations

import sys
import tempfile
from pathlib import Path

from robot.io.results import SimulationResult, save_result
from robot.scene.loader import OutputSpec


def save_or_fallback(result: SimulationResult, path: Path, output: OutputSpec | None) -> tuple[Path, bool]:
    """Save ``result`` to ``path``; if that write fails, to a new temporary folder (named in a message).

    Returns the path written and whether it is the one asked for. The output
    folder was checked writable before the run; this covers what can still go
    wrong (disk full, folder removed or made read-only during the run).
    """
    try:
        return save_result(result, path, output), True
    except OSError as exc:
        fallback = Path(tempfile.mkdtemp(prefix="clearance-")) / path.name
        written = save_result(result, fallback, output)
        print(
            f"error: could not write {path} ({exc.strerror or exc}); the result was saved to {written} instead",
            file=sys.stderr,
        )
        return written, False
