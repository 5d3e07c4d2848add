"""Geometry shared by the benchmark generators (paper §IV-A "Scenario Design"): shapes, irregular boundaries,
clutter placement, start-region selection by geodesic band, and the millimetre rounding that makes the shipped
files reproducible byte for byte.

Every function takes an explicit ``numpy.random.Generator``; nothing here prints or touches global state.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import LineString, Point
from shapely.geometry import Polygon as ShapelyPolygon
from shapely.ops import unary_union

from np_sim.frames import from_target_frame
from np_sim.geodesic import GeodesicGrid, geodesic_grid
from np_sim.scene import CircleObstacle, Obstacle, PolygonObstacle, Scene
from np_sim.vehicle import VehicleSpec

COORD_DECIMALS = 3
"""Shipped coordinates are rounded to this many decimals (millimetres) before any check runs."""


class DraftRejected(Exception):
    """A generator draw that cannot become a valid scene; ``check`` names the rejection counter it feeds."""

    def __init__(self, check: str, detail: str = ""):
        super().__init__(f"{check}: {detail}" if detail else check)
        self.check = check
        self.detail = detail


# ---------------------------------------------------------------------------------------------- shapes


def rectangle(cx: float, cy: float, length_m: float, width_m: float, angle_rad: float = 0.0) -> np.ndarray:
    """(4, 2) counter-clockwise corners of a rectangle centred at (cx, cy), ``length_m`` along ``angle_rad``
    (parked cars, carts, pillars of the paper §IV-A scenes)."""
    c, s = math.cos(angle_rad), math.sin(angle_rad)
    hl, hw = 0.5 * length_m, 0.5 * width_m
    local = np.array([[-hl, -hw], [hl, -hw], [hl, hw], [-hl, hw]])
    return np.stack([cx + c * local[:, 0] - s * local[:, 1], cy + s * local[:, 0] + c * local[:, 1]], axis=1)


def box(x0: float, y0: float, x1: float, y1: float) -> np.ndarray:
    """(4, 2) counter-clockwise corners of the axis-aligned box [x0, x1] × [y0, y1] (paper §IV-A layouts)."""
    return np.array([[x0, y0], [x1, y0], [x1, y1], [x0, y1]], float)


def blob(rng: np.random.Generator, cx: float, cy: float, radius_m: float, n_vertices: int,
         irregularity: float = 0.35) -> np.ndarray:
    """(n, 2) star-shaped (hence simple) irregular polygon around (cx, cy): sorted random angles, radii in
    ``radius_m · [1 − irregularity, 1]`` (the "irregular clutter" of paper §IV-A)."""
    gaps = rng.uniform(0.6, 1.4, n_vertices)
    angles = rng.uniform(0, 2 * math.pi) + 2 * math.pi * np.cumsum(gaps) / gaps.sum()
    radii = radius_m * rng.uniform(1.0 - irregularity, 1.0, n_vertices)
    return np.stack([cx + radii * np.cos(angles), cy + radii * np.sin(angles)], axis=1)


def obstacle_geometry(obstacle: Obstacle):
    """Shapely geometry of an obstacle (a circle as a 64-gon buffer of its centre), for generator geometry tests."""
    if isinstance(obstacle, PolygonObstacle):
        return ShapelyPolygon(obstacle.vertices)
    return Point(obstacle.center).buffer(obstacle.radius, 16)


def union_of(obstacles) -> shapely.Geometry:
    """Union of the obstacles' shapely geometries (empty polygon when there are none), for generator checks."""
    geoms = [obstacle_geometry(o) for o in obstacles]
    return unary_union(geoms) if geoms else ShapelyPolygon()


def to_world(points, target_world) -> np.ndarray:
    """Target-frame points (..., 2) to the world frame of a target pose (paper §III-B eq:target-frame, inverse)."""
    return from_target_frame(np.asarray(points, float), np.asarray(target_world, float))


# ---------------------------------------------------------------------------------------------- boundaries


