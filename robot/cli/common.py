"""Shared pieces of the subcommands: exit codes, option types, output checks, the progress bar."""

from __future__ import annotations

import argparse
import gc
import math
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Iterator

from robot.errors import RobotError

#: exit codes of every command
EXIT_OK, EXIT_RUN_FAILED, EXIT_BAD_INPUT, EXIT_INTERNAL, EXIT_INTERRUPTED = 0, 1, 2, 3, 130

EXIT_CODES_HELP = """exit status:
  0    success
  1    the run failed or was interrupted; the partial result was saved (the message says where)
  2    bad input: scene, option, input file or output folder (the message names it; nothing was run)
  3    internal error (a bug: please report it with the traceback)
  130  interrupted before any result existed"""


class UsageError(RobotError):
    """A command-line option is invalid (or invalid together with others)."""


class OutputError(UsageError):
    """An output location cannot be written (checked before any run)."""


def positive_seconds(text: str) -> float:
    """argparse type: a finite time > 0 (s)."""
    return _number(text, low=0.0, what="a finite number of seconds > 0")


def positive_number(text: str) -> float:
    """argparse type: a finite number > 0."""
    return _number(text, low=0.0, what="a finite number > 0")


def positive_int(text: str) -> int:
    """argparse type: an integer >= 1."""
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not an integer >= 1") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be an integer >= 1")
    return value


def number_list(text: str) -> tuple[float, ...]:
    """argparse type: comma-separated finite numbers > 0 (e.g. tolerances, step sizes)."""
    return tuple(_number(part, low=0.0, what="comma-separated finite numbers > 0") for part in text.split(","))


def _number(text: str, *, low: float, what: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not {what}") from None
    if not math.isfinite(value) or value <= low:
        raise argparse.ArgumentTypeError(f"{text!r} is not {what}")
    return value


def writable_folder(path: Path, option: str = "--out") -> Path:
    """Create ``path`` if needed and check that files can be written in it (before any run)."""
    path = Path(path)
    if path.exists() and not path.is_dir():
        raise OutputError(f"{option}={str(path)!r} is a file, not a folder; give a folder for the outputs")
    try:
        path.mkdir(parents=True, exist_ok=True)
        with tempfile.TemporaryFile(dir=path):
            pass
    except OSError as exc:
        raise OutputError(f"{option}={str(path)!r} cannot be written ({exc.strerror or exc}); choose another folder") from None
    return path


def writable_file(path: Path, option: str) -> Path:
    """Check that the file ``path`` can be written (it is not a folder; its folder is writable)."""
    path = Path(path)
    if path.is_dir():
        raise OutputError(f"{option}={str(path)!r} is a folder; give a file name")
    writable_folder(path.parent if str(path.parent) else Path("."), f"the folder of {option}")
    return path


@contextmanager
def progress_bar(total: float, description: str, enabled: bool | None = None) -> Iterator[Callable[[float], None]]:
    """A tqdm bar over simulated time (shown only on a terminal unless ``enabled``; hidden: tqdm is not imported)."""
    enabled = sys.stderr.isatty() if enabled is None else enabled
    if not enabled:
        yield lambda t: None
        return
    from tqdm import tqdm

    bar = tqdm(total=total, desc=description, unit="s sim", bar_format="{l_bar}{bar}| {n:.4f}/{total:.3f} s [{elapsed}<{remaining}]")
    last = [0.0]

    def update(t: float) -> None:
        if t - last[0] >= total / 1000 or t >= total:
            bar.update(t - last[0])
            last[0] = t

    try:
        yield update
    finally:
        bar.close()


@contextmanager
def collector_spared_setup() -> Iterator[Callable[[], None]]:
    """Keep Python's cyclic garbage collector off a command's setup: ``with collector_spared_setup() as set_up:``.

    A run's imports and model (numba's types and dispatchers, Pinocchio, scipy,
    the mechanism: ~10^5 objects) live until the command ends, and every
    collection of the oldest generation walks them all: 0.1 s of CPU of
    collections in ``clearance run``, measured, for no garbage found. Inside the
    block the collector is off until ``set_up()`` (call it once the setup is
    built), which freezes every object then alive (``gc.freeze``: left out of
    later collections) and turns the collector back on for the run. Leaving the
    block unfreezes them and restores the collector's state, so a caller that
    runs commands in its own process (tests) keeps an ordinary collector; a
    caller that had frozen objects of its own keeps them frozen, and then the
    setup's stay frozen with them (``gc.unfreeze`` cannot tell them apart). The
    setup's garbage cycles (made while the collector was off) are kept until the
    block ends: it did not change the peak memory of ``clearance run``.
    """
    enabled = gc.isenabled()
    frozen_before = gc.get_freeze_count()
    gc.disable()

    def set_up() -> None:
        gc.freeze()
        if enabled:
            gc.enable()

    try:
        yield set_up
    finally:
        if frozen_before == 0:  # a caller's own frozen objects stay frozen
            gc.unfreeze()
        if enabled:
            gc.enable()


def count_text(value: float | int | None, fmt: str = "d") -> str:
    """A counter for people: ``n/a`` when unknown (``None`` or negative, the solvers' "not counted")."""
    if value is None or value < 0:
        return "n/a"
    return format(value, fmt)


def exit_on_error(main: Callable[[], int | None]) -> None:
    """Run ``main``; a library error prints its message (no traceback) and exits with status 2."""
    try:
        code = main()
    except RobotError as exc:
        print(f"error: {exc}", file=sys.stderr)
        sys.exit(EXIT_BAD_INPUT)
    sys.exit(code or 0)
