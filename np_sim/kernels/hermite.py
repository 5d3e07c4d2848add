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


@njit(cache=True)
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


@njit(cache=True)
def discrete_curvature_kernel(pts: np.ndarray, kappa0: float, kbar: np.ndarray):
    """eq:hermite-kappa on points (N, 2): fills kbar (N−2,), returns (max κ̄, Δκ_H, sampled length L_H).

    v_j = (g_{j+1} − g_j)/Δt, κ̄_j = ‖v̂_{j+1} − v̂_j‖ / (Δt ‖v_j‖), Δκ_H = |κ0 − κ̄_0| + Σ_{j≥1} |κ̄_j − κ̄_{j−1}|,
    with Δt = 1/(N−1). A zero-length step gives non-finite values (the candidate is then infeasible).
    """
    n = pts.shape[0]
    dt = 1.0 / (n - 1)
    length = 0.0
    kmax = 0.0
    dk = 0.0
    prev_ux = 0.0
    prev_uy = 0.0
    prev_speed = 0.0
    for j in range(n - 1):
        vx = (pts[j + 1, 0] - pts[j, 0]) / dt
        vy = (pts[j + 1, 1] - pts[j, 1]) / dt
        speed = math.sqrt(vx * vx + vy * vy)
        length += speed * dt
        ux = vx / speed if speed > 0.0 else np.nan
        uy = vy / speed if speed > 0.0 else np.nan
        if j >= 1:
            i = j - 1
            kb = math.sqrt((ux - prev_ux) ** 2 + (uy - prev_uy) ** 2) / (dt * prev_speed)
            kbar[i] = kb
            if i == 0:
                dk = abs(kappa0 - kb)
            else:
                dk += abs(kb - kbar[i - 1])
            if not (kb <= kmax):  # also catches NaN
                kmax = kb
        prev_ux = ux
        prev_uy = uy
        prev_speed = speed
    return kmax, dk, length


@njit(cache=True)
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
    """All candidates from the target-frame pose (x̃, ỹ, θ̃) into ``pts`` (C, N, 2, target frame) and per-candidate
    max κ̄, Δκ_H, L_H and the selection cost w_dk·Δκ_H + w_len·L_H + w_const (eq:mincost). Returns C.

    Tangents (eq:hermite): magnitude = endpoint distance × scale, along the reached heading at g(0) and the
    candidate terminal heading at g(1); negated for reverse connections.
    """
    n = basis.shape[1]
    kb = np.empty(n - 2)
    sign = 1.0 if forward else -1.0
    c0 = math.cos(tht)
    s0 = math.sin(tht)
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
                    for j in range(n):
                        pts[c, j, 0] = basis[0, j] * xt + basis[1, j] * gx + basis[2, j] * t0x + basis[3, j] * t1x
                        pts[c, j, 1] = basis[0, j] * yt + basis[2, j] * t0y + basis[3, j] * t1y
                    km, d, length = discrete_curvature_kernel(pts[c], kappa0, kb)
                    kbar_max[c] = km
                    dk[c] = d
                    lengths[c] = length
                    costs[c] = w_dk * d + w_len * length + w_const
                    c += 1
    return c


@njit(cache=True)
def candidate_valid(
    geo, k: int, cand_pts: np.ndarray, target: np.ndarray, heading_t0: float, heading_t1: float,
    forward: bool, footprint: bool, local: np.ndarray, dbasis: np.ndarray, tangents: np.ndarray,
    corners: np.ndarray,
) -> bool:
    """All N points of one candidate (target frame) are valid in scene k's world frame.

    Under the footprint convention the vehicle heading at each sample is the analytic tangent direction of
    eq:hermite (plus π when reversing). ``tangents`` holds (t0x, t0y, t1x, t1y, g0x, g0y, g1x, g1y).
    """
    rot = target[2] - 0.5 * math.pi  # target frame -> world
    cr = math.cos(rot)
    sr = math.sin(rot)
    n = cand_pts.shape[0]
    for j in range(n):
        qx = cand_pts[j, 0]
        qy = cand_pts[j, 1]
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


@njit(cache=True)
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
                           tangents, corners):
            return c
    return -1
