"""The delivery site: one irregular parking area and its assigned parking spots (spec §4.4, paper §V-F, App. C).

The site stands in for the paper's real-vehicle site (a delivery-vehicle parking area whose static boundary is
50 HD-map polylines), which we cannot record. It is one simple polygon of `SiteConfig.n_edges` = 50 edges,
about 61 × 55 m including the entrance throat, world frame, metres:

* south: a kerb with an **entrance throat** (6 m wide, flared, cut by the map 6 m outside the lot), a kerbed
  **planter peninsula** and the chamfered corner of a building (SE);
* east: a straight kerb with three **parallel** spots, a **pillar notch**, then a slanted kerb and a chamfer;
* north: a kerb with a row of **reverse** bays and a **loading-dock recess** holding two more;
* west: the stepped corner of a building (NW) and a kerb with **angled** (45°, nose-in) bays;
* inside: a back-to-back double row of reverse bays (marked on the ground, no kerb: parked vehicles shape it).

The boundary is a fixed template of 36 "survey" vertices plus kerb vertices that the seed places on the longest
edges (a few centimetres off the straight line, as kerbs are) until the ring has exactly ``n_edges`` edges.

Spot poses are vehicle reference-point poses (rear-axle centre, heading) of a vehicle parked in the spot:
``"reverse"`` (perpendicular bay, reversed in: the heading points out of the bay), ``"forward"`` (perpendicular
bay, nose in), ``"parallel"`` (kerb-side slot, heading along the kerb) and ``"angled"`` (45° bay, nose in).
Each spot's reference point is snapped to the node of the 1.5 m geodesic lattice (`np_sim.geodesic`, origin at
the boundary's bounding-box minimum) nearest to its design position that keeps the footprint at least
``min_spot_clearance_m`` from the boundary and from the other spots: the feasibility check of the clips then
judges a tight bay by its neighbours, not by where the lattice happens to cut it.

The site ships as ``np_sim/data/site_v1.json`` (`load_site`); ``generate_site(seed=0)`` reproduces that file
byte for byte (`site_json`). File format::

    {
      "version": 1,
      "name": "delivery_site_v1",
      "seed": 0,
      "boundary": [[x, y], ...],                          # simple polygon, counter-clockwise, each vertex once
      "spots": [{"name": "N01", "kind": "reverse", "pose": [x, y, theta]}, ...]
    }
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from shapely.geometry import LinearRing
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.config import ObservationConfig
from np_sim.errors import SceneError
from np_sim.scene import Scene, format_json
from np_sim.vehicle import VehicleSpec

SITE_FORMAT_VERSION = 1
"""The only site JSON version this module reads and writes."""

DATA_DIR = Path(__file__).resolve().parent / "data"
"""Folder of the shipped site and clip files."""

SITE_PATH = DATA_DIR / "site_v1.json"
"""The shipped site (`load_site`)."""

SPOT_KINDS = ("reverse", "forward", "parallel", "angled")
"""Spot kinds; ``"reverse"`` spots are reversed into (the parked heading points out of the bay)."""

SITE_MAX_BOUNDARY_SEGMENTS = 50
"""Boundary slots of the site observation: the site's 50 edges, rounded up to a multiple of ten."""

SITE_OBSERVATION = ObservationConfig(
    use_lidar=False,
    max_obstacles=10,
    vertices_per_obstacle=5,
    max_boundary_segments=SITE_MAX_BOUNDARY_SEGMENTS,
)
"""Observation of the paper's real-vehicle configuration (App. C): no LiDAR, the nearest ten detections as
five-vertex polygons, the site's HD-map boundary."""


@dataclass(frozen=True)
class SiteConfig:
    """Parameters of `generate_site`; the defaults make the shipped site."""

    n_edges: int = 50
    """Edges of the boundary ring (template vertices plus seeded kerb vertices)."""
    kerb_offset_m: float = 0.08
    """Largest sideways offset of a kerb vertex from the edge it splits (m)."""
    grid_m: float = 1.5
    """Lattice spacing spot reference points are snapped to (m); the geodesic grid's cell size."""
    wall_gap_m: float = 0.6
    """Design gap between a parked vehicle's bumper (or side, parallel spots) and the kerb (m)."""
    min_spot_clearance_m: float = 0.55
    """Least distance from a snapped spot footprint to the boundary (m)."""
    min_spot_gap_m: float = 0.8
    """Least distance between two spot footprints (m)."""


