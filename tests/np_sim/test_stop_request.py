"""The graceful stop of training runs: SIGTERM or SIGUSR1 is recorded while a StopRequest is entered, a second one
gets the default action, and the previous handlers come back on exit."""

import os
import signal
import threading

import pytest

from np_sim.stop_request import STOP_SIGNALS, STOPPED_EXIT_STATUSES, StopRequest, TrainingStopped
from stop_helpers import guarded_stop_signals


@pytest.mark.parametrize("signum", STOP_SIGNALS)
def test_a_stop_signal_is_recorded_and_the_next_one_gets_the_default_action(signum):
    with guarded_stop_signals() as guard:  # the previous handler, which must come back
        with StopRequest() as stop:
            assert not stop.requested
            os.kill(os.getpid(), signum)  # the handler runs before os.kill returns to this frame's next bytecode
            assert stop.requested and stop.signum == signum
            assert all(signal.getsignal(s) == signal.SIG_DFL for s in STOP_SIGNALS)
        assert all(signal.getsignal(s) is guard for s in STOP_SIGNALS) and not guard.received


def test_outside_the_main_thread_it_changes_no_handler():
    previous = {s: signal.getsignal(s) for s in STOP_SIGNALS}
    seen = []

    def enter():
        with StopRequest() as stop:
            seen.append(({s: signal.getsignal(s) for s in STOP_SIGNALS}, stop.requested))

    thread = threading.Thread(target=enter)
    thread.start()
    thread.join()
    assert seen == [(previous, False)]


def test_the_stopped_exception_names_the_run_the_signal_and_its_shell_exit_status(tmp_path):
    stopped = TrainingStopped(tmp_path / "run", "epoch 7 of 240", signal.SIGTERM)
    assert str(stopped) == f"{tmp_path / 'run'}: stopped by SIGTERM after epoch 7 of 240; snapshot.pt written, " \
                           "continue it with --resume"
    usr1 = 128 + int(signal.SIGUSR1)  # 138 on Linux, 158 on macOS
    assert stopped.exit_status == 143 and TrainingStopped("r", "x", signal.SIGUSR1).exit_status == usr1
    assert STOPPED_EXIT_STATUSES == {143, usr1}
