"""HOPE's 42-anchor LiDAR action mask (``jiamiya/HOPE`` ``src/model/action_mask.py``) and how the agent applies it
(``ppo_agent.py`` ``_post_process_action`` → ``ActionMask.choose_action``).

**Anchors.** 21 steering angles δ_j = δ_max (1 − j/10), j = 0..20 (0.75 … −0.75 rad), first driving forward, then the
same 21 in reverse: 42 anchors. In normalised action units an anchor is (δ_j/δ_max, ±1).

**Swept distances.** Each anchor is rolled out from the origin at HOPE's mask speed (1 m/s, ``step_speed``) for the
rollout time T (0.5 s): n = 10 poses at arc lengths s_k = k·v·T/n, k = 1..n (a 0.5 m sweep; a full-speed action
covers 1.25 m). For beam direction ψ_b = 2πb/n_beams (vehicle frame) and pose k, d*_{b,a,k} is the distance from
the origin to the farthest crossing of the ray with the footprint rectangle at that pose (0 when it misses).
Beams and d* are up-sampled ×10 by circular linear interpolation over the beam index.

**Mask.** The observed distance per beam is clip(d_i − b_i, 0, range) + b_i, up-sampled the same way. Anchor a is
free for its first m_a poses, m_a = the first k at which some up-sampled beam has d* > observed (n if none).
Post-processing (HOPE ``post_process``), per gear half: the two extreme-steering anchors lose one pose, a minimum
filter of width 5 over neighbouring steering anchors (edges reflected), clip to [0, n], divide by n. When every
entry is 0 the mask is 0.01 everywhere.

**Use by the agent** (`apply_mask`): the executed action is one of the 42 anchors, drawn with probability
∝ exp(Σ_d clip(log N(anchor_d; μ_d, σ_d), −10, 10)) · mask_a; the agent then scores that anchor under its Gaussian
(log-probability for PPO). The mask value weights the anchor's probability; it does not shorten the action.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from hope_policy.config import HopeEnvConfig
from hope_policy.spaces import N_ANCHORS
from np_sim.kernels.kinematics import arc_point

N_STEER = N_ANCHORS // 2
MASK_SPEED_MPS = 1.0
"""Speed of HOPE's anchor sweeps (``configs.py`` ``step_speed``), in m/s."""
MASK_SECTOR = 50
"""Up-sampled beams per run of the exact shortcut in `free_poses` (a speed setting; the mask does not depend on it)."""
MASK_FLOOR = 0.01
"""HOPE's mask value for every anchor when no anchor has a free pose."""
LOG_PROB_CLIP = 10.0
"""HOPE clips each per-dimension Gaussian log-density to ±10 before summing."""


def anchor_actions() -> np.ndarray:
    """(42, 2) normalised anchor actions (δ_j/δ_max, ±1): forward anchors 0..20, reverse 21..41."""
    steer = 1.0 - np.arange(N_STEER) / (N_STEER - 1) * 2.0
    return np.concatenate([np.stack([steer, np.ones(N_STEER)], 1), np.stack([steer, -np.ones(N_STEER)], 1)])


def anchor_poses(config: HopeEnvConfig) -> np.ndarray:
    """(42, n, 3) poses (x, y, θ) of each anchor's sweep from the origin at arc lengths s_k = k·v·T/n, k = 1..n
    (v = HOPE's mask speed), on the arc of steering angle δ_j (curvature tan δ_j / wheelbase, spec §2 signs)."""
    n = config.mask_iterations
    a = anchor_actions()
    c = np.tan(a[:, 0] * config.max_steer_rad) / config.vehicle.wheelbase_m
    length = a[:, 1] * MASK_SPEED_MPS * config.rollout_s
    kappa = -np.sign(length) * c
    out = np.empty((len(a), n, 3))
    for j in range(len(a)):
        for k in range(n):
            out[j, k] = arc_point(0.0, 0.0, 0.0, kappa[j], length[j] * (k + 1) / n)
    return out