def irregular_boundary(rng: np.random.Generator, corners: np.ndarray, protected, n_segments: int,
                       chamfer_m: tuple[float, float] = (1.5, 5.0), notch_depth_m: tuple[float, float] = (1.0, 2.5),
                       notch_width_m: tuple[float, float] = (3.0, 8.0), jitter_m: float = 0.0,
                       straight_edges: tuple[int, ...] = (), max_tries: int = 60) -> np.ndarray:
    """Make a simple polygon with (at most) ``n_segments`` segments from the convex ``corners`` ring by cutting
    corners (chamfers: +1 segment), denting edges (trapezoidal notches: +4 segments) and jittering vertices,
    keeping ``protected`` (shapely geometry) strictly inside (paper §IV-A boundary irregularity).

    The bounding box of ``corners`` is kept exactly (every change keeps at least one vertex on each of its four
    sides), so a target placed on the 1.5 m lattice from the box's corner stays on a geodesic-grid cell centre.

    Edges listed in ``straight_edges`` (indices into ``corners``' edges, edge i from corner i to i+1) are never
    dented and their end corners never cut (e.g. the kerb a parking row stands on).
    """
    ring = [tuple(p) for p in np.asarray(corners, float)]
    protected = protected.intersection(ShapelyPolygon(corners).buffer(-0.01))
    fixed = {tuple(corners[i % len(corners)]) for e in straight_edges for i in (e, e + 1)}
    fixed_edges = {(tuple(corners[e]), tuple(corners[(e + 1) % len(corners)])) for e in straight_edges}

    lo, hi = np.min(corners, axis=0), np.max(corners, axis=0)

    def ok(candidate: list[tuple[float, float]]) -> bool:
        pts = np.array(candidate)
        if not (np.array_equal(pts.min(axis=0), lo) and np.array_equal(pts.max(axis=0), hi)):
            return False
        poly = ShapelyPolygon(candidate)
        return poly.is_valid and poly.contains(protected)

    tries = 0
    while len(ring) < n_segments and tries < max_tries:
        tries += 1
        room = n_segments - len(ring)
        if room >= 4 and rng.random() < 0.4:
            i = int(rng.integers(len(ring)))
            a, b = np.array(ring[i]), np.array(ring[(i + 1) % len(ring)])
            if (ring[i], ring[(i + 1) % len(ring)]) in fixed_edges:
                continue
            edge = b - a
            length = float(np.hypot(*edge))
            width = rng.uniform(*notch_width_m)
            if length < width + 4.0:
                continue
            u = edge / length
            inward = np.array([-u[1], u[0]])
            if ShapelyPolygon(ring).exterior.is_ccw is False:
                inward = -inward
            s0 = rng.uniform(2.0, length - width - 2.0)
            depth = rng.uniform(*notch_depth_m)
            taper = rng.uniform(0.0, 0.3) * width
            p0, p3 = a + u * s0, a + u * (s0 + width)
            p1, p2 = p0 + u * taper + inward * depth, p3 - u * taper + inward * depth
            candidate = ring[: i + 1] + [tuple(p) for p in (p0, p1, p2, p3)] + ring[i + 1:]
        else:
            i = int(rng.integers(len(ring)))
            if ring[i] in fixed:
                continue
            v = np.array(ring[i])
            prev, nxt = np.array(ring[i - 1]), np.array(ring[(i + 1) % len(ring)])
            c = rng.uniform(*chamfer_m)
            if np.hypot(*(prev - v)) < 2 * c + 1 or np.hypot(*(nxt - v)) < 2 * c + 1:
                continue
            pa = v + c * (prev - v) / np.hypot(*(prev - v)) * rng.uniform(0.6, 1.4)
            pb = v + c * (nxt - v) / np.hypot(*(nxt - v)) * rng.uniform(0.6, 1.4)
            candidate = ring[:i] + [tuple(pa), tuple(pb)] + ring[i + 1:]
        if ok(candidate):
            ring = candidate
    if jitter_m > 0:
        for i in range(len(ring)):
            if ring[i] in fixed:
                continue
            candidate = list(ring)
            candidate[i] = tuple(np.clip(np.array(ring[i]) + rng.uniform(-jitter_m, jitter_m, 2), lo, hi))
            if ok(candidate):
                ring = candidate
    return np.array(ring, float)


# ---------------------------------------------------------------------------------------------- clutter


@dataclass(frozen=True)
class ClutterSpec:
    """How random clutter is drawn (paper §IV-A "irregular clutter")."""

    gap_m: float = 2.6
    """Least distance from a clutter item to every other obstacle (a passable lane for the 1.942 m car)."""
    wall_gap_m: float = 0.6
    """Least distance from a clutter item to the boundary."""
    blob_radius_m: tuple[float, float] = (0.6, 1.6)
    """Radius range of irregular 5–8-vertex polygons (m)."""
    weights: tuple[float, float, float, float, float] = (0.35, 0.2, 0.2, 0.15, 0.1)
    """Relative frequencies of blob, bin (circle), cart/pallet, pillar, parked car."""


