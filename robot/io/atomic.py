"""Atomic file writes: write a temporary file in the target folder, then rename.

A reader never sees a half-written result, and an interrupted run leaves the
previous file intact (``os.replace`` is atomic on POSIX and Windows). The
temporary file is removed whatever stops the write (an exception, Ctrl-C, or
SIGTERM once :mod:`robot.cli.interrupts` turned it into an exception). The
finished file gets the permissions of any new file of the user (``0666`` less the
umask), not the ``0600`` that :func:`tempfile.mkstemp` gives.
"""

from __future__ import annotations

import os
import tempfile
from pathlib import Path
from typing import Callable


def current_umask() -> int:
    """The process's umask (read from ``/proc`` where possible: setting it to read it is not thread-safe)."""
    try:
        with open("/proc/self/status", encoding="ascii") as status:
            for line in status:
                if line.startswith("Umask:"):
                    return int(line.split()[1], 8)
    except (OSError, ValueError):
        pass
    mask = os.umask(0o022)
    os.umask(mask)
    return mask


def atomic_write(path: Path | str, write: Callable[[Path], None]) -> Path:
    """Call ``write(tmp_path)`` then move ``tmp_path`` onto ``path`` atomically (permissions: 0666 & ~umask)."""
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.", suffix=path.suffix or ".tmp")
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        write(tmp_path)
        os.chmod(tmp_path, 0o666 & ~current_umask())
        os.replace(tmp_path, path)
    except BaseException:
        tmp_path.unlink(missing_ok=True)
        raise
    return path


def atomic_write_text(path: Path | str, text: str) -> Path:
    """Write ``text`` (UTF-8) to ``path`` atomically."""
    return atomic_write(path, lambda tmp: tmp.write_text(text, encoding="utf-8"))


def atomic_write_png(figure, path: Path | str, *, dpi: int, close: bool = False, **options) -> Path:
    """Write a matplotlib ``figure`` as a PNG of (size x ``dpi``) pixels to ``path`` atomically.

    ``options`` go to ``Figure.savefig`` (e.g. ``bbox_inches``); ``close``: release the figure
    from pyplot afterwards, whatever happened (figures made with ``pyplot.subplots``).
    """
    try:
        return atomic_write(path, lambda tmp: figure.savefig(tmp, format="png", dpi=dpi, **options))
    finally:
        if close:
            import matplotlib.pyplot as plt  # only a caller that used pyplot asks, so it is loaded already

            plt.close(figure)
