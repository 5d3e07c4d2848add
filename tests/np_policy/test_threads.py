"""np_policy.threads: a block run on one thread, as a pool worker runs, leaves its caller's thread counts as they
were."""

import numba
import pytest
import torch

from np_policy.threads import threads


def _counts() -> tuple[int, int]:
    return torch.get_num_threads(), numba.get_num_threads()


def test_a_block_runs_on_one_thread_and_the_callers_counts_come_back_even_after_an_error():
    saved = _counts()
    try:
        torch.set_num_threads(2)
        numba.set_num_threads(min(2, numba.config.NUMBA_NUM_THREADS))
        caller = _counts()
        with threads(1):
            assert _counts() == (1, 1)
        assert _counts() == caller
        with pytest.raises(RuntimeError, match="inside"):
            with threads(1):
                raise RuntimeError("inside")
        assert _counts() == caller
    finally:
        torch.set_num_threads(saved[0])
        numba.set_num_threads(saved[1])