@dataclass(frozen=True, eq=False)
class Spot:
    """One assigned parking pose of the site."""

    name: str
    """Spot label: row letter and number, e.g. ``"N03"``."""
    kind: str
    """One of `SPOT_KINDS`."""
    pose: np.ndarray
    """(3,) reference-point pose x (m), y (m), θ (rad) of a vehicle parked in the spot, read-only."""

    def __post_init__(self) -> None:
        pose = np.array(self.pose, dtype=np.float64)
        if pose.shape != (3,):
            raise SceneError(f"Spot.pose: expected shape (3,), got {pose.shape}")
        pose.flags.writeable = False
        object.__setattr__(self, "pose", pose)
        if self.kind not in SPOT_KINDS:
            raise SceneError(f"Spot.kind: expected one of {', '.join(SPOT_KINDS)}, got {self.kind!r}")


@dataclass(frozen=True, eq=False)
class Site:
    """The delivery site: HD-map boundary and assigned parking spots, world frame (module docstring)."""

    name: str
    """Site name (``"delivery_site_v1"``)."""
    seed: int
    """Seed `generate_site` made it from."""
    boundary: np.ndarray
    """(B, 2) float64 simple polygon (m), counter-clockwise, each vertex once, read-only."""
    spots: tuple[Spot, ...]
    """Assigned parking poses in a fixed order (clips refer to them by index)."""
    version: int = SITE_FORMAT_VERSION
    """Site format version."""

    def __post_init__(self) -> None:
        boundary = np.array(self.boundary, dtype=np.float64)
        if boundary.ndim != 2 or boundary.shape[1] != 2:
            raise SceneError(f"Site.boundary: expected an array of shape (n, 2), got shape {boundary.shape}")
        boundary.flags.writeable = False
        object.__setattr__(self, "boundary", boundary)
        object.__setattr__(self, "spots", tuple(self.spots))

    @property
    def n_edges(self) -> int:
        """Number of boundary edges (the ring closes itself)."""
        return int(len(self.boundary))

    def spot_poses(self) -> np.ndarray:
        """(n_spots, 3) reference-point poses of all spots, in spot order."""
        return np.stack([spot.pose for spot in self.spots])

    def scene(self, target, obstacles=(), *, name: str = "", tags: dict | None = None) -> Scene:
        """A `Scene` of this boundary with ``obstacles`` and ``target`` (not validated; call ``validate``)."""
        return Scene(
            boundary=self.boundary,
            obstacles=tuple(obstacles),
            target=np.asarray(target, dtype=np.float64),
            start_region=None,
            name=name,
            tags=dict(tags or {}),
        )

    def validate(self, *, source: str = "<site>", vehicle: VehicleSpec | None = None) -> None:
        """Raise `SceneError` unless the boundary is a simple polygon and every spot footprint is strictly inside."""
        if self.version != SITE_FORMAT_VERSION:
            raise SceneError(f"{source}: version: expected {SITE_FORMAT_VERSION}, got {self.version!r}")
        if not self.spots:
            raise SceneError(f"{source}: spots: expected at least one spot, got none")
        for index, spot in enumerate(self.spots):
            self.scene(spot.pose).validate(source=f"{source}: spots[{index}] ({spot.name})", vehicle=vehicle)

    # ------------------------------------------------------------------ I/O

    def to_dict(self) -> dict:
        """JSON-safe dict (plain floats and lists, fixed key order) that `from_dict` turns back into this site."""
        return {
            "version": int(self.version),
            "name": self.name,
            "seed": int(self.seed),
            "boundary": self.boundary.tolist(),
            "spots": [{"name": s.name, "kind": s.kind, "pose": s.pose.tolist()} for s in self.spots],
        }

    @classmethod
    def from_dict(cls, data: Any, *, source: str = "<dict>") -> Site:
        """Build and validate a site from its JSON-shaped dict; `SceneError` naming ``source`` and the field."""
        if not isinstance(data, dict):
            raise SceneError(f"{source}: expected a JSON object at the top level, got {type(data).__name__}")
        keys = ("version", "name", "seed", "boundary", "spots")
        for key in data:
            if key not in keys:
                raise SceneError(f"{source}: {key}: unknown field; expected only {', '.join(keys)}")
        for key in keys:
            if key not in data:
                raise SceneError(f"{source}: {key}: missing required field")
        if data["version"] != SITE_FORMAT_VERSION:
            raise SceneError(f"{source}: version: expected {SITE_FORMAT_VERSION}, got {data['version']!r}")
        if not isinstance(data["name"], str):
            raise SceneError(f"{source}: name: expected a string, got {data['name']!r}")
        if isinstance(data["seed"], bool) or not isinstance(data["seed"], int):
            raise SceneError(f"{source}: seed: expected an integer, got {data['seed']!r}")
        spots_data = data["spots"]
        if not isinstance(spots_data, list):
            raise SceneError(f"{source}: spots: expected a list of spot objects, got {type(spots_data).__name__}")
        spots = []
        for index, item in enumerate(spots_data):
            where = f"spots[{index}]"
            if not isinstance(item, dict) or sorted(item) != ["kind", "name", "pose"]:
                raise SceneError(
                    f'{source}: {where}: expected an object with "name", "kind" and "pose", got {item!r}'
                )
            pose = item["pose"]
            if (not isinstance(pose, list) or len(pose) != 3
                    or not all(isinstance(v, (int, float)) and not isinstance(v, bool) and math.isfinite(v)
                               for v in pose)):
                raise SceneError(f"{source}: {where}.pose: expected [x, y, theta] finite numbers, got {pose!r}")
            if item["kind"] not in SPOT_KINDS:
                raise SceneError(
                    f"{source}: {where}.kind: expected one of {', '.join(SPOT_KINDS)}, got {item['kind']!r}"
                )
            spots.append(Spot(str(item["name"]), item["kind"], np.array(pose, dtype=np.float64)))
        try:
            boundary_array = np.array(data["boundary"], dtype=np.float64)
        except (TypeError, ValueError):
            raise SceneError(f"{source}: boundary: expected a list of [x, y] points") from None
        if boundary_array.ndim != 2 or boundary_array.shape[1] != 2:
            raise SceneError(f"{source}: boundary: expected a list of [x, y] points, got shape {boundary_array.shape}")
        site = cls(data["name"], data["seed"], boundary_array, tuple(spots), data["version"])
        site.validate(source=source)
        return site

    @classmethod
    def load(cls, path: str | Path) -> Site:
        """Read and validate a site JSON file; errors name the file."""
        source = str(path)
        try:
            data = json.loads(Path(path).read_text(encoding="utf-8"))
        except json.JSONDecodeError as error:
            raise SceneError(
                f"{source}: invalid JSON at line {error.lineno}, column {error.colno}: {error.msg}"
            ) from None
        return cls.from_dict(data, source=source)

    def save(self, path: str | Path) -> None:
        """Write `site_json` of this site to ``path``."""
        Path(path).write_text(site_json(self), encoding="utf-8")


