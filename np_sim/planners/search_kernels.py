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

A successor enters the open list keyed by f with the grid term alone in place of h (``heuristic_bound``, a lower
bound: the Reeds–Shepp length is most of a node's cost to open and most opened nodes are never expanded); when it is
popped its full h is computed, and it is pushed back with the full f when that is larger. A node is therefore
expanded only when its full f is the least in the open list, the order eager evaluation gives (up to ties).

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
from np_sim.planners.heuristic import grid_distance

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
def grid_lookup(hgrid, origin_x: float, origin_y: float, cell_m: float, x: float, y: float) -> float:
    """Holonomic distance of the grid cell holding (x, y) (``hgrid``: the lazy Dijkstra state of
    ``np_sim.planners.heuristic.lazy_grid``), less one cell diagonal (so it never overestimates the distance between
    the point and the goal by discretisation); inf outside the grid."""
    col = int(math.floor((x - origin_x) / cell_m + 0.5))
    row = int(math.floor((y - origin_y) / cell_m + 0.5))
    if row < 0 or row >= hgrid[0].shape[0] or col < 0 or col >= hgrid[0].shape[1]:
        return math.inf
    return max(0.0, grid_distance(hgrid, cell_m, row, col) - math.sqrt(2.0) * cell_m)


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
              hgrid, h_origin_x: float, h_origin_y: float, h_cell_m: float) -> float:
    """h of a node: max(Reeds–Shepp length, holonomic grid distance) to the goal pose; for a region goal (radius
    ``region_m`` > 0) the grid distance less the radius."""
    hol = grid_lookup(hgrid, h_origin_x, h_origin_y, h_cell_m, x, y)
    if region_m > 0.0:
        return max(0.0, hol - region_m)
    return max(rs_length(x, y, th, gx, gy, gth, kappa_max), hol)


@njit(cache=True, error_model="numpy")
def heuristic_bound(x: float, y: float, region_m: float, hgrid, h_origin_x: float, h_origin_y: float,
                    h_cell_m: float) -> float:
    """A lower bound of ``heuristic`` that needs no Reeds–Shepp length: its grid term (all of it for a region
    goal)."""
    hol = grid_lookup(hgrid, h_origin_x, h_origin_y, h_cell_m, x, y)
    if region_m > 0.0:
        return max(0.0, hol - region_m)
    return hol


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
def goal_reached(x: float, y: float, th: float, goal: np.ndarray, tol_m: float, tol_rad: float,
                 region_m: float) -> bool:
    """The pose (x, y, θ) meets the goal: within ``region_m`` of the goal point for a region goal (``region_m`` > 0),
    otherwise within ``tol_m`` of the goal point and ``tol_rad`` of its heading."""
    dist = math.hypot(x - goal[0], y - goal[1])
    if region_m > 0.0:
        return dist <= region_m
    return dist <= tol_m and abs(wrap_angle(th - goal[2])) <= tol_rad


@njit(cache=True, error_model="numpy")
def analytic_due(x: float, y: float, th: float, goal: np.ndarray, kappa_max: float, expanded: int,
                 analytic_every: int, analytic_near_m: float) -> bool:
    """An analytic Reeds–Shepp shot is tried on every ``analytic_every``-th expansion (the 1st, the
    (analytic_every + 1)th, …) and whenever the Reeds–Shepp length to the goal is at most ``analytic_near_m``."""
    return (expanded % analytic_every == 1
            or rs_length(x, y, th, goal[0], goal[1], goal[2], kappa_max) <= analytic_near_m)


@njit(cache=True, error_model="numpy")
def successor_g(g_parent: float, parent_kappa: float, parent_len: float, kappa: float, length: float,
                costs: np.ndarray, kappa_max: float) -> float:
    """g after the arc (κ, l) from a node of cost ``g_parent`` reached by the arc (κ_parent, l_parent): plus
    |l|·(1, or the reverse factor when l < 0) + c_steer·|κ|/κ_max, and, unless the node is the start (l_parent = 0),
    the gear-switch cost when l changes sign and c_Δκ·|κ − κ_parent|/κ_max (``costs`` as in ``expand``)."""
    g = g_parent + abs(length) * (costs[0] if length < 0.0 else 1.0)
    g += costs[2] * abs(kappa) / kappa_max
    if parent_len != 0.0:
        if parent_len * length < 0.0:
            g += costs[1]
        g += costs[3] * abs(kappa - parent_kappa) / kappa_max
    return g