def ray_box_far_distance(directions: np.ndarray, corners: np.ndarray) -> np.ndarray:
    """(B, P) distance from the origin along each ray (B, 2) unit directions to the farthest crossing with the
    closed polygon ``corners`` (P, V, 2); 0 where the ray misses."""
    p = corners[:, :, None, :]  # (P, V, 1, 2)
    e = np.roll(corners, -1, axis=1)[:, :, None, :] - p
    u = directions[None, None, :, :]
    denom = u[..., 0] * e[..., 1] - u[..., 1] * e[..., 0]
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (p[..., 0] * e[..., 1] - p[..., 1] * e[..., 0]) / denom
        s = (p[..., 0] * u[..., 1] - p[..., 1] * u[..., 0]) / denom
    tol = 1e-8
    hit = (denom != 0) & (t >= -tol) & (s >= -tol) & (s <= 1 + tol)
    return np.where(hit, t, 0.0).max(axis=1).T


def upsample_circular(x: np.ndarray, rate: int) -> np.ndarray:
    """Linear interpolation ×``rate`` along axis 0, treating it as circular (HOPE ``_linear_interpolate``):
    y[j] = x[j // r] (1 − f) + x[j // r + 1] f, f = (j mod r)/r, index n wrapping to 0."""
    j = np.arange(x.shape[0] * rate)
    f = ((j % rate) / rate).reshape((-1,) + (1,) * (x.ndim - 1))
    xc = np.concatenate([x, x[:1]], axis=0)
    return xc[j // rate] * (1.0 - f) + xc[j // rate + 1] * f


def swept_distances(config: HopeEnvConfig) -> np.ndarray:
    """d* (42, n, n_beams · up-sampling): up-sampled farthest footprint distance of each anchor sweep pose per beam."""
    n_beams = config.observation.n_beams
    psi = 2.0 * math.pi * np.arange(n_beams) / n_beams
    directions = np.stack([np.cos(psi), np.sin(psi)], 1)
    poses = anchor_poses(config).reshape(-1, 3)
    local = config.vehicle.footprint_local()
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    corners = np.stack([poses[:, :1] + c * local[:, 0] - s * local[:, 1],
                        poses[:, 1:2] + s * local[:, 0] + c * local[:, 1]], axis=-1)
    far = ray_box_far_distance(directions, corners)  # (n_beams, 42 · n)
    up = upsample_circular(far, config.mask_upsample).reshape(-1, N_ANCHORS, config.mask_iterations)
    return np.ascontiguousarray(up.transpose(1, 2, 0))


def sector_maxima(dist_star: np.ndarray, sector: int) -> np.ndarray:
    """(42, n, S) maximum of d* over each run of ``sector`` consecutive up-sampled beams (the last run may be
    shorter): lets `free_poses` skip beam runs whose observed minimum already exceeds the sweep."""
    n_up = dist_star.shape[2]
    starts = np.arange(0, n_up, sector)
    return np.ascontiguousarray(np.maximum.reduceat(dist_star, starts, axis=2))


@njit(cache=True, error_model="numpy")
def free_poses(distances: np.ndarray, b_ranges: np.ndarray, lidar_range: float, dist_star: np.ndarray,
               sector_max: np.ndarray, sector: int, rate: int, out: np.ndarray) -> None:
    """m_a (42,) into ``out``: how many leading poses of each anchor sweep stay inside the observed free range
    (module docstring, "Mask"); ``distances`` are the benchmark ray distances d_i, ``dist_star`` (42, n, n_up)
    from `swept_distances` and ``sector_max`` from `sector_maxima` (an exact shortcut: a run of beams whose
    smallest observed distance is at least the run's largest d* cannot block)."""
    n_beams = distances.shape[0]
    obs = np.empty(n_beams + 1)
    for i in range(n_beams):
        obs[i] = min(max(distances[i] - b_ranges[i], 0.0), lidar_range) + b_ranges[i]
    obs[n_beams] = obs[0]
    n_up = n_beams * rate
    up = np.empty(n_up)
    for j in range(n_up):
        f = (j % rate) / rate
        up[j] = obs[j // rate] * (1.0 - f) + obs[j // rate + 1] * f
    n_sec = sector_max.shape[2]
    sec_min = np.full(n_sec, np.inf)
    for j in range(n_up):
        sec_min[j // sector] = min(sec_min[j // sector], up[j])
    n_iter = dist_star.shape[1]
    for a in range(dist_star.shape[0]):
        m = n_iter
        for k in range(n_iter):
            if _blocked(dist_star[a, k], sector_max[a, k], sec_min, up, sector):
                m = k
                break
        out[a] = m


@njit(cache=True, error_model="numpy")
def _blocked(row: np.ndarray, row_max: np.ndarray, sec_min: np.ndarray, up: np.ndarray, sector: int) -> bool:
    """Some up-sampled beam has d* greater than the observed distance."""
    for q in range(row_max.shape[0]):
        if row_max[q] <= sec_min[q]:
            continue
        for j in range(q * sector, min((q + 1) * sector, up.shape[0])):
            if row[j] > up[j]:
                return True
    return False


@njit(cache=True, error_model="numpy")
def post_process(free: np.ndarray, n_iter: int, width: int, out: np.ndarray) -> None:
    """HOPE's mask post-processing of the free-pose counts ``free`` (42,) into ``out`` (module docstring)."""
    half = free.shape[0] // 2
    reduced = free.astype(np.float64)
    for g in range(2):
        reduced[g * half] -= 1.0
        reduced[g * half + half - 1] -= 1.0
    r = width // 2
    total = 0.0
    for g in range(2):
        for i in range(half):
            m = np.inf
            for d in range(-r, width - r):
                j = i + d
                if j < 0:
                    j = -j - 1
                elif j >= half:
                    j = 2 * half - j - 1
                m = min(m, reduced[g * half + j])
            v = min(max(m, 0.0), float(n_iter)) / n_iter
            out[g * half + i] = v
            total += v
    if total == 0.0:
        out[:] = MASK_FLOOR


def anchor_probabilities(mean, std, mask) -> np.ndarray:
    """(…, 42) probabilities of the masked anchor choice for Gaussian policies N(mean, std) (…, 2) and masks
    (…, 42): p_a ∝ exp(Σ_d clip(log N(anchor_{a,d}; μ_d, σ_d), −10, 10)) · mask_a (HOPE ``choose_action``)."""
    mean = np.asarray(mean, float)[..., None, :]
    std = np.asarray(std, float)[..., None, :]
    z = (anchor_actions() - mean) / std
    log_density = -0.5 * z * z - np.log(math.sqrt(2.0 * math.pi) * std)
    score = np.clip(log_density, -LOG_PROB_CLIP, LOG_PROB_CLIP).sum(-1)
    weights = np.exp(score) * np.asarray(mask, float)
    return weights / weights.sum(-1, keepdims=True)


def apply_mask(mean, std, mask, rng: np.random.Generator | None = None) -> np.ndarray:
    """The masked action (…, 2) in normalised units: an anchor drawn from `anchor_probabilities` with ``rng``
    (HOPE's training and evaluation), or the most probable anchor when ``rng`` is None (a deterministic variant).
    The agent scores the returned anchor with its own Gaussian for PPO's log-probability."""
    p = anchor_probabilities(mean, std, mask)
    flat = p.reshape(-1, N_ANCHORS)
    if rng is None:
        idx = flat.argmax(-1)
    else:
        cdf = np.cumsum(flat, -1)
        idx = np.minimum((cdf < rng.random((len(flat), 1)) * cdf[:, -1:]).sum(-1), N_ANCHORS - 1)
    return anchor_actions()[idx].reshape(p.shape[:-1] + (2,))
