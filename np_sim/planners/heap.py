"""A compiled binary min-heap over two parallel arrays (keys, ids), for the searches' open lists.

The heap lives in caller-owned arrays so that a search can stop and resume (time budgets) without copying; each
function takes the current size and returns the new one.
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True, error_model="numpy")
def heap_push(keys: np.ndarray, ids: np.ndarray, size: int, key: float, item: int) -> int:
    """Insert ``item`` with priority ``key``; returns the new size (the arrays must have room)."""
    i = size
    while i > 0:
        parent = (i - 1) >> 1
        if keys[parent] <= key:
            break
        keys[i] = keys[parent]
        ids[i] = ids[parent]
        i = parent
    keys[i] = key
    ids[i] = item
    return size + 1


@njit(cache=True, error_model="numpy")
def heap_pop(keys: np.ndarray, ids: np.ndarray, size: int):
    """Remove the smallest key; returns (key, item, new size). ``size`` must be > 0."""
    top_key, top_id = keys[0], ids[0]
    size -= 1
    last_key, last_id = keys[size], ids[size]
    i = 0
    while True:
        child = 2 * i + 1
        if child >= size:
            break
        if child + 1 < size and keys[child + 1] < keys[child]:
            child += 1
        if keys[child] >= last_key:
            break
        keys[i] = keys[child]
        ids[i] = ids[child]
        i = child
    if size > 0:
        keys[i] = last_key
        ids[i] = last_id
    return top_key, top_id, size