@njit(cache=True, error_model="numpy")
def node_priority(g: float, h: float, h_weight: float, x: float, y: float, use_guide: bool, guide: np.ndarray,
                  guide_weight: float, guide_cap_m: float) -> float:
    """f = g + w_h·h + w_g·min(d_guide, cap), the guide term only with ``use_guide`` (NP-Guided A*, paper §IV-B)."""
    f = g + h_weight * h
    if use_guide:
        f += guide_weight * min(polyline_distance(x, y, guide), guide_cap_m)
    return f


@njit(cache=True, error_model="numpy")
def store_node(k: int, x: float, y: float, th: float, g: float, parent: int, kappa: float, length: float, cell: int,
               stamp: int, node_pose: np.ndarray, node_g: np.ndarray, node_parent: np.ndarray, node_arc: np.ndarray,
               node_cell: np.ndarray, cell_stamp: np.ndarray, cell_g: np.ndarray) -> None:
    """Write node ``k`` (pose, g, parent, arc from the parent, lattice cell) and make it its cell's best open node."""
    node_pose[k, 0], node_pose[k, 1], node_pose[k, 2] = x, y, th
    node_g[k] = g
    node_parent[k] = parent
    node_arc[k, 0], node_arc[k, 1] = kappa, length
    node_cell[k] = cell
    cell_stamp[cell] = stamp
    cell_g[cell] = g


@njit(cache=True, error_model="numpy")
def push_successors(i: int, geo, footprint: bool, local: np.ndarray, goal: np.ndarray, prims: np.ndarray,
                    costs: np.ndarray, kappa_max: float, n_samples: int, region_m: float,
                    lattice: np.ndarray, n_lattice: np.ndarray,
                    hgrid, h_origin: np.ndarray, h_cell_m: float,
                    use_guide: bool, guide: np.ndarray, guide_weight: float, guide_cap_m: float,
                    node_pose: np.ndarray, node_g: np.ndarray, node_parent: np.ndarray, node_arc: np.ndarray,
                    node_cell: np.ndarray, node_exact: np.ndarray, cell_stamp: np.ndarray, cell_g: np.ndarray,
                    closed_stamp: np.ndarray, heap_keys: np.ndarray, heap_ids: np.ndarray, state: np.ndarray,
                    corners: np.ndarray, hit: np.ndarray) -> bool:
    """Open the successor of node ``i`` along each primitive whose end lies in an unclosed lattice cell, improves
    that cell's best g, passes ``arc_scored`` and has a finite h, keyed by ``heuristic_bound`` (``expand`` puts
    the full h in when it pops it); False when the node arrays are full."""
    x, y, th = node_pose[i, 0], node_pose[i, 1], node_pose[i, 2]
    parent_kappa, parent_len = node_arc[i, 0], node_arc[i, 1]
    stamp = state[S_STAMP]
    for p in range(prims.shape[0]):
        kappa, length = prims[p, 0], prims[p, 1]
        nx_, ny_, nth_ = arc_point(x, y, th, kappa, length)
        c = lattice_cell(nx_, ny_, nth_, lattice[0], lattice[1], lattice[2], n_lattice[0], n_lattice[1],
                         n_lattice[2])
        if c < 0 or closed_stamp[c] == stamp:
            continue
        g = successor_g(node_g[i], parent_kappa, parent_len, kappa, length, costs, kappa_max)
        if cell_stamp[c] == stamp and cell_g[c] <= g:
            continue
        if not arc_scored(geo, x, y, th, kappa, length, n_samples, footprint, local, corners, hit):
            continue
        h = heuristic_bound(nx_, ny_, region_m, hgrid, h_origin[0], h_origin[1], h_cell_m)
        if not math.isfinite(h):
            continue
        k = state[S_N_NODES]
        if k >= node_g.shape[0]:
            return False
        state[S_N_NODES] = k + 1
        store_node(k, nx_, ny_, nth_, g, i, kappa, length, c, stamp, node_pose, node_g, node_parent, node_arc,
                   node_cell, cell_stamp, cell_g)
        node_exact[k] = region_m > 0.0  # a region goal's h is the grid term alone
        f = node_priority(g, h, costs[4], nx_, ny_, use_guide, guide, guide_weight, guide_cap_m)
        state[S_HEAP_SIZE] = heap_push(heap_keys, heap_ids, state[S_HEAP_SIZE], f, k)
    return True