def site_json(site: Site) -> str:
    """The site's file text: indent 2, fixed key order, one point per line, trailing newline."""
    return format_json(site.to_dict()) + "\n"


_LOADED: dict[str, Site] = {}


def load_site(path: str | Path | None = None) -> Site:
    """The shipped delivery site (``np_sim/data/site_v1.json``), or the site file at ``path``; cached per path."""
    key = str(Path(path).resolve()) if path is not None else str(SITE_PATH)
    site = _LOADED.get(key)
    if site is None:
        site = Site.load(key)
        _LOADED[key] = site
    return site


# ---------------------------------------------------------------------- generator

# Survey vertices of the boundary, counter-clockwise (interior on the left), metres.
_TEMPLATE = (
    (1.0, 0.0),  # SW corner chamfer
    (25.5, 0.0),  # throat: west kerb flare
    (26.5, -1.2),
    (27.0, -2.5),
    (27.0, -6.0),  # map cut across the entrance road
    (33.0, -6.0),
    (33.0, -2.5),
    (33.5, -1.2),  # throat: east kerb flare
    (34.5, 0.0),
    (39.5, 0.0),  # planter peninsula
    (39.5, 6.0),
    (40.0, 6.8),
    (41.0, 6.8),
    (41.5, 6.0),
    (41.5, 0.0),
    (54.0, 0.0),  # SE building, chamfered corner
    (54.0, 6.5),
    (55.0, 7.5),
    (60.2, 7.5),
    (60.2, 33.0),  # east kerb (parallel spots), pillar notch
    (59.4, 33.0),
    (59.4, 34.0),
    (60.2, 34.0),
    (61.0, 42.0),  # slanted kerb, NE chamfer
    (58.5, 45.2),
    (50.0, 45.2),  # loading-dock recess
    (50.0, 48.7),
    (43.0, 48.7),
    (43.0, 45.2),
    (8.8, 45.2),  # NW building: east face, chamfer, stepped south face
    (8.8, 40.0),
    (7.8, 39.0),
    (3.5, 39.0),
    (3.5, 37.0),
    (0.0, 37.0),
    (0.0, 1.0),
)

