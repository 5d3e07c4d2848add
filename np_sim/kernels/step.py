"""The batched environment step and observation, compiled (one call steps every env, or a chosen subset of them;
``prange`` over envs).

The per-env logic follows Algorithm 1 of the paper: execute the arc (eq:arc) checked at ``samples_per_arc``
points, step reward (eq:step-reward), failure, direct terminal success, else the gated Hermite connector
(eq:hermite … eq:mincost) and the success reward (eq:terminal-reward, eq:effective-kappa), else timeout.
Scalar settings travel in one float array ``P`` indexed by the constants below (built by ``np_sim.env_core``).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from np_sim.kernels.collision import arc_valid
from np_sim.kernels.geometry import cast_beams_offsets
from np_sim.kernels.hermite import build_candidates, select_candidate
from np_sim.kernels.kinematics import arc_point, wrap_angle

# --- indices into P -------------------------------------------------------------------------------------------
(P_KAPPA_MAX, P_LENGTH_MAX, P_POS_TOL, P_HEAD_TOL, P_CONN_KAPPA_MAX, P_SEL_DK, P_SEL_LEN, P_SEL_CONST,
 P_R_DK, P_R_LEN, P_R_STEP, P_R_REV, P_R_SHORT_W, P_R_SHORT_M, P_R_BONUS, P_R_SUCC_REV, P_R_SUCC_DK,
 P_R_H_W, P_R_H_DK, P_R_H_LEN, P_R_H_CONST, P_R_H_FLOOR, P_R_FAIL, P_LIDAR_RANGE,
 P_SAMPLES, P_MAX_ARCS, P_N_BEAMS, P_FOOTPRINT, P_USE_LIDAR, P_ENSEMBLE, P_GATE, P_SIZE) = range(32)

# --- per-env state columns (float64 array S of shape (N, S_SIZE)) -----------------------------------------------
(S_X, S_Y, S_TH, S_PREV_KAPPA, S_PREV_L, S_N_ARCS, S_N_REV, S_DK_EFF, S_SUM_LEN, S_SUM_DK, S_SCENE,
 S_SIZE) = range(12)

# --- per-env step outputs (float64 array R of shape (N, R_SIZE)) -----------------------------------------------
(R_REWARD, R_TERMINATED, R_TRUNCATED, R_SUCCESS, R_COLLISION, R_HERMITE, R_H_LEN, R_H_DK, R_H_FORWARD,
 R_H_COST, R_SIZE) = range(11)


@njit(cache=True, error_model="numpy")
def write_observation(geo, k: int, x: float, y: float, th: float, target: np.ndarray, static_row: np.ndarray,
                      b_ranges: np.ndarray, off_c: np.ndarray, off_s: np.ndarray, use_lidar: bool,
                      lidar_range: float, lidar: np.ndarray, out: np.ndarray) -> None:
    """One flat observation: ego (x̃, ỹ, cos θ̃, sin θ̃) in the target frame (eq:target-frame), then the
    rectified LiDAR clearances max(d − b, 0) (eq:lidar-clearance) when enabled, then the scene's static
    target-frame geometry slots."""
    a = 0.5 * math.pi - target[2]
    c = math.cos(a)
    s = math.sin(a)
    dx = x - target[0]
    dy = y - target[1]
    tht = wrap_angle(th - target[2] + 0.5 * math.pi)
    out[0] = c * dx - s * dy
    out[1] = s * dx + c * dy
    out[2] = math.cos(tht)
    out[3] = math.sin(tht)
    o = 4
    if use_lidar:
        n_beams = lidar.shape[0]
        cast_beams_offsets(x, y, th, geo[8][k], geo[9][k], off_c, off_s, lidar_range, lidar)
        for i in range(n_beams):
            out[o + i] = max(lidar[i] - b_ranges[i], 0.0)
        o += n_beams
    for i in range(static_row.shape[0]):
        out[o + i] = static_row[i]


@njit(parallel=True, cache=True, error_model="numpy")
def observe_batch(geo, targets, static_obs, S, P, b_ranges, off_c, off_s, env_ids, obs):
    """Observations of the envs ``env_ids`` at their current poses (used after resets)."""
    n_beams = int(P[P_N_BEAMS])
    for r in prange(env_ids.shape[0]):
        i = env_ids[r]
        k = int(S[i, S_SCENE])
        lidar = np.empty(n_beams)
        write_observation(geo, k, S[i, S_X], S[i, S_Y], S[i, S_TH], targets[k], static_obs[k], b_ranges, off_c,
                          off_s, P[P_USE_LIDAR] > 0.0, P[P_LIDAR_RANGE], lidar, obs[i])


@njit(cache=True, error_model="numpy")
def _sign(v: float) -> float:
    return 1.0 if v > 0.0 else (-1.0 if v < 0.0 else 0.0)


@njit(cache=True, error_model="numpy")
def _step_reward(S, P, i, kappa: float, length: float) -> float:
    """Step reward (eq:step-reward) of env i's arc (κ, l), updating its reversal count and the sums of the terminal
    reward (eq:effective-kappa); the history terms are zero on the first arc."""
    first = S[i, S_N_ARCS] == 0.0
    prev_k = S[i, S_PREV_KAPPA]
    prev_l = S[i, S_PREV_L]
    short = max(0.0, P[P_R_SHORT_M] - abs(length))
    reward = -P[P_R_LEN] * abs(length) - P[P_R_STEP] - P[P_R_SHORT_W] * short * short
    if not first:
        reward -= P[P_R_DK] * abs(kappa - prev_k)
        if length * prev_l < 0.0:
            reward -= P[P_R_REV]
            S[i, S_N_REV] += 1.0
        S[i, S_DK_EFF] += abs(_sign(length) * kappa - _sign(prev_l) * prev_k)  # eq:effective-kappa
        S[i, S_SUM_DK] += abs(kappa - prev_k)
    S[i, S_SUM_LEN] += abs(length)
    return reward


@njit(cache=True, error_model="numpy")
def _connect(geo, k, target, P, nx: float, ny: float, nth: float, kappa: float, local, offsets, headings, scales0,
             scales1, basis, dbasis, pts, kbar_max, dk, lengths, costs):
    """The gated Hermite connector (eq:hermite … eq:mincost) from the reached pose (nx, ny, nth) of scene k:
    (index of the selected candidate or −1, whether it drives forward)."""
    # target-frame reached pose (eq:target-frame)
    a = 0.5 * math.pi - target[2]
    ca = math.cos(a)
    sa = math.sin(a)
    dx = nx - target[0]
    dy = ny - target[1]
    xt = ca * dx - sa * dy
    yt = sa * dx + ca * dy
    tht = wrap_angle(nth - target[2] + 0.5 * math.pi)
    if not (P[P_GATE] == 0.0 or math.sin(tht) > 0.0):
        return -1, False
    forward = yt < 0.0
    n_cand = build_candidates(xt, yt, tht, forward, kappa, offsets, headings, scales0, scales1, basis, P[P_SEL_DK],
                              P[P_SEL_LEN], P[P_SEL_CONST], pts, kbar_max, dk, lengths, costs)
    ensemble = P[P_ENSEMBLE] > 0.0
    hermite = select_candidate(geo, k, target, xt, yt, tht, forward, offsets, headings, scales0, scales1, dbasis, pts,
                               kbar_max, costs, n_cand, ensemble, P[P_CONN_KAPPA_MAX], P[P_FOOTPRINT] > 0.0, local)
    return hermite, forward


@njit(cache=True, error_model="numpy")
def _success_reward(S, P, i, hermite: int, h_len: float, h_dk: float) -> float:
    """Success reward of env i (eq:terminal-reward), with the connector's penalty when it closed the episode."""
    p_h = 0.0
    if hermite >= 0:
        p_h = -(P[P_R_H_DK] * h_dk + P[P_R_H_LEN] * h_len + P[P_R_H_CONST])
        if P[P_ENSEMBLE] > 0.0:
            p_h = max(p_h, P[P_R_H_FLOOR])
    return (P[P_R_BONUS] - P[P_R_SUCC_REV] * S[i, S_N_REV] - P[P_R_SUCC_DK] * S[i, S_DK_EFF]
            + P[P_R_H_W] * p_h)


