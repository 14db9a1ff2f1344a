"""What each local worker process runs first (dask's ``distributed.worker.preload``): Ctrl-C is the sweep's.

Ctrl-C at a terminal sends SIGINT to the whole foreground process group, so the
local workers received it as well as the sweep process. The sweep process
handles it (it keeps the finished runs, closes the cluster and says how to
resume); each worker also raised ``KeyboardInterrupt`` inside dask and printed
its traceback before that message. The local workers therefore ignore SIGINT:
the cluster's close stops them, and a run in flight is dropped as documented.
Workers of a cluster the user started (``--scheduler``) are not touched.
"""

from __future__ import annotations

import signal
from typing import Any


def dask_setup(worker: Any) -> None:
    """Called by dask in the worker process, in its main thread, before the worker takes tasks."""
    signal.signal(signal.SIGINT, signal.SIG_IGN)
