"""Compiled inner loop of Hybrid A* (Dolgov, Thrun, Montemerlo & Diebel 2010, "Path planning for autonomous
vehicles in unknown semi-structured environments", IJRR 29(5)).

Nodes are continuous poses (x, y, θ) reached by motion primitives — arcs (κ, l) of paper eq:arc — and binned in an
(x, y, θ) lattice: a cell is closed once one node in it has been expanded, and keeps only its best-g open node.
Node priority f = g + w_h·h + w_g·d_guide, with

* g: Σ per arc of |l|·(1, or the reverse factor when l < 0) + gear-switch cost + c_steer·|κ|/κ_max
  + c_Δκ·|κ − κ_parent|/κ_max (metres);
* h = max(Reeds–Shepp length to the goal ignoring obstacles, holonomic grid distance with obstacles);
* d_guide: distance from the node's position to a guide polyline, saturated at a cap (NP-Guided A*, paper §IV-B),
  0 without a guide.

Every arc (primitive or analytic Reeds–Shepp piece) is checked by the rule its plan is scored by (``arc_scored``):
under the reference-point convention the env's own check at the paper's n samples per arc (``arc_valid``), under
the footprint convention the exact swept test of ``np_sim.kernels.swept``, which also implies the env's sampled
footprint check. The search state lives in caller
arrays so that ``expand`` can stop after a chunk of expansions and resume (time budget).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from np_sim.kernels.collision import arc_valid
from np_sim.kernels.kinematics import arc_point, wrap_angle
from np_sim.kernels.reeds_shepp import rs_arcs_into, rs_length
from np_sim.kernels.swept import EXACT_TOLERANCE_M, swept_arc_contact
from np_sim.planners.heap import heap_pop, heap_push

# status codes returned by ``expand``
FOUND = 0
"""A node within the goal tolerance (or region) was expanded."""
FOUND_ANALYTIC = 1
"""A collision-free Reeds–Shepp path from the returned node to the goal exists (written to ``rs_out``)."""
EXHAUSTED = 2
"""The open list is empty: no path on this lattice."""
CHUNK_DONE = 3
"""The chunk's expansion allowance is spent; call again to continue."""
NODES_FULL = 4
"""The node arrays are full."""

# indices into the int64 ``state`` array
S_HEAP_SIZE, S_N_NODES, S_EXPANDED, S_STAMP, S_N_RS = range(5)


@njit(cache=True, error_model="numpy")
def arc_scored(geo, x: float, y: float, th: float, kappa: float, length: float, n_samples: int, footprint: bool,
               local: np.ndarray, corners: np.ndarray, hit: np.ndarray) -> bool:
    """The arc (κ, l) from (x, y, θ) passes the rule its plan is scored by: the footprint swept exactly (footprint
    convention; ``hit`` is scratch) or the reference point at ``n_samples`` poses (the paper's rule)."""
    if footprint:
        contact = swept_arc_contact(geo, 0, x, y, th, kappa, length, True, local, EXACT_TOLERANCE_M, False, hit)
        return contact < 0.0
    return arc_valid(geo, 0, x, y, th, kappa, length, n_samples, False, local, corners)


@njit(cache=True, error_model="numpy")
def polyline_distance(px: float, py: float, guide: np.ndarray) -> float:
    """Euclidean distance from (px, py) to the polyline ``guide`` (M, 2) (to the point itself when M = 1)."""
    best = math.inf
    m = guide.shape[0]
    if m == 1:
        return math.hypot(px - guide[0, 0], py - guide[0, 1])
    for i in range(m - 1):
        ax, ay = guide[i, 0], guide[i, 1]
        dx, dy = guide[i + 1, 0] - ax, guide[i + 1, 1] - ay
        den = dx * dx + dy * dy
        t = 0.0 if den == 0.0 else min(1.0, max(0.0, ((px - ax) * dx + (py - ay) * dy) / den))
        d = math.hypot(px - ax - t * dx, py - ay - t * dy)
        if d < best:
            best = d
    return best