def clutter_item(rng: np.random.Generator, cx: float, cy: float, spec: ClutterSpec) -> Obstacle:
    """One clutter obstacle centred near (cx, cy): an irregular polygon, a bin, a cart, a pillar or a car
    (paper §IV-A clutter)."""
    kind = int(rng.choice(5, p=np.array(spec.weights) / np.sum(spec.weights)))
    angle = rng.uniform(0, math.pi)
    if kind == 0:
        return PolygonObstacle(blob(rng, cx, cy, rng.uniform(*spec.blob_radius_m), int(rng.integers(5, 9))))
    if kind == 1:
        return CircleObstacle(np.array([cx, cy]), rng.uniform(0.3, 0.6))
    if kind == 2:
        return PolygonObstacle(rectangle(cx, cy, rng.uniform(1.0, 1.8), rng.uniform(0.7, 1.2), angle))
    if kind == 3:
        side = rng.uniform(0.4, 0.8)
        return PolygonObstacle(rectangle(cx, cy, side, side, angle))
    return PolygonObstacle(rectangle(cx, cy, 4.689, 1.942, angle))


def place_clutter(rng: np.random.Generator, count: int, boundary: np.ndarray, obstacles: list[Obstacle],
                  keepout, spec: ClutterSpec, tries_per_item: int = 40,
                  focus: tuple[float, float, float] | None = None) -> list[Obstacle]:
    """Up to ``count`` clutter items inside ``boundary``, at least ``spec.gap_m`` from every obstacle (the given
    ones and each other), ``spec.wall_gap_m`` from the boundary, disjoint from ``keepout`` (shapely geometry).

    With ``focus = (x, y, r)`` two draws in three are centred within ``r`` of (x, y) (clutter around the target).
    Returns only the new items (fewer than ``count`` when the space runs out).
    """
    outline = ShapelyPolygon(boundary)
    inner = outline.buffer(-spec.wall_gap_m)
    lo, hi = np.asarray(boundary).min(axis=0), np.asarray(boundary).max(axis=0)
    placed: list[Obstacle] = []
    taken = [obstacle_geometry(o) for o in obstacles]
    for _ in range(count):
        for _ in range(tries_per_item):
            if focus is not None and rng.random() < 2.0 / 3.0:
                radius, angle = focus[2] * math.sqrt(rng.random()), rng.uniform(0, 2 * math.pi)
                cx, cy = focus[0] + radius * math.cos(angle), focus[1] + radius * math.sin(angle)
            else:
                cx, cy = rng.uniform(lo, hi)
            item = clutter_item(rng, cx, cy, spec)
            geom = obstacle_geometry(item)
            if not inner.contains(geom) or geom.intersects(keepout):
                continue
            if any(geom.distance(t) < spec.gap_m for t in taken):
                continue
            placed.append(item)
            taken.append(geom)
            break
    return placed


# ---------------------------------------------------------------------------------------------- start regions


