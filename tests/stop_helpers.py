"""Helpers of the tests of `np_sim.stop_request`: a trainer step that sends this process a stop signal after one
chosen step, and a guard that keeps such a signal from ending pytest when the code under test fails to catch it."""

import os
import signal
from contextlib import contextmanager

from np_sim.stop_request import STOP_SIGNALS


def signal_after(step, signum, when):
    """``step`` (a trainer method or function taking the trainer) wrapped to send this process ``signum`` right
    after the call on a trainer for which ``when(trainer)`` holds."""

    def stepped_then_signalled(trainer):
        result = step(trainer)
        if when(trainer):
            os.kill(os.getpid(), signum)
        return result

    return stepped_then_signalled


@contextmanager
def guarded_stop_signals():
    """While the block runs, the stop signals reach a handler that records them instead of their default action
    (ending this process, pytest with it); yields that handler, whose ``received`` lists what reached it."""

    def guard(signum, frame):
        guard.received.append(signum)

    guard.received = []
    previous = {s: signal.signal(s, guard) for s in STOP_SIGNALS}
    try:
        yield guard
    finally:
        for signum, handler in previous.items():
            signal.signal(signum, handler)
