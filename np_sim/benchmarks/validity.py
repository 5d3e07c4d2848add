"""The four validity checks every shipped benchmark scene passes (paper §IV-A "Scenario Design", spec §4).

1. **target validity** — the scene's geometry is well formed (`Scene.validate`) and the target footprint is
   strictly inside the boundary and disjoint from every obstacle;
2. **object capacity** — at most 20 obstacles of at most 8 vertices and at most 10 boundary segments
   (`SceneCapacity()`, a circle counts as its octagon);
3. **connected start** — on the footprint-inflated 1.5 m grid (`np_sim.geodesic.geodesic_grid`) the start
   region and the target share one free component: at least ``min_reachable_fraction`` of the free cells whose
   centres lie in the start region are reachable from the target's cell, and (when given) every start's own
   cell is reachable;
4. **analytic feasibility** — some *approach pose* reaches the target through the Hermite ensemble
   (`np_sim.hermite.connect`, paper §III-D): poses ``d`` metres ahead of or behind the target along its axis
   (ỹ = ±d in the target frame), ``o`` metres to the side (x̃ = o) and rotated by ``h`` from the target heading,
   tried in the order d (near first), side of the target (ahead first), o, h; the first one that is
   footprint-free, lies in a reachable grid cell and has a feasible connection (under
   ``feasibility_convention``, by default the stricter full-footprint convention, which implies the paper's
   reference-point one) passes the check.

A generator regenerates a draw that fails any check (next sub-seed) and counts the failure under the check's
name; nothing failing is ever shipped.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from np_sim.benchmarks.common import region_cells
from np_sim.collision import path_valid
from np_sim.config import Convention
from np_sim.errors import CapacityError, SceneError
from np_sim.frames import from_target_frame
from np_sim.geodesic import GeodesicGrid, geodesic_grid
from np_sim.hermite import Connection, connect
from np_sim.scene import Scene, SceneCapacity
from np_sim.vehicle import VehicleSpec

CHECK_NAMES = ("target_validity", "object_capacity", "connected_start", "analytic_feasibility")
"""The four checks in the order they run."""


@dataclass(frozen=True)
class ValidityConfig:
    """Thresholds of the four validity checks (paper §IV-A)."""

    capacity: SceneCapacity = field(default_factory=SceneCapacity)
    """Object-capacity limits (20 obstacles × 8 vertices, 10 boundary segments)."""
    cell_m: float = 1.5
    """Cell size of the footprint-inflated geodesic grid (m)."""
    min_reachable_fraction: float = 0.9
    """Least fraction of the start region's free cells that must be reachable from the target's cell."""
    min_region_cells: int = 3
    """Least number of free cells with centres inside the start region."""
    approach_distances_m: tuple[float, ...] = (3.0, 4.5, 6.0, 7.5)
    """Distances |ỹ| of the approach poses from the target along its axis (m)."""
    approach_offsets_m: tuple[float, ...] = (0.0, -1.0, 1.0, -2.0, 2.0, -3.0, 3.0)
    """Lateral offsets x̃ of the approach poses (m)."""
    approach_headings_deg: tuple[float, ...] = (0.0, -10.0, 10.0, -20.0, 20.0)
    """Heading offsets of the approach poses from the target heading (deg)."""
    connector_mode: str = "ensemble"
    """Hermite connector used for analytic feasibility ('ensemble': 81 candidates)."""
    feasibility_convention: Convention = "footprint"
    """Collision convention of the feasibility connection ('footprint' implies 'reference_point')."""


@dataclass(frozen=True)
class CheckResult:
    """Outcome of one validity check."""

    name: str
    """One of `CHECK_NAMES`."""
    passed: bool
    """Whether the scene passed."""
    detail: str = ""
    """Why it failed, or what made it pass (e.g. the approach pose)."""


def check_target_validity(scene: Scene, vehicle: VehicleSpec | None = None) -> CheckResult:
    """Check 1 (paper §IV-A target validity): well-formed geometry and a footprint-free target."""
    try:
        scene.validate(source=scene.name or "<scene>", vehicle=vehicle)
    except SceneError as error:
        return CheckResult("target_validity", False, str(error))
    return CheckResult("target_validity", True)


def check_object_capacity(scene: Scene, capacity: SceneCapacity | None = None) -> CheckResult:
    """Check 2 (paper §IV-A object capacity): the scene fits ``capacity`` (default `SceneCapacity()`)."""
    try:
        scene.check_capacity(SceneCapacity() if capacity is None else capacity, source=scene.name or "<scene>")
    except CapacityError as error:
        return CheckResult("object_capacity", False, str(error))
    return CheckResult("object_capacity", True)


def reachable(grid: GeodesicGrid, xy) -> np.ndarray:
    """Bool array (...,): the grid cell holding each world point (..., 2) has a finite geodesic distance."""
    return np.isfinite(grid.distance_at(np.asarray(xy, float)))


def region_reachability(scene: Scene, grid: GeodesicGrid) -> tuple[int, int]:
    """(free cells with centres in the start region, of which reachable from the target); the whole boundary
    stands for a missing start region."""
    region = scene.start_region if scene.start_region is not None else scene.boundary
    rows, cols = region_cells(grid, region)
    free = grid.free[rows, cols]
    n_free = int(free.sum())
    n_reach = int(np.isfinite(grid.distance[rows[free], cols[free]]).sum())
    return n_free, n_reach


def check_connected_start(scene: Scene, grid: GeodesicGrid, config: ValidityConfig | None = None,
                          starts=None) -> CheckResult:
    """Check 3 (paper §IV-A connected start) on the footprint-inflated grid ``grid`` of ``scene``.

    Passes when the start region holds at least ``min_region_cells`` free cells, at least
    ``min_reachable_fraction`` of them are reachable from the target, and every row of ``starts`` (n, ≥2),
    when given, lies in a reachable cell.
    """
    config = ValidityConfig() if config is None else config
    n_free, n_reach = region_reachability(scene, grid)
    if n_free < config.min_region_cells:
        return CheckResult("connected_start", False,
                           f"start region holds {n_free} free grid cells, expected >= {config.min_region_cells}")
    fraction = n_reach / n_free
    if fraction < config.min_reachable_fraction:
        return CheckResult("connected_start", False,
                           f"{n_reach} of {n_free} start-region cells reachable ({fraction:.2f} < "
                           f"{config.min_reachable_fraction})")
    if starts is not None:
        s = np.asarray(starts, float).reshape(-1, np.shape(starts)[-1])
        ok = reachable(grid, s[:, :2])
        if not ok.all():
            bad = int(np.flatnonzero(~ok)[0])
            return CheckResult("connected_start", False, f"start {bad} {s[bad].tolist()} lies in an unreachable cell")
    return CheckResult("connected_start", True, f"{n_reach}/{n_free} start-region cells reachable")


def approach_poses(scene: Scene, config: ValidityConfig | None = None) -> np.ndarray:
    """(n, 3) world-frame approach poses in the order `check_analytic_feasibility` tries them."""
    config = ValidityConfig() if config is None else config
    target = np.asarray(scene.target, float)
    rows = []
    for d in config.approach_distances_m:
        for side in (1.0, -1.0):
            for o in config.approach_offsets_m:
                for h in config.approach_headings_deg:
                    xy = from_target_frame(np.array([o, side * d]), target)
                    rows.append([xy[0], xy[1], target[2] + math.radians(h)])
    return np.array(rows)


def find_approach(scene: Scene, grid: GeodesicGrid | None = None, config: ValidityConfig | None = None,
                  vehicle: VehicleSpec | None = None) -> tuple[np.ndarray, Connection] | None:
    """The first approach pose (see the module docstring) with a feasible Hermite connection, and that
    connection; None when there is none (paper §IV-A analytic feasibility)."""
    config = ValidityConfig() if config is None else config
    grid = geodesic_grid(scene, cell_m=config.cell_m, vehicle=vehicle) if grid is None else grid
    for pose in approach_poses(scene, config):
        if not reachable(grid, pose[:2]):
            continue
        if not path_valid(scene, pose[None], "footprint", vehicle):
            continue
        connection = connect(scene, pose, 0.0, config.connector_mode, convention=config.feasibility_convention,
                             vehicle=vehicle)
        if connection is not None:
            return pose, connection
    return None


def check_analytic_feasibility(scene: Scene, grid: GeodesicGrid, config: ValidityConfig | None = None,
                               vehicle: VehicleSpec | None = None) -> CheckResult:
    """Check 4 (paper §IV-A analytic feasibility): some approach pose connects through the Hermite ensemble."""
    found = find_approach(scene, grid, config, vehicle)
    if found is None:
        return CheckResult("analytic_feasibility", False, "no approach pose connects to the target")
    pose, connection = found
    return CheckResult("analytic_feasibility", True,
                       f"approach {np.round(pose, 3).tolist()} connects "
                       f"({'forward' if connection.forward else 'reverse'},"
                       f" L_H = {connection.length:.2f} m)")


def run_checks(scene: Scene, config: ValidityConfig | None = None, grid: GeodesicGrid | None = None,
               starts=None, vehicle: VehicleSpec | None = None, stop_at_first: bool = True) -> list[CheckResult]:
    """Run the four checks in `CHECK_NAMES` order (paper §IV-A); with ``stop_at_first`` the list ends at the first
    failure. The grid is built when not given (and only once the first two checks pass)."""
    config = ValidityConfig() if config is None else config
    results = [check_target_validity(scene, vehicle)]
    if stop_at_first and not results[-1].passed:
        return results
    results.append(check_object_capacity(scene, config.capacity))
    if stop_at_first and not results[-1].passed:
        return results
    if grid is None:
        grid = geodesic_grid(scene, cell_m=config.cell_m, vehicle=vehicle)
    results.append(check_connected_start(scene, grid, config, starts))
    if stop_at_first and not results[-1].passed:
        return results
    results.append(check_analytic_feasibility(scene, grid, config, vehicle))
    return results


def first_failure(results: list[CheckResult]) -> CheckResult | None:
    """The first failed result of `run_checks`, or None when all passed."""
    return next((r for r in results if not r.passed), None)
