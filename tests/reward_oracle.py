"""Test oracle: the reward terms of the planning episode written as plain Python (paper eq:step-reward,
eq:effective-kappa, eq:terminal-reward), for tests to compare the env against.

The env never calls these: its rewards are computed once, in the compiled step kernel (``np_sim.kernels.step``).
``tests/np_sim/test_reward.py`` pins this oracle to hand-computed values; weights come from ``RewardConfig``.
"""

from __future__ import annotations

import numpy as np

from np_sim.config import RewardConfig


def step_reward(kappa: float, length: float, prev_kappa: float | None, prev_length: float | None,
                config: RewardConfig = RewardConfig()) -> float:
    """eq:step-reward: −0.05|κ_t − κ_{t−1}| − 10|l_t| − 5 − 100 I[l_t l_{t−1} < 0] − 2 max(0, 0.5 − |l_t|)².

    ``prev_*`` None (the first arc) sets both history terms to zero.
    """
    short = max(0.0, config.short_arc_m - abs(length))
    r = -config.length_weight * abs(length) - config.step_penalty - config.short_arc_weight * short**2
    if prev_kappa is not None:
        r -= config.kappa_change_weight * abs(kappa - prev_kappa)
        if length * prev_length < 0:
            r -= config.reversal_penalty
    return float(r)


def effective_kappa_change(arcs) -> float:
    """eq:effective-kappa: Σ_{t≥2} |sgn(l_t)κ_t − sgn(l_{t−1})κ_{t−1}| over arcs (T, 2) rows (κ, l)."""
    a = np.asarray(arcs, float).reshape(-1, 2)
    steer = np.sign(a[:, 1]) * a[:, 0]
    return float(np.abs(np.diff(steer)).sum())


def hermite_score(delta_kappa_h: float, length_h: float, ensemble: bool,
                  config: RewardConfig = RewardConfig()) -> float:
    """p_H of eq:terminal-reward: −(0.05Δκ_H + 10L_H + 5), floored at −500 for the ensemble only."""
    p = -(config.hermite_kappa_weight * delta_kappa_h + config.hermite_length_weight * length_h
          + config.hermite_constant)
    return float(max(p, config.hermite_floor)) if ensemble else float(p)


def success_reward(arcs, p_h: float = 0.0, config: RewardConfig = RewardConfig()) -> float:
    """eq:terminal-reward: 1250.5 − 20 N_rev − Δκ_eff + 1.5 p_H over the episode's policy arcs (p_H = 0 direct)."""
    a = np.asarray(arcs, float).reshape(-1, 2)
    n_rev = int(np.count_nonzero(a[1:, 1] * a[:-1, 1] < 0))
    return float(config.success_bonus - config.success_reversal_weight * n_rev
                 - config.success_kappa_weight * effective_kappa_change(a) + config.hermite_weight * p_h)