# Rows of spots: (prefix, kind, line start, line end, first along-line position, spacing, count). The row's
# "kerb line" runs from start to end with the bays on its left; positions are measured from the start (m).
_ROWS = (
    ("N", "reverse", (60.0, 45.2), (0.0, 45.2), 19.5, 3.0, 11),  # north kerb, x = 40.5 .. 10.5
    ("D", "reverse", (50.0, 48.7), (43.0, 48.7), 2.0, 3.0, 2),  # loading-dock recess, x = 48 .. 45
    ("U", "reverse", (15.0, 26.0), (36.0, 26.0), 1.5, 3.0, 7),  # central row, upper half (faces north)
    ("L", "reverse", (36.0, 26.0), (15.0, 26.0), 1.5, 3.0, 7),  # central row, lower half (faces south)
    ("E", "parallel", (60.2, 7.5), (60.2, 33.0), 3.0, 7.5, 3),  # east kerb, slots along the kerb
    ("W", "angled", (0.0, 37.0), (0.0, 1.0), 4.0, 4.5, 6),  # west kerb, 45° nose-in
    ("S", "forward", (0.0, 0.0), (25.5, 0.0), 4.5, 3.0, 7),  # south kerb west of the throat, nose in
    ("R", "reverse", (41.5, 0.0), (54.0, 0.0), 2.0, 3.0, 3),  # south kerb east of the planter
)


def _kerb_vertices(template: np.ndarray, n_edges: int, offset_m: float, rng: np.random.Generator) -> np.ndarray:
    """Split the longest edge (at 35–65 % of it, ``offset_m`` at most off the line, kept inside the template's
    bounding box) until the ring has ``n_edges`` vertices."""
    ring = [tuple(p) for p in template]
    lo, hi = template.min(axis=0), template.max(axis=0)
    while len(ring) < n_edges:
        lengths = [math.dist(ring[i], ring[(i + 1) % len(ring)]) for i in range(len(ring))]
        i = int(np.argmax(lengths))
        a, b = np.array(ring[i]), np.array(ring[(i + 1) % len(ring)])
        t = (b - a) / lengths[i]
        normal = np.array([-t[1], t[0]])
        point = a + rng.uniform(0.35, 0.65) * (b - a) + rng.uniform(-offset_m, offset_m) * normal
        point = np.clip(point, lo, hi)  # kerb vertices never move the bounding box (the lattice origin)
        ring.insert(i + 1, (round(float(point[0]), 3), round(float(point[1]), 3)))
    return np.array(ring, dtype=np.float64)


