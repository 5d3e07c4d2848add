"""tracking.kernels: the compiled nearest-piece search against a numpy version."""

import numpy as np

from tracking.kernels import nearest_piece


def _nearest_numpy(xy, p, i0, i1):
    a, d = xy[i0:i1], xy[i0 + 1:i1 + 1] - xy[i0:i1]
    t = np.clip(np.einsum("ij,ij->i", p - a, d) / np.einsum("ij,ij->i", d, d), 0, 1)
    gap = p - a - t[:, None] * d
    k = int(np.argmin(np.einsum("ij,ij->i", gap, gap)))
    return i0 + k, t[k]


def test_nearest_piece_matches_numpy_on_random_polylines():
    rng = np.random.default_rng(0)
    for _ in range(200):
        xy = np.cumsum(rng.normal(size=(int(rng.integers(3, 40)), 2)), axis=0)
        p = rng.normal(scale=5.0, size=2)
        i0 = int(rng.integers(0, len(xy) - 2))
        i1 = int(rng.integers(i0 + 1, len(xy)))
        i, t = nearest_piece(xy, p[0], p[1], i0, i1)
        j, u = _nearest_numpy(xy, p, i0, i1)
        assert i == j and abs(t - u) < 1e-12
