"""Reeds–Shepp shortest paths as action arcs (Reeds & Shepp 1990; spec §7, §10).

``shortest_length(start, goal, kappa_max)`` is the length (m) of the shortest forward/reverse path of curvature
at most κ_max between two poses; ``shortest_path(start, goal, kappa_max)`` returns that path as (T, 2) arcs (κ, l)
of paper eq:arc, T ≤ 5, ready for ``Plan.arcs``. The 48-word solver is compiled (``np_sim.kernels.reeds_shepp``).
"""

from __future__ import annotations

import math

import numpy as np

from np_sim.kernels.reeds_shepp import MAX_PIECES, rs_arcs_into, rs_length

__all__ = ["shortest_length", "shortest_path"]

MIN_PIECE_M = 1e-9
"""Pieces shorter than this (m) are dropped from returned paths: rounding residue at word boundaries."""


def _pose(name: str, pose) -> tuple[float, float, float]:
    p = np.asarray(pose, dtype=float)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"reeds_shepp: {name} must be a finite [x, y, θ] of shape (3,), got {pose!r}")
    return float(p[0]), float(p[1]), float(p[2])


def _kappa(kappa_max) -> float:
    k = float(kappa_max)
    if not (math.isfinite(k) and k > 0):
        raise ValueError(f"reeds_shepp: kappa_max must be a finite positive curvature (1/m), got {kappa_max!r}")
    return k


def shortest_length(start, goal, kappa_max: float) -> float:
    """Length (m) of the shortest Reeds–Shepp path from ``start`` to ``goal`` (poses [x, y, θ]) at curvature ≤ κ_max.

    Reeds & Shepp (1990): the minimum over their 48 words (formulas 8.1–8.11 and symmetries), scaled by 1/κ_max.
    """
    return float(rs_length(*_pose("start", start), *_pose("goal", goal), _kappa(kappa_max)))


def shortest_path(start, goal, kappa_max: float) -> np.ndarray:
    """The shortest Reeds–Shepp path as (T, 2) arcs (κ, l) of paper eq:arc, T ≤ 5, in driving order.

    Each piece of physical steering c ∈ {left, straight, right} and signed length l (sign = gear) is the arc
    κ = −sgn(l)·c·κ_max (spec §2), so ``arc_step`` applied piece by piece from ``start`` ends at ``goal``.
    """
    out = np.empty((MAX_PIECES, 2))
    n = rs_arcs_into(*_pose("start", start), *_pose("goal", goal), _kappa(kappa_max), MIN_PIECE_M, out)
    return out[:n].copy()
