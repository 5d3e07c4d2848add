"""The compiled batched step of the adapted HOPE environment (paper App. B): one call advances every env.

Per env: take the next Reeds–Shepp takeover chunk if one is queued, else the policy's arc; execute it with the
project's arc kinematics (paper eq:arc) checked at ``samples_per_arc`` reference points; hard collision or boundary
failure terminates; else direct success (0.1 m, 10°) or the gated fixed-Hermite terminator (paper eq:hermite …
eq:hermite-kappa, first feasible of nine) ends the episode in success; else the step budget truncates; else HOPE's
shaping reward is paid and, near the target, the RS takeover searches a path. Then the observation is written.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from hope_policy import reward as W
from hope_policy.action_mask import MASK_SECTOR, free_poses, post_process
from hope_policy.observation import signed_clearance, target_representation
from hope_policy.takeover import find_takeover
from np_sim.kernels.collision import arc_valid, pose_valid
from np_sim.kernels.geometry import INSIDE, footprint_corners, point_in_polygon, polygon_edges_cross
from np_sim.kernels.hermite import build_candidates, select_candidate
from np_sim.kernels.kinematics import arc_point, wrap_angle

# --- indices into P -------------------------------------------------------------------------------------------
(P_KAPPA_MAX, P_MAX_LEN, P_SAMPLES, P_MAX_STEPS, P_POS_TOL, P_HEAD_TOL, P_CONN_KAPPA_MAX, P_SEL_DK, P_SEL_LEN,
 P_SEL_CONST, P_FOOTPRINT, P_ENSEMBLE, P_GATE, P_LIDAR_RANGE, P_RS_ON, P_RS_DIST, P_RS_SPACING, P_RS_RATIO,
 P_MASK_ON, P_MASK_RATE, P_MASK_WIDTH, P_SIZE) = range(22)

# --- per-env state columns ------------------------------------------------------------------------------------
(S_X, S_Y, S_TH, S_SCENE, S_STEPS, S_START_DIST, S_BEST_IOU, S_PREV_KAPPA, S_RS_LEN, S_RS_POS, S_SIZE) = range(11)

# --- per-env step outputs -------------------------------------------------------------------------------------
(R_REWARD, R_TERMINATED, R_TRUNCATED, R_SUCCESS, R_COLLISION, R_OUT_OF_BOUNDS, R_RS_STEP, R_RS_FOUND, R_HERMITE,
 R_H_LEN, R_H_DK, R_H_FORWARD, R_KAPPA, R_LENGTH, R_SIZE) = range(15)


@njit(cache=True, error_model="numpy")
def outside_boundary(geo, k: int, x: float, y: float, th: float, footprint: bool, local: np.ndarray) -> bool:
    """The pose leaves scene k's boundary: the reference point (or a footprint corner or edge) not strictly inside."""
    if not footprint:
        return point_in_polygon(x, y, geo[0][k], geo[1][k]) != INSIDE
    corners = np.empty((4, 2))
    footprint_corners(x, y, th, local, corners)
    for i in range(4):
        if point_in_polygon(corners[i, 0], corners[i, 1], geo[0][k], geo[1][k]) != INSIDE:
            return True
    return polygon_edges_cross(corners, 4, geo[0][k], geo[1][k])


@njit(cache=True, error_model="numpy")
def first_failure_outside(geo, k, x, y, th, kappa, length, n, footprint, local) -> bool:
    """Whether the first failing sample of the arc (checked as ``arc_valid`` does) is a boundary failure."""
    corners = np.empty((4, 2))
    for j in range(n):
        px, py, pth = arc_point(x, y, th, kappa, length * (j + 1) / n)
        if not pose_valid(geo, k, px, py, pth, footprint, local, corners):
            return outside_boundary(geo, k, px, py, pth, footprint, local)
    return False