def region_cells(grid: GeodesicGrid, region: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """(rows, cols) of the geodesic-grid cells (paper §III-E, 1.5 m) whose centres lie strictly inside ``region``."""
    ny, nx = grid.free.shape
    rows, cols = np.mgrid[0:ny, 0:nx]
    xs = grid.origin[0] + cols * grid.cell_m
    ys = grid.origin[1] + rows * grid.cell_m
    inside = shapely.contains_xy(ShapelyPolygon(region), xs, ys)
    return rows[inside], cols[inside]


def region_distances(grid: GeodesicGrid, region: np.ndarray) -> np.ndarray:
    """Geodesic distances (m, inf when unreachable; paper §III-E grid) of the free cells whose centres are inside
    ``region``."""
    rows, cols = region_cells(grid, region)
    free = grid.free[rows, cols]
    return grid.distance[rows[free], cols[free]]


def choose_start_region(rng: np.random.Generator, scene: Scene, grid: GeodesicGrid, band_m: tuple[float, float],
                        aim_m: tuple[float, float], size_m: tuple[float, float], keepout,
                        allowed=None, tolerance_m: float = 2.0, max_candidates: int = 80,
                        clearance_m: float = 0.3) -> np.ndarray:
    """A start region whose free cells' median geodesic distance lies in ``band_m`` (spec §4.1: the regime is a
    property of the region).

    Draws an aim distance uniformly in ``aim_m``, takes reachable cells within ``tolerance_m`` of it (inside
    ``allowed`` when given) in random order, and returns the first jittered ``size_m`` quadrilateral centred on
    one that stays ``clearance_m`` inside the boundary and away from obstacles, avoids ``keepout``, covers at
    least three free cells, and has its median in the band. Raises `DraftRejected("start_region")` otherwise.
    """
    aim = rng.uniform(*aim_m)
    candidates = np.argwhere(np.isfinite(grid.distance) & (np.abs(grid.distance - aim) <= tolerance_m))
    rng.shuffle(candidates)
    inside = ShapelyPolygon(scene.boundary).buffer(-clearance_m)
    space = inside.difference(union_of(scene.obstacles).buffer(clearance_m))
    for row, col in candidates[:max_candidates]:
        centre = grid.origin + grid.cell_m * np.array([col, row], float)
        if allowed is not None and not allowed.contains(Point(centre)):
            continue
        length, width = size_m
        if rng.random() < 0.5:
            length, width = width, length
        corners = rectangle(centre[0], centre[1], length, width, rng.uniform(-0.2, 0.2))
        corners = corners + rng.uniform(-0.35, 0.35, corners.shape)
        poly = ShapelyPolygon(corners)
        if not poly.is_valid or not space.contains(poly) or poly.intersects(keepout):
            continue
        distances = region_distances(grid, corners)
        if len(distances) < 3 or not np.all(np.isfinite(distances)):
            continue
        if band_m[0] <= float(np.median(distances)) <= band_m[1]:
            return corners
    raise DraftRejected("start_region", f"no region with median geodesic distance in {band_m} m")


# ---------------------------------------------------------------------------------------------- finishing


def round_obstacle(obstacle: Obstacle) -> Obstacle:
    """The obstacle with coordinates (and radius) rounded to `COORD_DECIMALS` (reproducible shipped files)."""
    if isinstance(obstacle, PolygonObstacle):
        return PolygonObstacle(np.round(obstacle.vertices, COORD_DECIMALS))
    return CircleObstacle(np.round(obstacle.center, COORD_DECIMALS), round(float(obstacle.radius), COORD_DECIMALS))


def finish_scene(boundary, obstacles, target, start_region, name: str, tags: dict) -> Scene:
    """The shipped form of a draft: coordinates rounded to millimetres, the heading wrapped to (−π, π] (kept
    exact otherwise); checks run on exactly this scene."""
    th = float(target[2])
    if not -math.pi < th <= math.pi:
        th = math.atan2(math.sin(th), math.cos(th))
        th = math.pi if th <= -math.pi else th
    t = np.array([round(float(target[0]), COORD_DECIMALS), round(float(target[1]), COORD_DECIMALS), th])
    return Scene(
        boundary=np.round(np.asarray(boundary, float), COORD_DECIMALS),
        obstacles=tuple(round_obstacle(o) for o in obstacles),
        target=t,
        start_region=None if start_region is None else np.round(np.asarray(start_region, float), COORD_DECIMALS),
        name=name,
        tags=tags,
    )


def draft_grid(boundary, obstacles, target, vehicle: VehicleSpec | None = None, cell_m: float = 1.5) -> GeodesicGrid:
    """Geodesic grid (paper §III-E) of a draft (boundary, obstacles, target) without a start region (the grid
    ignores it)."""
    return geodesic_grid(Scene(boundary, tuple(obstacles), target, None), cell_m=cell_m, vehicle=vehicle)


def segment_blocked(start_xy, target_xy, obstacles_union) -> bool:
    """True when the straight segment from ``start_xy`` to ``target_xy`` touches an obstacle (the "direct
    approach" of the paper §IV-A Topology-Stress families)."""
    return bool(LineString([tuple(start_xy), tuple(target_xy)]).intersects(obstacles_union))


def jsonable(value):
    """Tuples to lists, recursively (generator configs as JSON-safe dicts)."""
    if isinstance(value, dict):
        return {k: jsonable(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [jsonable(v) for v in value]
    return value