@njit(cache=True, error_model="numpy")
def step_one(geo, targets, static_obs, S, P, i, kappa, length, local, b_ranges, off_c, off_s, offsets, headings,
             scales0, scales1, basis, dbasis, pts, kbar_max, dk, lengths, costs, obs_row, R_row) -> None:
    """Advance env i by the arc (κ, l) (already in physical units) and write its reward, flags and observation."""
    k = int(S[i, S_SCENE])
    target = targets[k]
    x = S[i, S_X]
    y = S[i, S_Y]
    th = S[i, S_TH]
    footprint = P[P_FOOTPRINT] > 0.0
    reward = _step_reward(S, P, i, kappa, length)

    # execute the arc, checked at samples_per_arc points (eq:arc)
    corners = np.empty((4, 2))
    valid = arc_valid(geo, k, x, y, th, kappa, length, int(P[P_SAMPLES]), footprint, local, corners)
    nx, ny, nth = arc_point(x, y, th, kappa, length)
    S[i, S_X] = nx
    S[i, S_Y] = ny
    S[i, S_TH] = nth
    S[i, S_PREV_KAPPA] = kappa
    S[i, S_PREV_L] = length
    S[i, S_N_ARCS] += 1.0

    terminated = False
    success = False
    hermite = -1
    h_len = 0.0
    h_dk = 0.0
    h_fwd = 0.0
    h_cost = 0.0
    if not valid:
        reward += P[P_R_FAIL]
        terminated = True
    else:
        dist = math.sqrt((nx - target[0]) ** 2 + (ny - target[1]) ** 2)
        if dist <= P[P_POS_TOL] and abs(wrap_angle(nth - target[2])) <= P[P_HEAD_TOL]:
            success = True
        else:
            hermite, forward = _connect(geo, k, target, P, nx, ny, nth, kappa, local, offsets, headings, scales0,
                                        scales1, basis, dbasis, pts, kbar_max, dk, lengths, costs)
            if hermite >= 0:
                success = True
                h_len = lengths[hermite]
                h_dk = dk[hermite]
                h_cost = costs[hermite]
                h_fwd = 1.0 if forward else -1.0
        if success:
            reward += _success_reward(S, P, i, hermite, h_len, h_dk)  # eq:terminal-reward
            terminated = True
    truncated = (not terminated) and S[i, S_N_ARCS] >= P[P_MAX_ARCS]

    R_row[R_REWARD] = reward
    R_row[R_TERMINATED] = 1.0 if terminated else 0.0
    R_row[R_TRUNCATED] = 1.0 if truncated else 0.0
    R_row[R_SUCCESS] = 1.0 if success else 0.0
    R_row[R_COLLISION] = 0.0 if valid else 1.0
    R_row[R_HERMITE] = hermite
    R_row[R_H_LEN] = h_len
    R_row[R_H_DK] = h_dk
    R_row[R_H_FORWARD] = h_fwd
    R_row[R_H_COST] = h_cost
    lidar = np.empty(b_ranges.shape[0])
    write_observation(geo, k, nx, ny, nth, target, static_obs[k], b_ranges, off_c, off_s, P[P_USE_LIDAR] > 0.0,
                      P[P_LIDAR_RANGE], lidar, obs_row)


@njit(parallel=True, cache=True, error_model="numpy")
def step_rows(geo, targets, static_obs, S, P, rows, actions, local, b_ranges, off_c, off_s, offsets, headings, scales0,
              scales1, basis, dbasis, pts, kbar_max, dk, lengths, costs, obs, R) -> None:
    """Step the envs ``rows`` (distinct indices), env ``rows[r]`` by the normalised action row ``actions[r]`` =
    (a_0, a_1) ∈ [−1, 1]², mapped to κ = a_0·κ_max, l = a_1·l_max; every other env's rows of ``S``, ``obs``, ``R``
    and the scratch stay untouched.

    ``pts``, ``kbar_max``, ``dk``, ``lengths``, ``costs`` are per-env Hermite scratch (leading axis = env).
    """
    for r in prange(rows.shape[0]):
        i = rows[r]
        kappa = actions[r, 0] * P[P_KAPPA_MAX]
        length = actions[r, 1] * P[P_LENGTH_MAX]
        step_one(geo, targets, static_obs, S, P, i, kappa, length, local, b_ranges, off_c, off_s, offsets, headings,
                 scales0, scales1, basis, dbasis, pts[i], kbar_max[i], dk[i], lengths[i], costs[i], obs[i], R[i])