@njit(cache=True, error_model="numpy")
def connect(geo, k, target, x, y, th, kappa, P, local, offsets, headings, scales0, scales1, basis, dbasis, pts,
            kbar_max, dk, lengths, costs):
    """The gated Hermite terminator from the reached pose: (candidate index or −1, forward) — the connector of the
    benchmark env (paper §III-D): target-frame pose (eq:target-frame), gate sin θ̃ > 0, forward when ỹ < 0."""
    a = 0.5 * math.pi - target[2]
    dx, dy = x - target[0], y - target[1]
    xt = math.cos(a) * dx - math.sin(a) * dy
    yt = math.sin(a) * dx + math.cos(a) * dy
    tht = wrap_angle(th - target[2] + 0.5 * math.pi)
    if P[P_GATE] > 0.0 and not math.sin(tht) > 0.0:
        return -1, True
    forward = yt < 0.0
    n_cand = build_candidates(xt, yt, tht, forward, kappa, offsets, headings, scales0, scales1, basis, P[P_SEL_DK],
                              P[P_SEL_LEN], P[P_SEL_CONST], pts, kbar_max, dk, lengths, costs)
    h = select_candidate(geo, k, target, xt, yt, tht, forward, offsets, headings, scales0, scales1, dbasis, pts,
                         kbar_max, costs, n_cand, P[P_ENSEMBLE] > 0.0, P[P_CONN_KAPPA_MAX], P[P_FOOTPRINT] > 0.0,
                         local)
    return h, forward


@njit(cache=True, error_model="numpy")
def observe_one(geo, k, x, y, th, target, P, b_ranges, off_c, off_s, tables, lidar, tgt, mask) -> None:
    """Signed LiDAR clearances, target representation and (when on) the action mask at the pose."""
    distances = np.empty(b_ranges.shape[0])
    signed_clearance(x, y, th, geo[8][k], geo[9][k], off_c, off_s, P[P_LIDAR_RANGE], b_ranges, distances, lidar)
    target_representation(x, y, th, target, tgt)
    if P[P_MASK_ON] > 0.0:
        free = np.empty(mask.shape[0], np.int64)
        dist_star, sector_max = tables
        free_poses(distances, b_ranges, P[P_LIDAR_RANGE], dist_star, sector_max, MASK_SECTOR, int(P[P_MASK_RATE]),
                   free)
        post_process(free, dist_star.shape[1], int(P[P_MASK_WIDTH]), mask)


@njit(parallel=True, cache=True, error_model="numpy")
def observe_batch(geo, targets, S, P, env_ids, b_ranges, off_c, off_s, tables, lidar, tgt, mask) -> None:
    """Observations of the envs ``env_ids`` at their current poses (after resets)."""
    for r in prange(env_ids.shape[0]):
        i = env_ids[r]
        k = int(S[i, S_SCENE])
        observe_one(geo, k, S[i, S_X], S[i, S_Y], S[i, S_TH], targets[k], P, b_ranges, off_c, off_s, tables,
                    lidar[i], tgt[i], mask[i])


