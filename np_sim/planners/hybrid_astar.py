"""Hybrid A* (Dolgov, Thrun, Montemerlo & Diebel 2010) and its NP-guided variant (paper §IV-B), returning a Plan.

``HybridAStar(config, convention).plan(scene, start, guide=None)`` searches from ``start`` to ``scene.target`` with
forward and reverse motion primitives — arcs (κ, l) of paper eq:arc at ``n_curvatures`` curvatures spanning
[−κ_max, κ_max] — over an (x, y, θ) lattice, with analytic Reeds–Shepp expansion checked against the scene, the
heuristic max(Reeds–Shepp length without obstacles, holonomic grid distance with obstacles), and a node and
time budget. With ``guide`` (M, 2) points of a reference path (the NeuralParker rollout), each node's priority
adds ``guide_weight`` × min(its distance to that polyline, ``guide_cap_m``) (NP-Guided A*): only the expansion order
changes, search and feasibility tests do not. ``plan_to_region`` stops at the first node within a radius of the
target (the region goal of the staged planner, paper Table ``tab:twostage``).

Every expanded arc and Reeds–Shepp piece is checked by the rule the plan is scored by (``np_sim.validate``): the
paper's ``samples_per_arc`` reference points per arc under the reference-point convention, the footprint swept
exactly (which implies the sampled footprint rule) under the footprint convention. A found plan is validated once
more with those rules before it is claimed; one that fails becomes a failure with reason 'validation: …'. The
compiled loop is ``np_sim.planners.search_kernels``.
"""

from __future__ import annotations

import math
import time
import weakref
from dataclasses import dataclass, field

import numpy as np

from np_sim.config import Convention, EpisodeConfig
from np_sim.errors import CapacityError, ConfigError
from np_sim.kernels.collision import poses_valid
from np_sim.kernels.reeds_shepp import MAX_PIECES
from np_sim.kinematics import arc_step, wrap_angle
from np_sim.plan import Plan
from np_sim.planners import search_kernels as sk
from np_sim.planners.heuristic import HolonomicGrid, holonomic_grid
from np_sim.scene import Scene
from np_sim.scene_arrays import packed_scene
from np_sim.validate import validation_failure
from np_sim.vehicle import VehicleSpec


