"""How many threads torch and numba's parallel loops run on in one process (training, autoencoder pretraining)."""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager

import numba
import torch


def use_threads(n: int) -> None:
    """Run torch and numba's parallel env loops on ``n`` threads each (numba's at most ``NUMBA_NUM_THREADS``; 0
    leaves both at their defaults, all cores). Setting torch alone did not hold: numba's OpenMP layer sets the
    process's OpenMP thread count to its own when its first parallel loop starts, after which torch ran on all
    cores too, and a run meant to share a 2-core machine with another job spun two threads in every update (an
    epoch about 10× slower)."""
    if n:
        numba.set_num_threads(min(n, numba.config.NUMBA_NUM_THREADS))
        torch.set_num_threads(n)


@contextmanager
def threads(n: int) -> Iterator[None]:
    """``use_threads(n)`` inside the block, the process's previous torch and numba counts restored after it (a run in
    the caller's process plays as a pool worker does, and leaves the caller as it was)."""
    before = torch.get_num_threads(), numba.get_num_threads()
    try:
        use_threads(n)
        yield
    finally:
        torch.set_num_threads(before[0])
        numba.set_num_threads(before[1])


def thread_counts() -> dict[str, int]:
    """The threads this process trains on: torch's and numba's counts (each epoch's metrics row records them)."""
    return {"torch_threads": torch.get_num_threads(), "numba_threads": numba.get_num_threads()}
