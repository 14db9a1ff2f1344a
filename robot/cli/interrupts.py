"""Clean stops: SIGINT (Ctrl-C) and SIGTERM end a command the same way, never mid-write.

A command goes through three phases (:class:`Phase`), and what a signal does
depends on the phase it arrives in:

* ``PREPARING`` (reading the scene, building the model): nothing to save; the
  command stops at once (``KeyboardInterrupt``, exit status 130).
* ``RUNNING``: inside the integration (the step loop's
  ``EventDrivenIntegrator.run`` is on the interrupted stack: the Lagrange model's
  runs and the Newton-Euler cross-check's) the signal raises ``KeyboardInterrupt``, which the
  step loop turns into a run stopped with cause ``interrupted``; the command then
  computes the outputs and saves the partial result. Outside the integration
  (computing the outputs) the signal is only noted.
* ``SAVING``: noted, never raised, so a write finishes (and its temporary file
  is renamed or removed) whatever arrives.

Every signal prints at once what is happening ("saving the partial result to
..."). SIGTERM is handled like SIGINT; worker processes can be told too
(``forward``: their ids get SIGINT).
"""

from __future__ import annotations

import enum
import os
import signal
import sys
from contextlib import contextmanager
from types import FrameType
from typing import Callable, Iterable, Iterator

HANDLED = (signal.SIGINT, signal.SIGTERM)


class Phase(enum.Enum):
    PREPARING = "preparing"
    RUNNING = "running"
    SAVING = "saving"


def _integration_code():
    # the step loop's run() turns KeyboardInterrupt into an "interrupted" result: every engine's
    # integration goes through it (the Lagrange model's integrate() and the Newton-Euler cross-check)
    from robot.integration.event_loop import EventDrivenIntegrator

    return EventDrivenIntegrator.run.__code__


def inside_integration(frame: FrameType | None) -> bool:
    """Whether ``frame`` runs inside the step loop, whose ``except KeyboardInterrupt`` stops a run cleanly."""
    code = _integration_code()
    while frame is not None:
        if frame.f_code is code:
            return True
        frame = frame.f_back
    return False


class StopControl:
    """The signal handler's state: the phase, what is being saved, the signals received."""

    def __init__(self, saving: str = "saving the result", forward: Callable[[], Iterable[int]] | None = None) -> None:
        self.phase = Phase.PREPARING
        self.saving = saving
        self.forward = forward
        self.received: list[str] = []

    @property
    def requested(self) -> bool:
        """Whether a stop was asked for."""
        return bool(self.received)

    def handle(self, signum: int, frame: FrameType | None) -> None:
        name = signal.Signals(signum).name
        self.received.append(name)
        if self.forward is not None:
            for pid in self.forward():
                try:
                    os.kill(pid, signal.SIGINT)
                except OSError:
                    pass
        first = len(self.received) == 1
        if self.phase is Phase.PREPARING:
            _say(f"{name}: stopping (no run has started, nothing to save)")
            raise KeyboardInterrupt
        if self.phase is Phase.RUNNING and first and inside_integration(frame):
            _say(f"{name}: stopping the integration; then {self.saving} (the partial result; please wait)")
            raise KeyboardInterrupt
        if first:
            _say(f"{name}: finishing: {self.saving}; please wait")
        else:
            _say(f"{name} again: still {self.saving}; please wait, the file is written atomically")


def _say(text: str) -> None:
    print(f"\n{text}", file=sys.stderr, flush=True)


@contextmanager
def clean_stops(saving: str = "saving the result", forward: Callable[[], Iterable[int]] | None = None) -> Iterator[StopControl]:
    """Handle SIGINT and SIGTERM with a :class:`StopControl` for the duration of the block."""
    control = StopControl(saving, forward)
    previous = {sig: signal.signal(sig, control.handle) for sig in HANDLED}
    try:
        yield control
    finally:
        for sig, handler in previous.items():
            signal.signal(sig, handler)


def install_in_worker() -> None:
    """Initializer of worker processes: the same clean stops, with the worker always in the running phase.

    A worker's own integration stops on the first signal and saves its partial
    result; it is told by the main process (``forward``) or by the terminal.
    """
    control = StopControl("saving this scene's partial result")
    control.phase = Phase.RUNNING
    for sig in HANDLED:
        signal.signal(sig, control.handle)