@dataclass(frozen=True)
class HybridAStarConfig:
    """Hybrid A* parameters; each default is documented below and none was fitted to the frozen test starts."""

    vehicle: VehicleSpec = field(default_factory=VehicleSpec)
    """Footprint (footprint convention) and curvature bound κ_max of the primitives and Reeds–Shepp paths."""
    xy_resolution_m: float = 0.5
    """Lattice cell size in x and y (m)."""
    heading_bins: int = 72
    """Lattice heading bins over 2π (72 = 5°)."""
    step_m: float = 1.0
    """Arc length of every motion primitive (m); must exceed the lattice cell diagonal."""
    n_curvatures: int = 5
    """Primitive curvatures, evenly spaced over [−κ_max, κ_max] (odd, so that κ = 0 is one of them)."""
    reverse_factor: float = 1.5
    """Cost multiplier on reverse arc length."""
    gear_switch_cost_m: float = 3.0
    """Cost added per change of gear (m)."""
    steer_cost_m: float = 0.1
    """Cost per primitive at full curvature, scaled by |κ|/κ_max (m)."""
    steer_change_cost_m: float = 0.3
    """Cost per full-range curvature change between consecutive primitives, scaled by |Δκ|/κ_max (m)."""
    heuristic_weight: float = 1.5
    """Weight on h in the priority f = g + w·h (> 1 trades optimality for fewer expansions)."""
    grid_cell_m: float = 0.25
    """Cell size of the holonomic-with-obstacles heuristic grid (m)."""
    samples_per_arc: int = EpisodeConfig.samples_per_arc
    """Reference points checked along every arc under the reference-point convention: the paper's scoring rule
    (the footprint convention sweeps each arc exactly)."""
    analytic_every: int = 5
    """Try the analytic Reeds–Shepp expansion at every n-th expansion ..."""
    analytic_near_m: float = 10.0
    """... and at every expansion whose Reeds–Shepp distance to the goal is within this (m)."""
    goal_tolerance_m: float = 0.1
    """Position tolerance of success (m), spec §2."""
    goal_tolerance_deg: float = 10.0
    """Heading tolerance of success (deg), spec §2."""
    max_expanded: int = 30000
    """Node budget: expansions before giving up."""
    time_budget_s: float = 1.0
    """Wall-time budget of one query (s), checked every ``chunk_expansions`` expansions."""
    chunk_expansions: int = 256
    """Expansions between two time-budget checks."""
    guide_weight: float = 1.0
    """NP-Guided A*: weight on the node's distance to the guide path (m per m); used only when a guide is given."""
    guide_cap_m: float = 3.0
    """NP-Guided A*: the distance term saturates here (m), so a wrong guide costs a bounded detour of the search."""
    max_lattice_bytes: int = 1 << 30
    """Most memory (bytes) one scene's lattice and heuristic grid may take; a larger scene is refused up front."""

    def __post_init__(self) -> None:
        positive = ("xy_resolution_m", "step_m", "reverse_factor", "heuristic_weight", "grid_cell_m",
                    "goal_tolerance_m", "goal_tolerance_deg", "time_budget_s")
        for name in positive:
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ConfigError(f"HybridAStarConfig.{name}: expected a finite positive number, got {value!r}")
        for name in ("gear_switch_cost_m", "steer_cost_m", "steer_change_cost_m", "analytic_near_m", "guide_weight",
                     "guide_cap_m"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value >= 0):
                raise ConfigError(f"HybridAStarConfig.{name}: expected a finite number >= 0, got {value!r}")
        for name in ("heading_bins", "analytic_every", "max_expanded", "chunk_expansions", "max_lattice_bytes",
                     "samples_per_arc"):
            value = getattr(self, name)
            if not (isinstance(value, int) and value >= 1):
                raise ConfigError(f"HybridAStarConfig.{name}: expected an integer >= 1, got {value!r}")
        if not (isinstance(self.n_curvatures, int) and self.n_curvatures >= 3 and self.n_curvatures % 2 == 1):
            raise ConfigError(f"HybridAStarConfig.n_curvatures: expected an odd integer >= 3, "
                              f"got {self.n_curvatures!r}")
        if self.step_m <= math.sqrt(2.0) * self.xy_resolution_m:
            raise ConfigError(f"HybridAStarConfig.step_m: must exceed the lattice cell diagonal "
                              f"{math.sqrt(2.0) * self.xy_resolution_m:.3f} m, got {self.step_m}")

    def primitives(self) -> np.ndarray:
        """(2·n_curvatures, 2) arcs (κ, l): every curvature forward (l = step) and in reverse (l = −step)."""
        kappas = np.linspace(-self.vehicle.kappa_max, self.vehicle.kappa_max, self.n_curvatures)
        return np.array([(k, s * self.step_m) for s in (1.0, -1.0) for k in kappas])


@dataclass(frozen=True, eq=False)
class _SceneMaps:
    """What a scene needs once: packed geometry, the heuristic grid to its target and the lattice extent."""

    geometry: tuple
    grid: HolonomicGrid
    lattice: np.ndarray  # origin x, origin y, resolution
    n_lattice: np.ndarray  # nx, ny, n_headings


