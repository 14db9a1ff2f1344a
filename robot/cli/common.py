"""Shared command-line helpers for the thin scripts in ``scripts/``."""

from __future__ import annotations

import sys
from contextlib import contextmanager
from typing import Callable, Iterator

from robot.errors import RobotError


@contextmanager
def progress_bar(total: float, description: str, enabled: bool | None = None) -> Iterator[Callable[[float], None]]:
    """A tqdm bar over simulated time (shown only on a terminal unless ``enabled``)."""
    from tqdm import tqdm

    enabled = sys.stderr.isatty() if enabled is None else enabled
    bar = tqdm(total=total, desc=description, unit="s sim", disable=not enabled, bar_format="{l_bar}{bar}| {n:.4f}/{total:.3f} s [{elapsed}<{remaining}]")
    last = [0.0]

    def update(t: float) -> None:
        if t - last[0] >= total / 1000 or t >= total:
            bar.update(t - last[0])
            last[0] = t

    try:
        yield update
    finally:
        bar.close()


def exit_on_error(main: Callable[[], int | None]) -> None:
    """Run ``main``; a library error prints its message (no traceback) and exits with status 2."""
    try:
        code = main()
    except RobotError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(2)
    sys.exit(code or 0)
