"""HOPE's reward adapted to hard termination (``jiamiya/HOPE`` ``car_parking_base.py`` ``_get_reward``,
``env_wrapper.py`` ``reward_shaping``; weights REWARD_WEIGHT, ratio REWARD_RATIO of ``configs.py``), compiled.

A step that continues the episode earns ratio · (w_t r_time + w_d r_dist + w_b r_box) with

* r_time = −tanh(t / 2000), t = HOPE's step counter after this action: the action count plus one (HOPE's reset
  runs one step without an action);
* r_dist = (ρ_prev − ρ) / max(|p_start − p^g|, 10), ρ the reference-point distance to the target;
* r_box = max(IoU − IoU_best, 0), then IoU_best ← max(IoU_best, IoU): IoU of the footprint rectangle and the target
  footprint (HOPE's union_area / (2 · A − union_area) with its "union_area" the intersection and both boxes of area
  A), IoU_best starting at the start pose's IoU.

A step that ends the episode earns only ratio · its terminal reward: success +50, collision −50, boundary −50,
step budget exhausted −1 (HOPE's ARRIVED, COLLIDED, OUTBOUND, OUTTIME).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from np_sim.kernels.geometry import footprint_corners

# indices into the reward parameter array built by `reward_parameters`
(W_TIME, TIME_SCALE, W_DIST, DIST_NORM_MIN, W_BOX, R_SUCCESS, R_COLLISION, R_BOUNDARY, R_TIMEOUT, RATIO,
 N_REWARD) = range(11)


def reward_parameters(reward) -> np.ndarray:
    """The ``HopeRewardConfig`` as the float array the kernels read."""
    w = np.zeros(N_REWARD)
    w[W_TIME], w[TIME_SCALE] = reward.time_cost_weight, reward.time_scale_steps
    w[W_DIST], w[DIST_NORM_MIN] = reward.distance_weight, reward.distance_norm_min_m
    w[W_BOX] = reward.box_union_weight
    w[R_SUCCESS], w[R_COLLISION] = reward.success_reward, reward.collision_reward
    w[R_BOUNDARY], w[R_TIMEOUT] = reward.boundary_reward, reward.timeout_reward
    w[RATIO] = reward.reward_ratio
    return w


@njit(cache=True, error_model="numpy")
def _clip_half_plane(poly: np.ndarray, n: int, ax: float, ay: float, bx: float, by: float, out: np.ndarray) -> int:
    """Sutherland–Hodgman: the part of ``poly[:n]`` left of the directed line a→b into ``out``; returns its size."""
    m = 0
    for i in range(n):
        px, py = poly[i, 0], poly[i, 1]
        qx, qy = poly[(i + 1) % n, 0], poly[(i + 1) % n, 1]
        sp = (bx - ax) * (py - ay) - (by - ay) * (px - ax)
        sq = (bx - ax) * (qy - ay) - (by - ay) * (qx - ax)
        if sp >= 0.0:
            out[m, 0], out[m, 1] = px, py
            m += 1
        if (sp >= 0.0) != (sq >= 0.0):
            t = sp / (sp - sq)
            out[m, 0], out[m, 1] = px + t * (qx - px), py + t * (qy - py)
            m += 1
    return m


@njit(cache=True, error_model="numpy")
def convex_intersection_area(a: np.ndarray, b: np.ndarray) -> float:
    """Area of the intersection of two convex counter-clockwise quadrilaterals (4, 2)."""
    buf0 = np.empty((16, 2))
    buf1 = np.empty((16, 2))
    buf0[:4] = a
    n = 4
    for e in range(4):
        n = _clip_half_plane(buf0, n, b[e, 0], b[e, 1], b[(e + 1) % 4, 0], b[(e + 1) % 4, 1], buf1)
        buf0[:n] = buf1[:n]
        if n == 0:
            return 0.0
    area = 0.0
    for i in range(n):
        area += buf0[i, 0] * buf0[(i + 1) % n, 1] - buf0[(i + 1) % n, 0] * buf0[i, 1]
    return 0.5 * area


@njit(cache=True, error_model="numpy")
def box_iou(x: float, y: float, th: float, target: np.ndarray, local: np.ndarray) -> float:
    """IoU of the footprint at (x, y, θ) and the footprint at the target pose (HOPE's box-union measure)."""
    ego = np.empty((4, 2))
    goal = np.empty((4, 2))
    footprint_corners(x, y, th, local, ego)
    footprint_corners(target[0], target[1], target[2], local, goal)
    inter = convex_intersection_area(ego, goal)
    area = (local[1, 0] - local[0, 0]) * (local[2, 1] - local[1, 1])
    return inter / (2.0 * area - inter)


@njit(cache=True, error_model="numpy")
def shaping_reward(w: np.ndarray, t: float, prev_dist: float, dist: float, start_dist: float, iou: float,
                   best_iou: float) -> float:
    """ratio · (w_t r_time + w_d r_dist + w_b r_box) of a continuing step (module docstring)."""
    r_time = -math.tanh(t / w[TIME_SCALE])
    r_dist = (prev_dist - dist) / max(start_dist, w[DIST_NORM_MIN])
    r_box = max(iou - best_iou, 0.0)
    return w[RATIO] * (w[W_TIME] * r_time + w[W_DIST] * r_dist + w[W_BOX] * r_box)
