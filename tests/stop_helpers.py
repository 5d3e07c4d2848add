"""A trainer step that sends this process a stop signal after one chosen step (tests of `np_sim.stop_request`)."""

import os


def signal_after(step, signum, when):
    """``step`` (a trainer method or function taking the trainer) wrapped to send this process ``signum`` right
    after the call on a trainer for which ``when(trainer)`` holds."""

    def stepped_then_signalled(trainer):
        result = step(trainer)
        if when(trainer):
            os.kill(os.getpid(), signum)
        return result

    return stepped_then_signalled
