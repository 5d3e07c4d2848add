"""A graceful stop for long training runs: SIGTERM or SIGUSR1 lets the run finish the epoch (or update) in progress,
write its snapshot there and exit, so that ``--resume`` continues it exactly and nothing after the last periodic
snapshot is lost.

A cluster that preempts a job sends SIGTERM; on a shared machine ``kill -USR1 PID`` asks a run to stop at its next
safe point. A second such signal ends the process at once (the signal's default action), as does SIGKILL. The
trainer then exits with status 128 + the signal's number (the shell's code for a process ended by that signal:
143 for SIGTERM, 138 for SIGUSR1), so a scheduler never mistakes the stop for a finished run.
"""

from __future__ import annotations

import signal
import sys
import threading
from pathlib import Path
from types import FrameType
from typing import NoReturn

STOP_SIGNALS = (signal.SIGTERM, signal.SIGUSR1)
"""Signals that ask a run to stop at its next snapshot point."""

STOPPED_EXIT_STATUSES = frozenset(128 + s for s in STOP_SIGNALS)
"""Exit statuses of a trainer that stopped on request after writing its snapshot."""


class TrainingStopped(Exception):
    """Raised by a trainer once it has written its snapshot on a stop request: the run is resumable from there."""

    def __init__(self, out: str | Path, position: str, signum: int):
        self.signum = signum
        super().__init__(f"{out}: stopped by {signal.Signals(signum).name} after {position}; snapshot.pt written, "
                         "continue it with --resume")

    @property
    def exit_status(self) -> int:
        """128 + the signal's number."""
        return 128 + self.signum

    def exit(self) -> NoReturn:
        """A trainer CLI's ending after the stop: this message on stderr, then SystemExit with `exit_status`."""
        print(self, file=sys.stderr)
        raise SystemExit(self.exit_status) from None


class StopRequest:
    """While entered (``with StopRequest() as stop:``), the first SIGTERM or SIGUSR1 sets ``stop.signum`` instead of
    ending the process, and both signals go back to their default action, so a second one ends it at once. The
    previous handlers are restored on exit. Python lets only the main thread install handlers: entered elsewhere,
    it changes nothing and is never requested."""

    def __init__(self) -> None:
        self.signum: int | None = None
        self._previous: dict[int, object] = {}

    def __enter__(self) -> StopRequest:
        if threading.current_thread() is threading.main_thread():
            self._previous = {s: signal.signal(s, self._request) for s in STOP_SIGNALS}
        return self

    def __exit__(self, *exc_info: object) -> None:
        for signum, handler in self._previous.items():
            signal.signal(signum, handler)
        self._previous = {}

    def _request(self, signum: int, frame: FrameType | None) -> None:
        self.signum = signum
        for s in STOP_SIGNALS:
            signal.signal(s, signal.SIG_DFL)

    @property
    def requested(self) -> bool:
        """A stop signal arrived since the context was entered."""
        return self.signum is not None