@njit(cache=True, error_model="numpy")
def grid_lookup(hgrid: np.ndarray, origin_x: float, origin_y: float, cell_m: float, x: float, y: float) -> float:
    """Holonomic distance of the grid cell holding (x, y), less one cell diagonal (so it never overestimates
    the distance between the point and the goal by discretisation); inf outside the grid."""
    col = int(math.floor((x - origin_x) / cell_m + 0.5))
    row = int(math.floor((y - origin_y) / cell_m + 0.5))
    if row < 0 or row >= hgrid.shape[0] or col < 0 or col >= hgrid.shape[1]:
        return math.inf
    return max(0.0, hgrid[row, col] - math.sqrt(2.0) * cell_m)


@njit(cache=True, error_model="numpy")
def lattice_cell(x: float, y: float, th: float, origin_x: float, origin_y: float, res_m: float, nx: int, ny: int,
                 n_headings: int) -> int:
    """Index of the (x, y, θ) lattice cell holding a pose, −1 outside the lattice."""
    ix = int(math.floor((x - origin_x) / res_m))
    iy = int(math.floor((y - origin_y) / res_m))
    if ix < 0 or ix >= nx or iy < 0 or iy >= ny:
        return -1
    it = int(math.floor((wrap_angle(th) + math.pi) / (2.0 * math.pi) * n_headings)) % n_headings
    return (iy * nx + ix) * n_headings + it


@njit(cache=True, error_model="numpy")
def heuristic(x: float, y: float, th: float, gx: float, gy: float, gth: float, kappa_max: float, region_m: float,
              hgrid: np.ndarray, h_origin_x: float, h_origin_y: float, h_cell_m: float) -> float:
    """h of a node: max(Reeds–Shepp length, holonomic grid distance) to the goal pose; for a region goal (radius
    ``region_m`` > 0) the grid distance less the radius."""
    hol = grid_lookup(hgrid, h_origin_x, h_origin_y, h_cell_m, x, y)
    if region_m > 0.0:
        return max(0.0, hol - region_m)
    return max(rs_length(x, y, th, gx, gy, gth, kappa_max), hol)


@njit(cache=True, error_model="numpy")
def rs_shot(geo, x: float, y: float, th: float, gx: float, gy: float, gth: float, kappa_max: float,
            n_samples: int, footprint: bool, local: np.ndarray, corners: np.ndarray, hit: np.ndarray,
            rs_out: np.ndarray) -> int:
    """Analytic expansion: the shortest Reeds–Shepp path to the goal, written to ``rs_out``; returns its arc count
    when every arc passes ``arc_scored``, −1 otherwise."""
    n = rs_arcs_into(x, y, th, gx, gy, gth, kappa_max, 1e-9, rs_out)
    px, py, pth = x, y, th
    for i in range(n):
        if not arc_scored(geo, px, py, pth, rs_out[i, 0], rs_out[i, 1], n_samples, footprint, local, corners, hit):
            return -1
        px, py, pth = arc_point(px, py, pth, rs_out[i, 0], rs_out[i, 1])
    return n