@njit(cache=True, error_model="numpy")
def _outcome(geo, k, target, S_row, P, W_row, local, kappa, length, x, y, th, hermite_args, R_row) -> None:
    """Termination, success and reward of the executed arc (module docstring); fills ``R_row``."""
    footprint = P[P_FOOTPRINT] > 0.0
    n = int(P[P_SAMPLES])
    valid = arc_valid(geo, k, x, y, th, kappa, length, n, footprint, local, np.empty((4, 2)))
    nx, ny, nth = arc_point(x, y, th, kappa, length)
    S_row[S_X], S_row[S_Y], S_row[S_TH] = nx, ny, nth
    S_row[S_STEPS] += 1.0
    R_row[R_HERMITE] = -1.0
    if not valid:
        out = first_failure_outside(geo, k, x, y, th, kappa, length, n, footprint, local)
        R_row[R_OUT_OF_BOUNDS] = 1.0 if out else 0.0
        R_row[R_COLLISION] = 1.0
        R_row[R_REWARD] = W_row[W.RATIO] * (W_row[W.R_BOUNDARY] if out else W_row[W.R_COLLISION])
        R_row[R_TERMINATED] = 1.0
        return
    dist = math.sqrt((nx - target[0]) ** 2 + (ny - target[1]) ** 2)
    success = dist <= P[P_POS_TOL] and abs(wrap_angle(nth - target[2])) <= P[P_HEAD_TOL]
    if not success:
        offsets, headings, scales0, scales1, basis, dbasis, pts, kbar_max, dk, lengths, costs = hermite_args
        h, forward = connect(geo, k, target, nx, ny, nth, kappa, P, local, offsets, headings, scales0, scales1,
                             basis, dbasis, pts, kbar_max, dk, lengths, costs)
        if h >= 0:
            success = True
            R_row[R_HERMITE], R_row[R_H_LEN], R_row[R_H_DK] = h, lengths[h], dk[h]
            R_row[R_H_FORWARD] = 1.0 if forward else -1.0
    if success:
        R_row[R_SUCCESS] = 1.0
        R_row[R_TERMINATED] = 1.0
        R_row[R_REWARD] = W_row[W.RATIO] * W_row[W.R_SUCCESS]
    elif S_row[S_STEPS] >= P[P_MAX_STEPS]:
        R_row[R_TRUNCATED] = 1.0
        R_row[R_REWARD] = W_row[W.RATIO] * W_row[W.R_TIMEOUT]
    else:
        prev = math.sqrt((x - target[0]) ** 2 + (y - target[1]) ** 2)
        iou = W.box_iou(nx, ny, nth, target, local)
        R_row[R_REWARD] = W.shaping_reward(W_row, S_row[S_STEPS] + 1.0, prev, dist, S_row[S_START_DIST], iou,
                                           S_row[S_BEST_IOU])
        S_row[S_BEST_IOU] = max(S_row[S_BEST_IOU], iou)


@njit(parallel=True, cache=True, error_model="numpy")
def step_batch(geo, targets, S, P, W_row, arcs, local, queue, b_ranges, off_c, off_s, tables, offsets, headings,
               scales0, scales1, basis, dbasis, pts, kbar_max, dk, lengths, costs, lidar, tgt, mask, R) -> None:
    """Advance every env i by its arc ``arcs[i]`` = (κ, l) (or its queued takeover chunk); fills R and the
    observation arrays. ``pts`` … ``costs`` are per-env Hermite scratch (leading axis = env)."""
    for i in prange(S.shape[0]):
        k = int(S[i, S_SCENE])
        target = targets[k]
        R[i, :] = 0.0
        if S[i, S_RS_POS] < S[i, S_RS_LEN]:
            j = int(S[i, S_RS_POS])
            kappa, length = queue[i, j, 0], queue[i, j, 1]
            S[i, S_RS_POS] += 1.0
            R[i, R_RS_STEP] = 1.0
        else:
            kappa, length = arcs[i, 0], arcs[i, 1]
        R[i, R_KAPPA], R[i, R_LENGTH] = kappa, length
        x, y, th = S[i, S_X], S[i, S_Y], S[i, S_TH]
        hermite_args = (offsets, headings, scales0, scales1, basis, dbasis, pts[i], kbar_max[i], dk[i], lengths[i],
                        costs[i])
        _outcome(geo, k, target, S[i], P, W_row, local, kappa, length, x, y, th, hermite_args, R[i])
        S[i, S_PREV_KAPPA] = kappa
        nx, ny, nth = S[i, S_X], S[i, S_Y], S[i, S_TH]
        done = R[i, R_TERMINATED] > 0.0 or R[i, R_TRUNCATED] > 0.0
        if (not done and P[P_RS_ON] > 0.0 and S[i, S_RS_POS] >= S[i, S_RS_LEN]
                and math.sqrt((nx - target[0]) ** 2 + (ny - target[1]) ** 2) < P[P_RS_DIST]):
            m = find_takeover(geo, k, nx, ny, nth, target, P[P_KAPPA_MAX], P[P_RS_SPACING], P[P_RS_RATIO],
                              P[P_FOOTPRINT] > 0.0, local, P[P_MAX_LEN], queue[i])
            S[i, S_RS_LEN], S[i, S_RS_POS] = m, 0.0
            R[i, R_RS_FOUND] = 1.0 if m > 0 else 0.0
        observe_one(geo, k, nx, ny, nth, target, P, b_ranges, off_c, off_s, tables, lidar[i], tgt[i], mask[i])