@njit(cache=True, error_model="numpy")
def expand(geo, footprint: bool, local: np.ndarray, goal: np.ndarray, prims: np.ndarray, costs: np.ndarray,
           kappa_max: float, n_samples: int, tol_m: float, tol_rad: float, region_m: float,
           lattice: np.ndarray, n_lattice: np.ndarray,
           hgrid, h_origin: np.ndarray, h_cell_m: float,
           guide: np.ndarray, guide_weight: float, guide_cap_m: float, analytic_every: int, analytic_near_m: float,
           node_pose: np.ndarray, node_g: np.ndarray, node_parent: np.ndarray, node_arc: np.ndarray,
           node_cell: np.ndarray, node_exact: np.ndarray, cell_stamp: np.ndarray, cell_g: np.ndarray,
           closed_stamp: np.ndarray, heap_keys: np.ndarray, heap_ids: np.ndarray, state: np.ndarray,
           max_expanded: int, rs_out: np.ndarray):
    """Run Hybrid A* expansions until a goal, an empty open list, ``max_expanded`` total expansions or full node
    arrays; returns (status, node).

    ``costs`` = (reverse factor, gear-switch cost m, steering cost m, steering-change cost m, heuristic weight);
    ``lattice`` = (origin x, origin y, resolution m); ``n_lattice`` = (nx, ny, n_headings); ``n_samples``: the
    reference points per arc of the paper's rule (``arc_scored``).
    """
    stamp = state[S_STAMP]
    corners = np.empty((4, 2))
    hit = np.empty(4)
    use_guide = guide_weight > 0.0 and guide.shape[0] > 0
    region_goal = region_m > 0.0
    while state[S_HEAP_SIZE] > 0:
        if state[S_EXPANDED] >= max_expanded:
            return CHUNK_DONE, -1
        key, i, size = heap_pop(heap_keys, heap_ids, state[S_HEAP_SIZE])
        state[S_HEAP_SIZE] = size
        cell = node_cell[i]
        if closed_stamp[cell] == stamp:
            continue
        if not node_exact[i]:
            # the key was a lower bound of f: with the full h, expand now only if it is still the least key
            node_exact[i] = True
            x, y, th = node_pose[i, 0], node_pose[i, 1], node_pose[i, 2]
            h = heuristic(x, y, th, goal[0], goal[1], goal[2], kappa_max, region_m, hgrid, h_origin[0], h_origin[1],
                          h_cell_m)
            f = node_priority(node_g[i], h, costs[4], x, y, use_guide, guide, guide_weight, guide_cap_m)
            if f > key:
                state[S_HEAP_SIZE] = heap_push(heap_keys, heap_ids, state[S_HEAP_SIZE], f, i)
                continue
        closed_stamp[cell] = stamp
        state[S_EXPANDED] += 1
        x, y, th = node_pose[i, 0], node_pose[i, 1], node_pose[i, 2]
        if goal_reached(x, y, th, goal, tol_m, tol_rad, region_m):
            return FOUND, i
        if not region_goal and analytic_due(x, y, th, goal, kappa_max, state[S_EXPANDED], analytic_every,
                                            analytic_near_m):
            n_rs = rs_shot(geo, x, y, th, goal[0], goal[1], goal[2], kappa_max, n_samples, footprint, local,
                           corners, hit, rs_out)
            if n_rs >= 0:
                state[S_N_RS] = n_rs
                return FOUND_ANALYTIC, i
        if not push_successors(i, geo, footprint, local, goal, prims, costs, kappa_max, n_samples, region_m,
                               lattice, n_lattice, hgrid, h_origin, h_cell_m, use_guide, guide, guide_weight,
                               guide_cap_m, node_pose, node_g, node_parent, node_arc, node_cell, node_exact,
                               cell_stamp, cell_g, closed_stamp, heap_keys, heap_ids, state, corners, hit):
            return NODES_FULL, -1
    return EXHAUSTED, -1