@njit(cache=True, error_model="numpy")
def expand(geo, footprint: bool, local: np.ndarray, goal: np.ndarray, prims: np.ndarray, costs: np.ndarray,
           kappa_max: float, n_samples: int, tol_m: float, tol_rad: float, region_m: float,
           lattice: np.ndarray, n_lattice: np.ndarray,
           hgrid: np.ndarray, h_origin: np.ndarray, h_cell_m: float,
           guide: np.ndarray, guide_weight: float, guide_cap_m: float, analytic_every: int, analytic_near_m: float,
           node_pose: np.ndarray, node_g: np.ndarray, node_parent: np.ndarray, node_arc: np.ndarray,
           node_cell: np.ndarray, cell_stamp: np.ndarray, cell_g: np.ndarray, closed_stamp: np.ndarray,
           heap_keys: np.ndarray, heap_ids: np.ndarray, state: np.ndarray, max_expanded: int,
           rs_out: np.ndarray):
    """Run Hybrid A* expansions until a goal, an empty open list, ``max_expanded`` total expansions or full node
    arrays; returns (status, node).

    ``costs`` = (reverse factor, gear-switch cost m, steering cost m, steering-change cost m, heuristic weight);
    ``lattice`` = (origin x, origin y, resolution m); ``n_lattice`` = (nx, ny, n_headings); ``n_samples``: the
    reference points per arc of the paper's rule (``arc_scored``).
    """
    gx, gy, gth = goal[0], goal[1], goal[2]
    reverse_factor, switch_cost, steer_cost, steer_change_cost, h_weight = (costs[0], costs[1], costs[2], costs[3],
                                                                            costs[4])
    ox, oy, res = lattice[0], lattice[1], lattice[2]
    nx, ny, nth = n_lattice[0], n_lattice[1], n_lattice[2]
    stamp = state[S_STAMP]
    corners = np.empty((4, 2))
    hit = np.empty(4)
    capacity = node_g.shape[0]
    use_guide = guide_weight > 0.0 and guide.shape[0] > 0
    while state[S_HEAP_SIZE] > 0:
        if state[S_EXPANDED] >= max_expanded:
            return CHUNK_DONE, -1
        _, i, size = heap_pop(heap_keys, heap_ids, state[S_HEAP_SIZE])
        state[S_HEAP_SIZE] = size
        cell = node_cell[i]
        if closed_stamp[cell] == stamp:
            continue
        closed_stamp[cell] = stamp
        state[S_EXPANDED] += 1
        x, y, th = node_pose[i, 0], node_pose[i, 1], node_pose[i, 2]
        dist = math.hypot(x - gx, y - gy)
        if region_m > 0.0:
            if dist <= region_m:
                return FOUND, i
        else:
            if dist <= tol_m and abs(wrap_angle(th - gth)) <= tol_rad:
                return FOUND, i
            if (state[S_EXPANDED] % analytic_every == 1
                    or rs_length(x, y, th, gx, gy, gth, kappa_max) <= analytic_near_m):
                n_rs = rs_shot(geo, x, y, th, gx, gy, gth, kappa_max, n_samples, footprint, local, corners, hit,
                               rs_out)
                if n_rs >= 0:
                    state[S_N_RS] = n_rs
                    return FOUND_ANALYTIC, i
        parent_len = node_arc[i, 1]
        parent_kappa = node_arc[i, 0]
        for p in range(prims.shape[0]):
            kappa, length = prims[p, 0], prims[p, 1]
            nx_, ny_, nth_ = arc_point(x, y, th, kappa, length)
            c = lattice_cell(nx_, ny_, nth_, ox, oy, res, nx, ny, nth)
            if c < 0 or closed_stamp[c] == stamp:
                continue
            g = node_g[i] + abs(length) * (reverse_factor if length < 0.0 else 1.0)
            g += steer_cost * abs(kappa) / kappa_max
            if parent_len != 0.0:
                if parent_len * length < 0.0:
                    g += switch_cost
                g += steer_change_cost * abs(kappa - parent_kappa) / kappa_max
            if cell_stamp[c] == stamp and cell_g[c] <= g:
                continue
            if not arc_scored(geo, x, y, th, kappa, length, n_samples, footprint, local, corners, hit):
                continue
            h = heuristic(nx_, ny_, nth_, gx, gy, gth, kappa_max, region_m, hgrid, h_origin[0], h_origin[1], h_cell_m)
            if not math.isfinite(h):
                continue
            k = state[S_N_NODES]
            if k >= capacity:
                return NODES_FULL, -1
            state[S_N_NODES] = k + 1
            node_pose[k, 0], node_pose[k, 1], node_pose[k, 2] = nx_, ny_, nth_
            node_g[k] = g
            node_parent[k] = i
            node_arc[k, 0], node_arc[k, 1] = kappa, length
            node_cell[k] = c
            cell_stamp[c] = stamp
            cell_g[c] = g
            f = g + h_weight * h
            if use_guide:
                f += guide_weight * min(polyline_distance(nx_, ny_, guide), guide_cap_m)
            state[S_HEAP_SIZE] = heap_push(heap_keys, heap_ids, state[S_HEAP_SIZE], f, k)
    return EXHAUSTED, -1

