"""Compiled Hermite terminal connector (paper eq:hermite, eq:hermite-kappa, eq:mincost).

Candidates are built in the target frame (target at the origin, heading +y, paper eq:target-frame) and checked
in the world frame. Candidate index order: lateral offset (outer), terminal heading, start scale, end scale
(inner); the fixed connector uses scales (1, 1) only, in offset-outer, heading-inner order.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from np_sim.kernels.collision import pose_valid


@njit(cache=True, error_model="numpy")
def hermite_basis(n: int):
    """Basis values (4, n) and their t-derivatives (4, n) of eq:hermite at t_j = j/(n−1)."""
    b = np.empty((4, n))
    db = np.empty((4, n))
    for j in range(n):
        t = j / (n - 1)
        t2 = t * t
        t3 = t2 * t
        b[0, j] = 2 * t3 - 3 * t2 + 1
        b[1, j] = 3 * t2 - 2 * t3
        b[2, j] = t3 - 2 * t2 + t
        b[3, j] = t3 - t2
        db[0, j] = 6 * t2 - 6 * t
        db[1, j] = 6 * t - 6 * t2
        db[2, j] = 3 * t2 - 4 * t + 1
        db[3, j] = 3 * t2 - 2 * t
    return b, db


@njit(cache=True, error_model="numpy")
def discrete_curvature_kernel(xs: np.ndarray, ys: np.ndarray, kappa0: float, kbar: np.ndarray, seg_len: np.ndarray,
                              cx: np.ndarray, cy: np.ndarray):
    """eq:hermite-kappa on points (xs, ys) of length N: fills kbar (N−2,), returns (max κ̄, Δκ_H, length L_H).

    With chords c_j = g_{j+1} − g_j (= v_j Δt, Δt = 1/(N−1)), κ̄_j = ‖v̂_{j+1} − v̂_j‖/(Δt‖v_j‖)
    = ‖ĉ_{j+1} − ĉ_j‖/‖c_j‖ and Δκ_H = |κ0 − κ̄_0| + Σ_{j≥1}|κ̄_j − κ̄_{j−1}|. The unit-vector difference is
    evaluated without cancellation from the chords' cross product × and dot product ·, with P = ‖c_j‖‖c_{j+1}‖:
    ‖ĉ_{j+1} − ĉ_j‖² = 2×²/(P(P + ·)) when · ≥ 0, else 2(P − ·)/P (same value, two sqrt and one division per
    point instead of five). A zero-length chord gives non-finite values (the candidate is then infeasible).
    ``seg_len``, ``cx``, ``cy`` are (N−1,) scratch; the loops are simple passes so LLVM vectorises them, and the
    sums use four interleaved accumulators (a fixed order, so results are deterministic).
    """
    n = xs.shape[0]
    m = n - 1
    for j in range(m):
        dx = xs[j + 1] - xs[j]
        dy = ys[j + 1] - ys[j]
        cx[j] = dx
        cy[j] = dy
        seg_len[j] = math.sqrt(dx * dx + dy * dy)
    for j in range(m - 1):
        cross = cx[j] * cy[j + 1] - cy[j] * cx[j + 1]
        dot = cx[j] * cx[j + 1] + cy[j] * cy[j + 1]
        p = seg_len[j] * seg_len[j + 1]
        if dot >= 0.0:
            diff2 = 2.0 * cross * cross / (p * (p + dot) * seg_len[j] * seg_len[j])
        else:
            diff2 = 2.0 * (p - dot) / (p * seg_len[j] * seg_len[j])
        kbar[j] = math.sqrt(diff2)
    l0 = 0.0
    l1 = 0.0
    l2 = 0.0
    l3 = 0.0
    j = 0
    while j + 4 <= m:
        l0 += seg_len[j]
        l1 += seg_len[j + 1]
        l2 += seg_len[j + 2]
        l3 += seg_len[j + 3]
        j += 4
    while j < m:
        l0 += seg_len[j]
        j += 1
    d0 = 0.0
    d1 = 0.0
    d2 = 0.0
    d3 = 0.0
    k0 = 0.0
    k1 = 0.0
    k2 = 0.0
    k3 = 0.0
    j = 1
    while j + 4 <= m - 1:
        d0 += abs(kbar[j] - kbar[j - 1])
        d1 += abs(kbar[j + 1] - kbar[j])
        d2 += abs(kbar[j + 2] - kbar[j + 1])
        d3 += abs(kbar[j + 3] - kbar[j + 2])
        k0 = max(k0, kbar[j])
        k1 = max(k1, kbar[j + 1])
        k2 = max(k2, kbar[j + 2])
        k3 = max(k3, kbar[j + 3])
        j += 4
    while j < m - 1:
        d0 += abs(kbar[j] - kbar[j - 1])
        k0 = max(k0, kbar[j])
        j += 1
    kmax = max(max(k0, k1), max(max(k2, k3), kbar[0]))
    for j in range(m - 1):  # NaN anywhere makes the candidate infeasible
        if not kbar[j] == kbar[j]:
            kmax = np.nan
            break
    dk = abs(kappa0 - kbar[0]) + ((d0 + d1) + (d2 + d3))
    length = (l0 + l1) + (l2 + l3)
    return kmax, dk, length


@njit(cache=True, error_model="numpy")
def build_candidates(
    xt: float,
    yt: float,
    tht: float,
    forward: bool,
    kappa0: float,
    offsets: np.ndarray,
    headings: np.ndarray,
    scales0: np.ndarray,
    scales1: np.ndarray,
    basis: np.ndarray,
    w_dk: float,
    w_len: float,
    w_const: float,
    pts: np.ndarray,
    kbar_max: np.ndarray,
    dk: np.ndarray,
    lengths: np.ndarray,
    costs: np.ndarray,
) -> int:
    """All candidates from the target-frame pose (x̃, ỹ, θ̃) into ``pts`` (C, 2, N: x row, y row; target frame)
    and per-candidate max κ̄, Δκ_H, L_H and the selection cost w_dk·Δκ_H + w_len·L_H + w_const (eq:mincost).
    Returns C.

    Tangents (eq:hermite): magnitude = endpoint distance × scale, along the reached heading at g(0) and the
    candidate terminal heading at g(1); negated for reverse connections.
    """
    n = basis.shape[1]
    kb = np.empty(n - 2)
    seg_len = np.empty(n - 1)
    cx = np.empty(n - 1)
    cy = np.empty(n - 1)
    sign = 1.0 if forward else -1.0
    c0 = math.cos(tht)
    s0 = math.sin(tht)
    b0 = basis[0]
    b1 = basis[1]
    b2 = basis[2]
    b3 = basis[3]
    c = 0
    for io in range(offsets.shape[0]):
        gx = offsets[io]
        dist = math.sqrt((gx - xt) ** 2 + yt * yt)
        for ih in range(headings.shape[0]):
            c1 = math.cos(headings[ih])
            s1 = math.sin(headings[ih])
            for i0 in range(scales0.shape[0]):
                t0x = sign * scales0[i0] * dist * c0
                t0y = sign * scales0[i0] * dist * s0
                for i1 in range(scales1.shape[0]):
                    t1x = sign * scales1[i1] * dist * c1
                    t1y = sign * scales1[i1] * dist * s1
                    xs = pts[c, 0]
                    ys = pts[c, 1]
                    for j in range(n):
                        xs[j] = b0[j] * xt + b1[j] * gx + b2[j] * t0x + b3[j] * t1x
                        ys[j] = b0[j] * yt + b2[j] * t0y + b3[j] * t1y
                    km, d, length = discrete_curvature_kernel(xs, ys, kappa0, kb, seg_len, cx, cy)
                    kbar_max[c] = km
                    dk[c] = d
                    lengths[c] = length
                    costs[c] = w_dk * d + w_len * length + w_const
                    c += 1
    return c


@njit(cache=True, error_model="numpy")
def coarse_to_fine(n: int) -> np.ndarray:
    """The indices 0..n−1 ordered coarse to fine: every 32nd, then the midpoints between them, … , then the rest."""
    order = np.empty(n, np.int64)
    seen = np.zeros(n, np.bool_)
    m = 0
    stride = 32
    while stride >= 1:
        for j in range(0, n, stride):
            if not seen[j]:
                seen[j] = True
                order[m] = j
                m += 1
        stride //= 2
    return order


@njit(cache=True, error_model="numpy")
def candidate_valid(
    geo, k: int, cand_pts: np.ndarray, target: np.ndarray, heading_t0: float, heading_t1: float,
    forward: bool, footprint: bool, local: np.ndarray, dbasis: np.ndarray, tangents: np.ndarray,
    corners: np.ndarray, check_order: np.ndarray,
) -> bool:
    """All N points of one candidate (``cand_pts`` (2, N), target frame) are valid in scene k's world frame.

    Under the footprint convention the vehicle heading at each sample is the analytic tangent direction of
    eq:hermite (plus π when reversing). ``tangents`` holds (t0x, t0y, t1x, t1y, g0x, g0y, g1x, g1y). Points are
    visited in ``check_order`` (coarse to fine), which finds a collision in fewer checks; the answer is the same
    for any order.
    """
    rot = target[2] - 0.5 * math.pi  # target frame -> world
    cr = math.cos(rot)
    sr = math.sin(rot)
    for j in check_order:
        qx = cand_pts[0, j]
        qy = cand_pts[1, j]
        wx = target[0] + cr * qx - sr * qy
        wy = target[1] + sr * qx + cr * qy
        th = 0.0
        if footprint:
            dx = (dbasis[0, j] * tangents[4] + dbasis[1, j] * tangents[6] + dbasis[2, j] * tangents[0]
                  + dbasis[3, j] * tangents[2])
            dy = (dbasis[0, j] * tangents[5] + dbasis[1, j] * tangents[7] + dbasis[2, j] * tangents[1]
                  + dbasis[3, j] * tangents[3])
            if dx == 0.0 and dy == 0.0:
                th = heading_t0 if j == 0 else heading_t1
            else:
                th = math.atan2(dy, dx)
                if not forward:
                    th += math.pi
            th += rot
        if not pose_valid(geo, k, wx, wy, th, footprint, local, corners):
            return False
    return True


@njit(cache=True, error_model="numpy")
def select_candidate(
    geo,
    k: int,
    target: np.ndarray,
    xt: float,
    yt: float,
    tht: float,
    forward: bool,
    offsets: np.ndarray,
    headings: np.ndarray,
    scales0: np.ndarray,
    scales1: np.ndarray,
    dbasis: np.ndarray,
    pts: np.ndarray,
    kbar_max: np.ndarray,
    costs: np.ndarray,
    n_cand: int,
    by_cost: bool,
    kappa_max: float,
    footprint: bool,
    local: np.ndarray,
) -> int:
    """Index of the selected feasible candidate, or −1.

    ``by_cost``: candidates are tried in increasing cost (stable: ties keep index order) and the first feasible
    one is returned — the eq:mincost argmin over the feasible set, since the cost does not depend on obstacles.
    Otherwise (fixed connector) candidates are tried in index order. Feasible = max κ̄ ≤ κ_max and all points
    valid.
    """
    if by_cost:
        order = np.argsort(costs[:n_cand], kind="mergesort")
    else:
        order = np.arange(n_cand)
    n_s0 = scales0.shape[0]
    n_s1 = scales1.shape[0]
    n_h = headings.shape[0]
    sign = 1.0 if forward else -1.0
    tangents = np.empty(8)
    corners = np.empty((4, 2))
    check_order = coarse_to_fine(pts.shape[2])
    for r in range(n_cand):
        c = order[r]
        if not (kbar_max[c] <= kappa_max):
            continue
        i1 = c % n_s1
        i0 = (c // n_s1) % n_s0
        ih = (c // (n_s1 * n_s0)) % n_h
        io = c // (n_s1 * n_s0 * n_h)
        gx = offsets[io]
        dist = math.sqrt((gx - xt) ** 2 + yt * yt)
        tangents[0] = sign * scales0[i0] * dist * math.cos(tht)
        tangents[1] = sign * scales0[i0] * dist * math.sin(tht)
        tangents[2] = sign * scales1[i1] * dist * math.cos(headings[ih])
        tangents[3] = sign * scales1[i1] * dist * math.sin(headings[ih])
        tangents[4] = xt
        tangents[5] = yt
        tangents[6] = gx
        tangents[7] = 0.0
        if candidate_valid(geo, k, pts[c], target, tht, headings[ih], forward, footprint, local, dbasis,
                           tangents, corners, check_order):
            return c
    return -1