def _design_pose(kind: str, a: np.ndarray, t: np.ndarray, s: float, gap: float, vehicle: VehicleSpec) -> np.ndarray:
    """Reference pose of a vehicle parked at along-line position ``s`` of a kerb line (bays on the line's left)."""
    inward = np.array([-t[1], t[0]])
    base = a + s * t
    if kind == "reverse":
        return np.array([*(base + (gap + vehicle.rear_overhang_m) * inward), math.atan2(inward[1], inward[0])])
    if kind == "forward":
        return np.array([*(base + (gap + vehicle.front_m) * inward), math.atan2(-inward[1], -inward[0])])
    if kind == "parallel":
        # the slot is centred on s; the vehicle body is centred in it, heading along the line
        centre_offset = 0.5 * (vehicle.front_m - vehicle.rear_overhang_m)
        xy = base - centre_offset * t + (gap + 0.5 * vehicle.width_m) * inward
        return np.array([*xy, math.atan2(t[1], t[0])])
    # angled: nose in at 45° to the kerb, leaning back along the line direction
    direction = -inward * math.cos(math.pi / 4) - t * math.sin(math.pi / 4)
    theta = math.atan2(direction[1], direction[0])
    corners = vehicle.footprint(np.array([base[0], base[1], theta]))
    reach = float(np.min((corners - base) @ inward))  # most negative = deepest corner towards the kerb
    return np.array([*(base + (gap - reach) * inward), theta])


def generate_site(seed: int = 0, config: SiteConfig | None = None, vehicle: VehicleSpec | None = None) -> Site:
    """Generate the delivery site deterministically from ``seed`` (module docstring); seed 0 is the shipped site.

    Raises
    ------
    SceneError
        If a spot finds no lattice node with the required clearances (a template or config error).
    """
    config = SiteConfig() if config is None else config
    vehicle = VehicleSpec() if vehicle is None else vehicle
    rng = np.random.default_rng(seed)
    boundary = _kerb_vertices(np.array(_TEMPLATE, dtype=np.float64), config.n_edges, config.kerb_offset_m, rng)
    region = ShapelyPolygon(boundary)
    ring = LinearRing(boundary)
    origin = boundary.min(axis=0)
    spots: list[Spot] = []
    footprints: list[ShapelyPolygon] = []
    for prefix, kind, start, end, first, spacing, count in _ROWS:
        a, b = np.array(start, dtype=np.float64), np.array(end, dtype=np.float64)
        t = (b - a) / np.linalg.norm(b - a)
        for k in range(count):
            design = _design_pose(kind, a, t, first + k * spacing, config.wall_gap_m, vehicle)
            node = np.round((design[:2] - origin) / config.grid_m)
            candidates = [node + np.array([dc, dr]) for dr in (-1, 0, 1) for dc in (-1, 0, 1)]
            candidates.sort(key=lambda n: float(np.linalg.norm(origin + n * config.grid_m - design[:2])))
            for cand in candidates:
                xy = np.round(origin + cand * config.grid_m, 3)
                pose = np.array([xy[0], xy[1], round(float(design[2]), 6)])
                footprint = ShapelyPolygon(vehicle.footprint(pose))
                if (region.contains_properly(footprint)
                        and footprint.distance(ring) >= config.min_spot_clearance_m
                        and all(footprint.distance(other) >= config.min_spot_gap_m for other in footprints)):
                    break
            else:
                raise SceneError(
                    f"generate_site: spot {prefix}{k + 1:02d} ({kind}) finds no {config.grid_m} m lattice node "
                    f"near {design[:2].round(2).tolist()} with {config.min_spot_clearance_m} m clearance"
                )
            spots.append(Spot(f"{prefix}{k + 1:02d}", kind, pose))
            footprints.append(footprint)
    site = Site("delivery_site_v1", int(seed), boundary, tuple(spots))
    site.validate(source=f"generate_site(seed={seed})", vehicle=vehicle)
    return site
