"""Path metrics of a plan (paper eq:metrics)."""

from __future__ import annotations

import numpy as np


def plan_metrics(arcs, hermite_length: float | None = None, hermite_delta_kappa: float | None = None,
                 hermite_forward: bool | None = None) -> tuple[float, int, float]:
    """(L, N_rev, Δκ) of executed arcs (T, 2) rows (κ_t, l_t) and an optional terminal Hermite segment.

    eq:metrics: L = Σ|l_t| + L_H; N_rev = Σ_{t≥2} I[l_t l_{t−1} < 0] + I[l_T q_H < 0];
    Δκ = Σ_{t≥2} |κ_t − κ_{t−1}| + Δκ_H, with q_H = +1 forward, −1 reverse. Without a Hermite segment (direct
    terminal success) its terms are omitted.
    """
    a = np.asarray(arcs, dtype=float).reshape(-1, 2)
    kappa, length = a[:, 0], a[:, 1]
    has_h = hermite_length is not None
    if has_h and (hermite_delta_kappa is None or hermite_forward is None):
        raise ValueError("plan_metrics: a Hermite segment needs hermite_length, hermite_delta_kappa and "
                         "hermite_forward")
    total = float(np.abs(length).sum()) + (float(hermite_length) if has_h else 0.0)
    reversals = int(np.count_nonzero(length[1:] * length[:-1] < 0))
    dk = float(np.abs(np.diff(kappa)).sum())
    if has_h:
        q_h = 1.0 if hermite_forward else -1.0
        if len(length) and length[-1] * q_h < 0:
            reversals += 1
        dk += float(hermite_delta_kappa)
    return total, reversals, dk