class HybridAStar:
    """Hybrid A* over the scene's collision convention (see the module docstring)."""

    name = "hybrid_astar"
    """Registry key (`np_sim.planners.protocol.Planner`); ``convention`` is set per instance."""

    def __init__(self, config: HybridAStarConfig | None = None, convention: Convention = "reference_point"):
        if convention not in ("reference_point", "footprint"):
            raise ConfigError(f"HybridAStar: convention must be 'reference_point' or 'footprint', got {convention!r}")
        self.config = HybridAStarConfig() if config is None else config
        if not isinstance(self.config, HybridAStarConfig):
            raise ConfigError(f"HybridAStar: config must be a HybridAStarConfig, got {type(self.config).__name__}")
        self.convention = convention
        self._maps: weakref.WeakKeyDictionary[Scene, _SceneMaps] = weakref.WeakKeyDictionary()
        self._local = self.config.vehicle.footprint_local()
        self._prims = self.config.primitives()
        c = self.config
        self._costs = np.array([c.reverse_factor, c.gear_switch_cost_m, c.steer_cost_m, c.steer_change_cost_m,
                                c.heuristic_weight])
        self._cells = (np.zeros(0, np.int64), np.zeros(0), np.zeros(0, np.int64))
        self._stamp = 0

    # ------------------------------------------------------------------------------------------------ public

    def plan(self, scene: Scene, start, guide=None) -> Plan:
        """Plan from ``start`` [x, y, θ] to ``scene.target``; ``guide`` (M, 2) world points turns on NP guidance."""
        return self._search(scene, start, self._guide(guide), region_m=0.0)

    def plan_to_region(self, scene: Scene, start, radius_m: float) -> Plan:
        """Plan from ``start`` to the first pose within ``radius_m`` of the target position (region goal).

        The heuristic is the holonomic grid distance less the radius; no analytic expansion. An empty plan with
        success when ``start`` is already inside the region.
        """
        if not (math.isfinite(radius_m) and radius_m > 0):
            raise ValueError(f"HybridAStar.plan_to_region: radius_m must be a finite positive distance, "
                             f"got {radius_m!r}")
        return self._search(scene, start, np.zeros((0, 2)), region_m=float(radius_m))

    # ------------------------------------------------------------------------------------------------ internals

    @staticmethod
    def _guide(guide) -> np.ndarray:
        if guide is None:
            return np.zeros((0, 2))
        g = np.asarray(guide, dtype=float)
        if g.ndim != 2 or g.shape[1] != 2 or len(g) == 0 or not np.all(np.isfinite(g)):
            raise ValueError(f"HybridAStar.plan: guide must be finite (M, 2) world points with M >= 1, got shape "
                             f"{g.shape}")
        return np.ascontiguousarray(g)

    def _scene_maps(self, scene: Scene) -> _SceneMaps:
        maps = self._maps.get(scene)
        if maps is None:
            c = self.config
            geo = packed_scene(scene).geometry
            b = np.asarray(scene.boundary, float)
            lo, hi = b.min(axis=0), b.max(axis=0)
            # lattice: int64 stamp, float64 g, int64 closed per (x, y, θ) cell; heuristic grid: 147 B per cell
            cells = [int(extent / c.xy_resolution_m) + 1 for extent in hi - lo]
            grid_cells = [int(extent / c.grid_cell_m) + 1 for extent in hi - lo]
            need = 24 * cells[0] * cells[1] * c.heading_bins + 147 * grid_cells[0] * grid_cells[1]
            if need > c.max_lattice_bytes:
                raise CapacityError(
                    f"{scene.name or '<scene>'}: boundary: a {hi[0] - lo[0]:g} x {hi[1] - lo[1]:g} m extent needs "
                    f"{need / 2**20:,.0f} MiB of Hybrid A* lattice and heuristic grid, over "
                    f"HybridAStarConfig.max_lattice_bytes = {c.max_lattice_bytes / 2**20:,.0f} MiB; "
                    "raise the bound or coarsen xy_resolution_m / heading_bins / grid_cell_m")
            n = np.array([int((hi[0] - lo[0]) / c.xy_resolution_m) + 1, int((hi[1] - lo[1]) / c.xy_resolution_m) + 1,
                          c.heading_bins], np.int64)
            maps = _SceneMaps(geo, holonomic_grid(geo, b, scene.target[:2], c.grid_cell_m),
                              np.array([lo[0], lo[1], c.xy_resolution_m]), n)
            self._maps[scene] = maps
        return maps

    def _cell_arrays(self, size: int):
        """Lattice bookkeeping reused across queries; a fresh stamp marks every cell unseen in O(1)."""
        if self._cells[0].shape[0] < size:
            self._cells = (np.zeros(size, np.int64), np.zeros(size), np.zeros(size, np.int64))
            self._stamp = 0
        self._stamp += 1
        return self._cells

    def _search(self, scene: Scene, start, guide: np.ndarray, region_m: float) -> Plan:
        t0 = time.perf_counter()
        c = self.config
        p = np.array(start, dtype=float)  # a writeable copy: numba compiles a read-only array as another type
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"HybridAStar.plan: start must be a finite [x, y, θ] of shape (3,), got {start!r}")
        if not isinstance(scene, Scene):
            raise TypeError(f"HybridAStar.plan: scene must be a Scene, got {type(scene).__name__}")
        maps = self._scene_maps(scene)
        footprint = self.convention == "footprint"
        if not poses_valid(maps.geometry, 0, p[None, :], footprint, self._local):
            return Plan(start=p, reason="start in collision", plan_time_s=time.perf_counter() - t0)
        goal = np.asarray(scene.target, float)
        if region_m > 0 and math.hypot(*(p[:2] - goal[:2])) <= region_m:
            return Plan(start=p, success=True, plan_time_s=time.perf_counter() - t0)

        capacity = c.max_expanded * len(self._prims) + 1
        node_pose, node_g = np.empty((capacity, 3)), np.empty(capacity)
        node_parent, node_arc, node_cell = (np.empty(capacity, np.int64), np.empty((capacity, 2)),
                                            np.empty(capacity, np.int64))
        node_exact = np.empty(capacity, np.bool_)
        node_exact[0] = True  # the start's key 0 puts it first; no other node is open yet
        heap_keys, heap_ids = np.empty(capacity), np.empty(capacity, np.int64)
        cell_stamp, cell_g, closed_stamp = self._cell_arrays(int(np.prod(maps.n_lattice)))
        start_cell = sk.lattice_cell(p[0], p[1], p[2], *maps.lattice, *maps.n_lattice)
        node_pose[0], node_g[0], node_parent[0], node_arc[0], node_cell[0] = p, 0.0, -1, (0.0, 0.0), start_cell
        cell_stamp[start_cell], cell_g[start_cell] = self._stamp, 0.0
        state = np.zeros(5, np.int64)
        state[sk.S_STAMP], state[sk.S_N_NODES] = self._stamp, 1
        state[sk.S_HEAP_SIZE] = 1
        heap_keys[0], heap_ids[0] = 0.0, 0
        rs_out = np.empty((MAX_PIECES, 2))
        grid = maps.grid
        status, node = sk.CHUNK_DONE, -1
        while status == sk.CHUNK_DONE:
            allowance = min(c.max_expanded, int(state[sk.S_EXPANDED]) + c.chunk_expansions)
            status, node = sk.expand(maps.geometry, footprint, self._local, goal, self._prims, self._costs,
                                     c.vehicle.kappa_max, c.samples_per_arc, c.goal_tolerance_m,
                                     math.radians(c.goal_tolerance_deg), region_m, maps.lattice, maps.n_lattice,
                                     grid.state, grid.origin, grid.cell_m, guide, c.guide_weight, c.guide_cap_m,
                                     c.analytic_every,
                                     c.analytic_near_m, node_pose, node_g, node_parent, node_arc, node_cell,
                                     node_exact, cell_stamp, cell_g, closed_stamp, heap_keys, heap_ids, state,
                                     allowance, rs_out)
            if status == sk.CHUNK_DONE and (state[sk.S_EXPANDED] >= c.max_expanded
                                            or time.perf_counter() - t0 > c.time_budget_s):
                break
        expanded = int(state[sk.S_EXPANDED])
        if status not in (sk.FOUND, sk.FOUND_ANALYTIC):
            reason = {sk.EXHAUSTED: "no path", sk.NODES_FULL: "node budget"}.get(status, "budget")
            return Plan(start=p, reason=reason, plan_time_s=time.perf_counter() - t0, expanded_nodes=expanded)
        chain = []
        while node_parent[node] >= 0:
            chain.append(node_arc[node].copy())
            node = node_parent[node]
        arcs = np.array(chain[::-1]).reshape(-1, 2)
        if status == sk.FOUND_ANALYTIC:
            arcs = np.concatenate([arcs, rs_out[: state[sk.S_N_RS]]])
        reason = "" if self._reached(p, arcs, goal, region_m) else "goal missed"
        if not reason:
            reason = validation_failure(scene, Plan(start=p, arcs=arcs, success=True), self.convention,
                                        c.vehicle, c.samples_per_arc)
        return Plan(start=p, arcs=arcs, success=reason == "", reason=reason, plan_time_s=time.perf_counter() - t0,
                    expanded_nodes=expanded)

    def _reached(self, start: np.ndarray, arcs: np.ndarray, goal: np.ndarray, region_m: float) -> bool:
        """The arcs end within the goal tolerance (or the region), integrated with eq:arc."""
        end = start
        for kappa, length in arcs:
            end = arc_step(end, kappa, length)
        dist = math.hypot(*(end[:2] - goal[:2]))
        if region_m > 0:
            return dist <= region_m
        return (dist <= self.config.goal_tolerance_m
                and abs(wrap_angle(end[2] - goal[2])) <= math.radians(self.config.goal_tolerance_deg))
