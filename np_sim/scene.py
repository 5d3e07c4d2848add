"""Scenes: boundary, obstacles, target pose and start region, with their JSON format and validation (spec §4, §10).

A scene is stored in the world frame as one JSON object::

    {
      "version": 1,
      "name": "reverse_bay",
      "tags": {"benchmark": "factorial", "split": "test"},
      "boundary": [[x, y], ...],                 # simple polygon, either orientation
      "obstacles": [{"polygon": [[x, y], ...]},  # simple polygon, >= 3 distinct vertices; may cross the boundary
                    {"circle": [cx, cy, r]}],    # r > 0
      "target": [x, y, theta],                   # reference-point pose (rear-axle centre), radians
      "start_region": [[x, y], ...],             # optional simple polygon inside the boundary; absent = whole lot
                                                 # (or {"box": [xmin, ymin, xmax, ymax]}, stored as its polygon)
      "start_headings": [lo, hi],                # optional heading range (rad) of drawn starts; absent = any
      "starts": [[x, y, theta], ...]             # optional explicit start poses (reference point, radians)
    }

Polygons (boundary, obstacle polygons, start region) describe a closed ring. Exact repeats are the same ring and
are dropped when a scene is built: a closing vertex equal to the first (the GeoJSON convention) and consecutive
equal vertices. Obstacles may cross or lie beyond the boundary (a real lot cut to a region of interest). The start
region must lie inside the boundary (touching it is allowed) and must not be wholly covered by obstacles: some of
its area must be free, with circles counted as their circumscribed 64-gon. Whether a whole footprint fits there is
the benchmark validity check's question (`np_sim.benchmarks.validity`), not the format's. ``start_headings`` is
``[lo, hi]`` with lo ≤ hi ≤ lo + 2π (a range may cross ±π, e.g. ``[2.5, 3.8]``). Each explicit start must have
its reference point strictly inside the boundary; whether it is free under a planner's collision convention is
checked where the starts are used (`np_sim.scene_starts`). The JSON Schema of the format is
``np_sim/data/scene.schema.json``.

Loading validates everything and fixes nothing else: every problem raises `SceneError` with the source (file path
or ``"<dict>"``), the field path (``obstacles[3].polygon[2]``) and what was expected against what came; an
unreadable, non-UTF-8, non-JSON or too deeply nested file is a `SceneError` too. The format has no object or vertex
limit; the NeuralParker observation limits live in `SceneCapacity` and are enforced only when a capacity is passed
(`CapacityError`).
"""

from __future__ import annotations

import json
import math
import re
import reprlib
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import shapely
from shapely.geometry import MultiPoint, Point
from shapely.geometry import Polygon as ShapelyPolygon
from shapely.ops import unary_union

from np_sim.errors import CapacityError, SceneError
from np_sim.vehicle import VehicleSpec

SCENE_FORMAT_VERSION = 1
"""The only scene JSON version this module reads and writes."""


def _frozen_ring(values, what: str) -> np.ndarray:
    """Copy polygon ``values`` to a read-only (n, 2) float64 array without exact repeats; SceneError on bad shape.

    A vertex equal to the one kept before it is dropped, and so are closing vertices equal to the first: the
    ring they describe is the same.
    """
    array = np.array(values, dtype=np.float64)
    if array.ndim != 2 or array.shape[1] != 2:
        raise SceneError(f"{what}: expected an array of shape (n, 2), got shape {array.shape}")
    if len(array) > 1:
        keep = np.ones(len(array), bool)
        keep[1:] = np.any(array[1:] != array[:-1], axis=1)
        array = array[keep]
        while len(array) > 1 and np.array_equal(array[-1], array[0]):
            array = array[:-1]
    array.flags.writeable = False
    return array


def _circle_points(center: np.ndarray, radius: float, n: int) -> np.ndarray:
    """(n, 2) points on the circle at angles 2πk/n, k = 0..n-1 (counter-clockwise)."""
    angles = 2.0 * np.pi * np.arange(n) / n
    return np.stack([center[0] + radius * np.cos(angles), center[1] + radius * np.sin(angles)], axis=1)


@dataclass(frozen=True)
class PolygonObstacle:
    """A polygonal obstacle given by its vertices in the world frame, either orientation; exact repeats dropped."""

    vertices: np.ndarray
    """(k, 2) float64 world-frame vertices (m), k >= 3, read-only, no vertex equal to the next (ring closes)."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "vertices", _frozen_ring(self.vertices, "PolygonObstacle.vertices"))


@dataclass(frozen=True)
class CircleObstacle:
    """A circular obstacle (bin, pillar, bollard); inscribed polygons stand in for it where polygons are needed."""

    center: np.ndarray
    """(2,) float64 world-frame centre (m), read-only."""
    radius: float
    """Radius (m), > 0."""

    def __post_init__(self) -> None:
        center = np.array(self.center, dtype=np.float64)
        if center.shape != (2,):
            raise SceneError(f"CircleObstacle.center: expected shape (2,), got {center.shape}")
        center.flags.writeable = False
        object.__setattr__(self, "center", center)
        object.__setattr__(self, "radius", float(self.radius))

    def octagon(self) -> np.ndarray:
        """(8, 2) vertices on the circle at angles 2πk/8, k = 0..7, counter-clockwise: observation form (App. A)."""
        return _circle_points(self.center, self.radius, 8)

    def ring(self, n: int = 16) -> np.ndarray:
        """(n, 2) vertices on the circle at angles 2πk/n, counter-clockwise: the ray-casting form (App. A, n = 16)."""
        if int(n) != n or n < 3:
            raise ValueError(f"CircleObstacle.ring: n must be an integer >= 3, got {n!r}")
        return _circle_points(self.center, self.radius, int(n))


Obstacle = PolygonObstacle | CircleObstacle


@dataclass(frozen=True)
class SceneCapacity:
    """The NeuralParker observation limits a scene must fit (spec §4); limits of the observation, not of the format."""

    max_obstacles: int = 20
    """Most obstacles the observation encodes."""
    max_polygon_vertices: int = 8
    """Most vertices per obstacle polygon (a circle counts as its 8-vertex octagon)."""
    max_boundary_segments: int = 10
    """Most boundary segments the observation encodes."""


@dataclass(frozen=True, eq=False)
class Scene:
    """One parking scene in the world frame (spec §4).

    Construct with `Scene.from_dict` or `Scene.load`, which validate; direct construction only normalises the
    arrays (float64, read-only, exact repeats and closing vertices of polygons dropped) and checks their shapes —
    call `validate` on scenes built in code. Validity rules are in the module docstring: simple polygons, the
    start region inside the boundary with free area, the target footprint strictly inside and obstacle-free;
    obstacles may cross the boundary.
    """

    boundary: np.ndarray
    """(B, 2) float64 simple polygon (m), either orientation, no vertex equal to the next (the ring closes)."""
    obstacles: tuple[Obstacle, ...]
    """Obstacles in scene order (the order the observation and ray casting use)."""
    target: np.ndarray
    """(3,) float64 target pose x (m), y (m), θ (rad) of the reference point; θ kept exactly as given."""
    start_region: np.ndarray | None
    """(S, 2) float64 simple polygon (m) where starts are drawn, or None for the whole free space."""
    name: str = ""
    """Human-readable scene name (used in titles and tables)."""
    tags: dict = field(default_factory=dict)
    """Free str -> str | int | float labels (benchmark, split, cell, ...)."""
    version: int = SCENE_FORMAT_VERSION
    """Scene format version; only `SCENE_FORMAT_VERSION` exists."""
    start_headings: np.ndarray | None = None
    """(2,) float64 heading range [lo, hi] (rad) of starts drawn from the start region, or None for any heading."""
    starts: np.ndarray | None = None
    """(n, 3) float64 explicit start poses x (m), y (m), θ (rad) of the reference point, or None."""

    def __post_init__(self) -> None:
        object.__setattr__(self, "boundary", _frozen_ring(self.boundary, "Scene.boundary"))
        target = np.array(self.target, dtype=np.float64)
        if target.shape != (3,):
            raise SceneError(f"Scene.target: expected shape (3,), got {target.shape}")
        target.flags.writeable = False
        object.__setattr__(self, "target", target)
        if self.start_region is not None:
            object.__setattr__(self, "start_region", _frozen_ring(self.start_region, "Scene.start_region"))
        for name, shape in (("start_headings", (2,)), ("starts", (-1, 3))):
            value = getattr(self, name)
            if value is not None:
                array = np.array(value, dtype=np.float64)
                if array.ndim != len(shape) or array.shape[-1] != shape[-1]:
                    raise SceneError(f"Scene.{name}: expected shape {shape} (-1: any), got {array.shape}")
                array.flags.writeable = False
                object.__setattr__(self, name, array)
        obstacles = tuple(self.obstacles)
        for index, obstacle in enumerate(obstacles):
            if not isinstance(obstacle, (PolygonObstacle, CircleObstacle)):
                raise SceneError(
                    f"Scene.obstacles[{index}]: expected a PolygonObstacle or CircleObstacle, "
                    f"got {type(obstacle).__name__}"
                )
        object.__setattr__(self, "obstacles", obstacles)
        object.__setattr__(self, "tags", dict(self.tags))

    # ------------------------------------------------------------------ construction and I/O

    @classmethod
    def from_dict(
        cls,
        data: Any,
        *,
        source: str = "<dict>",
        vehicle: VehicleSpec | None = None,
        capacity: SceneCapacity | None = None,
    ) -> Scene:
        """Build and validate a scene from its JSON-shaped dict (spec §10).

        Parameters
        ----------
        data
            The parsed JSON object.
        source
            Where ``data`` came from; it opens every error message.
        vehicle
            Vehicle whose footprint at the target must be free; default `VehicleSpec()`.
        capacity
            If given, the scene must also fit these observation limits (`CapacityError` otherwise).

        Raises
        ------
        SceneError
            On any malformed, degenerate, self-intersecting or colliding content; `CapacityError` on capacity.
        """
        scene = _parse_scene(data, source)
        scene.validate(source=source, vehicle=vehicle, capacity=capacity)
        return scene

    def to_dict(self) -> dict:
        """JSON-safe dict (plain floats and lists, fixed key order) that `from_dict` turns back into this scene."""
        out: dict[str, Any] = {
            "version": int(self.version),
            "name": self.name,
            "tags": {key: self.tags[key] for key in sorted(self.tags)},
            "boundary": self.boundary.tolist(),
            "obstacles": [_obstacle_to_dict(obstacle) for obstacle in self.obstacles],
            "target": self.target.tolist(),
        }
        if self.start_region is not None:
            out["start_region"] = self.start_region.tolist()
        if self.start_headings is not None:
            out["start_headings"] = self.start_headings.tolist()
        if self.starts is not None:
            out["starts"] = self.starts.tolist()
        return out

    @classmethod
    def load(
        cls,
        path: str | Path,
        *,
        vehicle: VehicleSpec | None = None,
        capacity: SceneCapacity | None = None,
    ) -> Scene:
        """Read and validate a scene JSON file; errors name the file (see `from_dict` for the arguments).

        Raises
        ------
        SceneError
            Also when the file cannot be read (missing, a directory, no permission), is not UTF-8, is not JSON or
            nests too deeply to parse.
        """
        source = str(path)
        return cls.from_dict(read_json(path), source=source, vehicle=vehicle, capacity=capacity)

    def save(self, path: str | Path) -> None:
        """Write the scene as JSON (indent 2, fixed key order, one point per line) to ``path``."""
        Path(path).write_text(format_json(self.to_dict()) + "\n", encoding="utf-8")

    # ------------------------------------------------------------------ validation

    def validate(
        self,
        *,
        source: str = "<scene>",
        vehicle: VehicleSpec | None = None,
        capacity: SceneCapacity | None = None,
    ) -> None:
        """Check the geometry: simple non-degenerate polygons, positive radii, version, free target footprint.

        ``from_dict``/``load`` call this; call it yourself on scenes built in code. With ``capacity`` the
        observation limits are checked too (before the target, so a too-large scene fails on capacity).

        Raises
        ------
        SceneError
            Naming ``source``, the field path and what was expected; `CapacityError` for capacity.
        """
        if self.version != SCENE_FORMAT_VERSION:
            raise SceneError(f"{source}: version: expected {SCENE_FORMAT_VERSION}, got {self.version!r}")
        if not np.all(np.isfinite(self.target)):
            raise SceneError(f"{source}: target: expected finite numbers, got {self.target.tolist()}")
        boundary = _check_polygon(self.boundary, source, "boundary")
        for index, obstacle in enumerate(self.obstacles):
            if isinstance(obstacle, PolygonObstacle):
                _check_polygon(obstacle.vertices, source, f"obstacles[{index}].polygon")
            else:
                where = f"obstacles[{index}].circle"
                if not np.all(np.isfinite(obstacle.center)) or not math.isfinite(obstacle.radius):
                    raise SceneError(f"{source}: {where}: expected finite numbers")
                if obstacle.radius <= 0.0:
                    raise SceneError(f"{source}: {where}[2]: expected a radius > 0, got {obstacle.radius!r}")
        if self.start_region is not None:
            self._check_start_region(boundary, _check_polygon(self.start_region, source, "start_region"), source)
        self._check_starts(boundary, source)
        if capacity is not None:
            self.check_capacity(capacity, source=source)
        self._check_target(boundary, vehicle if vehicle is not None else VehicleSpec(), source)

    def _check_target(self, boundary: ShapelyPolygon, vehicle: VehicleSpec, source: str) -> None:
        """Raise SceneError unless the target footprint is strictly inside the boundary and clear of every obstacle."""
        footprint = ShapelyPolygon(vehicle.footprint(self.target))
        pose = ", ".join(f"{value:g}" for value in self.target)
        if not boundary.contains_properly(footprint):
            raise SceneError(
                f"{source}: target: the vehicle footprint at ({pose}) must lie strictly inside the boundary, "
                "but it touches or crosses it"
            )
        for index, obstacle in enumerate(self.obstacles):
            if isinstance(obstacle, PolygonObstacle):
                hit = not footprint.disjoint(ShapelyPolygon(obstacle.vertices))
                kind = "polygon"
            else:
                hit = footprint.distance(Point(obstacle.center)) <= obstacle.radius
                kind = "circle"
            if hit:
                raise SceneError(
                    f"{source}: target: the vehicle footprint at ({pose}) must be disjoint from every obstacle, "
                    f"but it touches or overlaps obstacles[{index}] ({kind})"
                )

    def _check_start_region(self, boundary: ShapelyPolygon, region: ShapelyPolygon, source: str) -> None:
        """SceneError unless ``region`` lies inside ``boundary`` (touching allowed) and has area free of obstacles."""
        if not boundary.covers(region):
            outside = region.difference(boundary).representative_point()
            raise SceneError(
                f"{source}: start_region: expected a polygon inside the boundary, but it leaves the boundary "
                f"(e.g. at ({outside.x:g}, {outside.y:g}))"
            )
        shapes = [obstacle_shape(obstacle) for obstacle in self.obstacles]
        if shapes and region.difference(unary_union(shapes)).area <= 0.0:
            covering = [f"obstacles[{i}]" for i, shape in enumerate(shapes) if shape.intersects(region)]
            raise SceneError(
                f"{source}: start_region: expected some area free of obstacles, but it lies wholly inside "
                f"{', '.join(covering)} (no start can be drawn there)"
            )

    def _check_starts(self, boundary: ShapelyPolygon, source: str) -> None:
        """SceneError unless ``start_headings`` is a range lo ≤ hi ≤ lo + 2π of finite numbers and every explicit
        start is finite with its reference point strictly inside ``boundary``."""
        if self.start_headings is not None:
            lo, hi = self.start_headings
            if not (np.isfinite(lo) and np.isfinite(hi) and lo <= hi <= lo + 2.0 * math.pi):
                raise SceneError(f"{source}: start_headings: expected [lo, hi] (rad) with lo <= hi <= lo + 2π, "
                                 f"got {self.start_headings.tolist()}")
        for index, pose in enumerate(() if self.starts is None else self.starts):
            if not np.all(np.isfinite(pose)):
                raise SceneError(f"{source}: starts[{index}]: expected finite numbers, got {pose.tolist()}")
            if not boundary.contains_properly(Point(pose[0], pose[1])):
                raise SceneError(f"{source}: starts[{index}]: the reference point ({pose[0]:g}, {pose[1]:g}) must "
                                 "lie strictly inside the boundary")

    def check_capacity(self, capacity: SceneCapacity, *, source: str = "<scene>") -> None:
        """Raise `CapacityError` naming the limit and the count if the scene exceeds ``capacity`` (never truncates)."""
        if len(self.obstacles) > capacity.max_obstacles:
            raise CapacityError(
                f"{source}: obstacles: {len(self.obstacles)} obstacles exceed "
                f"SceneCapacity.max_obstacles = {capacity.max_obstacles}"
            )
        for index, obstacle in enumerate(self.obstacles):
            if isinstance(obstacle, PolygonObstacle):
                count, where, note = len(obstacle.vertices), f"obstacles[{index}].polygon", ""
            else:
                count, where, note = 8, f"obstacles[{index}].circle", " (a circle is observed as its octagon)"
            if count > capacity.max_polygon_vertices:
                raise CapacityError(
                    f"{source}: {where}: {count} vertices{note} exceed "
                    f"SceneCapacity.max_polygon_vertices = {capacity.max_polygon_vertices}"
                )
        if len(self.boundary) > capacity.max_boundary_segments:
            raise CapacityError(
                f"{source}: boundary: {len(self.boundary)} segments exceed "
                f"SceneCapacity.max_boundary_segments = {capacity.max_boundary_segments}"
            )

    # ------------------------------------------------------------------ derived geometry

    def polygons_for_observation(self) -> list[np.ndarray]:
        """Per obstacle in scene order, its (k, 2) vertices; circles as their octagon (paper App. A)."""
        return [o.vertices if isinstance(o, PolygonObstacle) else o.octagon() for o in self.obstacles]

    def polygons_for_rays(self) -> list[np.ndarray]:
        """Per obstacle in scene order, its (k, 2) vertices; circles as their 16-vertex ring (paper App. A)."""
        return [o.vertices if isinstance(o, PolygonObstacle) else o.ring(16) for o in self.obstacles]

    def boundary_segments(self) -> np.ndarray:
        """(B, 4) boundary segments x0, y0, x1, y1; segment i joins vertex i to vertex i+1, the last closes the ring."""
        return np.concatenate([self.boundary, np.roll(self.boundary, -1, axis=0)], axis=1)


# ---------------------------------------------------------------------- parsing helpers

_TOP_LEVEL_KEYS = ("version", "name", "tags", "boundary", "obstacles", "target", "start_region", "start_headings",
                   "starts")
_REQUIRED_KEYS = ("boundary", "obstacles", "target")


def _type_name(value: Any) -> str:
    """JSON-flavoured name of a value's type for error messages."""
    names = {bool: "boolean", int: "integer", float: "number", str: "string", list: "list", dict: "object"}
    return "null" if value is None else names.get(type(value), type(value).__name__)


_SHORT_REPR = reprlib.Repr()
"""repr with bounded depth and length (reprlib's defaults), safe on deeply nested or huge values."""


def _describe(value: Any) -> str:
    """Short ``type value`` description of what came, for error messages."""
    text = _SHORT_REPR.repr(value)
    if len(text) > 60:
        text = text[:57] + "..."
    return f"{_type_name(value)} {text}"


def _is_sequence(value: Any) -> bool:
    """True for the list-like containers a point list may arrive as (JSON lists, tuples, numpy arrays)."""
    if isinstance(value, np.ndarray):
        return value.ndim >= 1
    return isinstance(value, (list, tuple))


def _number(value: Any, source: str, where: str) -> float:
    """A finite real number (not a boolean), else SceneError."""
    if isinstance(value, np.generic):
        value = value.item()
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise SceneError(f"{source}: {where}: expected a number, got {_describe(value)}")
    try:
        number = float(value)
    except OverflowError:
        raise SceneError(
            f"{source}: {where}: expected a finite number, got an integer of {len(str(abs(value)))} digits "
            "(beyond the float range)"
        ) from None
    if not math.isfinite(number):
        raise SceneError(f"{source}: {where}: expected a finite number, got {value!r}")
    return number


def _numbers(value: Any, count: int, source: str, where: str, what: str) -> list[float]:
    """A list of exactly ``count`` finite numbers, else SceneError naming ``what`` was expected."""
    if not _is_sequence(value) or len(value) != count:
        raise SceneError(f"{source}: {where}: expected {what}, got {_describe(value)}")
    return [_number(item, source, f"{where}[{i}]") for i, item in enumerate(value)]


def _points(value: Any, source: str, where: str) -> np.ndarray:
    """A list of [x, y] pairs as an (n, 2) float64 array (no geometric checks yet), else SceneError."""
    if not _is_sequence(value):
        raise SceneError(f"{source}: {where}: expected a list of [x, y] points, got {_describe(value)}")
    rows = [_numbers(point, 2, source, f"{where}[{i}]", "an [x, y] pair") for i, point in enumerate(value)]
    return np.array(rows, dtype=np.float64).reshape(len(rows), 2)


def _check_keys(data: dict, allowed: tuple[str, ...], required: tuple[str, ...], source: str, where: str) -> None:
    """SceneError on a missing required key or an unknown key of ``data``."""
    prefix = f"{where}." if where else ""
    for key in data:
        if key not in allowed:
            raise SceneError(
                f"{source}: {prefix}{key}: unknown field; expected only {', '.join(allowed)}"
            )
    for key in required:
        if key not in data:
            raise SceneError(f"{source}: {prefix}{key}: missing required field")


def _parse_obstacle(data: Any, source: str, where: str) -> Obstacle:
    """One ``{"polygon": [...]}`` or ``{"circle": [cx, cy, r]}`` entry (shape and type checks only)."""
    if not isinstance(data, dict):
        raise SceneError(
            f'{source}: {where}: expected an object {{"polygon": [...]}} or {{"circle": [cx, cy, r]}}, '
            f"got {_describe(data)}"
        )
    _check_keys(data, ("polygon", "circle"), (), source, where)
    if len(data) != 1:
        raise SceneError(
            f'{source}: {where}: expected exactly one of "polygon" or "circle", got {sorted(data) or "none"}'
        )
    if "polygon" in data:
        return PolygonObstacle(_points(data["polygon"], source, f"{where}.polygon"))
    cx, cy, radius = _numbers(data["circle"], 3, source, f"{where}.circle", "a [cx, cy, r] triple")
    return CircleObstacle(np.array([cx, cy]), radius)


def _parse_scene(data: Any, source: str) -> Scene:
    """Types, shapes and keys of a scene dict into a `Scene`; geometry is checked by `Scene.validate`."""
    if not isinstance(data, dict):
        raise SceneError(f"{source}: expected a JSON object at the top level, got {_describe(data)}")
    _check_keys(data, _TOP_LEVEL_KEYS, _REQUIRED_KEYS, source, "")
    version = data.get("version", SCENE_FORMAT_VERSION)
    if isinstance(version, bool) or not isinstance(version, int) or version != SCENE_FORMAT_VERSION:
        raise SceneError(f"{source}: version: expected {SCENE_FORMAT_VERSION}, got {_describe(version)}")
    name = data.get("name", "")
    if not isinstance(name, str):
        raise SceneError(f"{source}: name: expected a string, got {_describe(name)}")
    tags = data.get("tags", {})
    if not isinstance(tags, dict):
        raise SceneError(f"{source}: tags: expected an object of string/number values, got {_describe(tags)}")
    for key, value in tags.items():
        if not isinstance(key, str):
            raise SceneError(f"{source}: tags: expected string keys, got {_describe(key)}")
        if isinstance(value, bool) or not isinstance(value, (str, int, float)):
            raise SceneError(f"{source}: tags.{key}: expected a string or number, got {_describe(value)}")
        if isinstance(value, float) and not math.isfinite(value):
            raise SceneError(f"{source}: tags.{key}: expected a finite number, got {value!r}")
    boundary = _points(data["boundary"], source, "boundary")
    obstacles_data = data["obstacles"]
    if not _is_sequence(obstacles_data):
        raise SceneError(f"{source}: obstacles: expected a list of obstacle objects, got {_describe(obstacles_data)}")
    obstacles = tuple(_parse_obstacle(item, source, f"obstacles[{i}]") for i, item in enumerate(obstacles_data))
    target = _numbers(data["target"], 3, source, "target", "an [x, y, theta] pose")
    start_region = _parse_start_region(data.get("start_region"), source)
    headings = data.get("start_headings")
    if headings is not None:
        headings = _numbers(headings, 2, source, "start_headings", "a [lo, hi] heading range (rad)")
    starts = data.get("starts")
    if starts is not None:
        if not _is_sequence(starts):
            raise SceneError(f"{source}: starts: expected a list of [x, y, theta] poses, got {_describe(starts)}")
        starts = [_numbers(pose, 3, source, f"starts[{i}]", "an [x, y, theta] pose") for i, pose in enumerate(starts)]
        starts = np.array(starts, dtype=np.float64).reshape(len(starts), 3)
    return Scene(
        boundary=boundary,
        obstacles=obstacles,
        target=np.array(target),
        start_region=start_region,
        name=name,
        tags=tags,
        version=version,
        start_headings=headings,
        starts=starts,
    )


def _parse_start_region(value: Any, source: str) -> np.ndarray | None:
    """The start region as (n, 2) points: a list of [x, y] points, or ``{"box": [xmin, ymin, xmax, ymax]}`` as its
    counter-clockwise rectangle (xmin < xmax, ymin < ymax); None when absent."""
    if value is None:
        return None
    if not isinstance(value, dict):
        return _points(value, source, "start_region")
    _check_keys(value, ("box",), ("box",), source, "start_region")
    xmin, ymin, xmax, ymax = _numbers(value["box"], 4, source, "start_region.box", "[xmin, ymin, xmax, ymax]")
    if not (xmin < xmax and ymin < ymax):
        raise SceneError(f"{source}: start_region.box: expected xmin < xmax and ymin < ymax, got "
                         f"{[xmin, ymin, xmax, ymax]}")
    return np.array([[xmin, ymin], [xmax, ymin], [xmax, ymax], [xmin, ymax]])


_LOCATION = re.compile(r"\[\s*([-+0-9.eE]+)\s+([-+0-9.eE]+)\s*\]")


def _check_polygon(vertices: np.ndarray, source: str, where: str) -> ShapelyPolygon:
    """SceneError unless ``vertices`` (exact repeats already dropped) form a simple polygon of area > 0."""
    n = len(vertices)
    if n < 3:
        raise SceneError(
            f"{source}: {where}: expected a polygon with at least 3 distinct vertices, got {n} "
            "(exact repeats and a closing vertex equal to the first count once)"
        )
    if not np.all(np.isfinite(vertices)):
        raise SceneError(f"{source}: {where}: expected finite coordinates")
    if MultiPoint(vertices).convex_hull.area == 0.0:
        raise SceneError(f"{source}: {where}: degenerate polygon: zero area (all {n} vertices are collinear)")
    polygon = ShapelyPolygon(vertices)
    if not polygon.is_valid:
        reason = shapely.is_valid_reason(polygon)
        match = _LOCATION.search(reason)
        at = f" at ({float(match.group(1)):g}, {float(match.group(2)):g})" if match else ""
        raise SceneError(
            f"{source}: {where}: expected a simple polygon, but it self-intersects{at} (shapely: {reason})"
        )
    return polygon


def obstacle_shape(obstacle: Obstacle) -> ShapelyPolygon:
    """The obstacle as a shapely polygon; a circle as its circumscribed 64-gon (covers the whole disc)."""
    if isinstance(obstacle, PolygonObstacle):
        return ShapelyPolygon(obstacle.vertices)
    circumradius = obstacle.radius / math.cos(math.pi / 64)
    return ShapelyPolygon(_circle_points(obstacle.center, circumradius, 64))


def read_json(path: str | Path) -> Any:
    """Parse the JSON file at ``path``; every failure (unreadable, not UTF-8, not JSON, too deep) is a SceneError.

    The message opens with the path and says what went wrong, for the user to fix the file or the path.
    """
    source = str(path)
    try:
        raw = Path(path).read_bytes()
    except OSError as error:
        reason = error.strerror or type(error).__name__
        raise SceneError(f"{source}: cannot read the scene file: {reason}") from None
    try:
        text = raw.decode("utf-8")
    except UnicodeDecodeError as error:
        raise SceneError(
            f"{source}: expected UTF-8 text, got byte 0x{raw[error.start]:02x} at offset {error.start}"
        ) from None
    try:
        return json.loads(text)
    except json.JSONDecodeError as error:
        raise SceneError(
            f"{source}: invalid JSON at line {error.lineno}, column {error.colno}: {error.msg}"
        ) from None
    except RecursionError:
        raise SceneError(f"{source}: invalid JSON: nested too deeply to parse") from None
    except ValueError as error:  # e.g. an integer literal beyond Python's digit limit
        raise SceneError(f"{source}: invalid JSON: {error}") from None


def _obstacle_to_dict(obstacle: Obstacle) -> dict:
    """JSON form of one obstacle."""
    if isinstance(obstacle, PolygonObstacle):
        return {"polygon": obstacle.vertices.tolist()}
    return {"circle": [float(obstacle.center[0]), float(obstacle.center[1]), float(obstacle.radius)]}


def format_json(value: Any, level: int = 0) -> str:
    """JSON text with indent 2 where lists of numbers (points, poses, circles) stay on one line."""
    pad, inner = "  " * level, "  " * (level + 1)
    if isinstance(value, dict) and value:
        items = [f"{inner}{json.dumps(key)}: {format_json(item, level + 1)}" for key, item in value.items()]
        return "{\n" + ",\n".join(items) + "\n" + pad + "}"
    if isinstance(value, list) and value and not all(isinstance(item, (int, float)) for item in value):
        items = [inner + format_json(item, level + 1) for item in value]
        return "[\n" + ",\n".join(items) + "\n" + pad + "]"
    return json.dumps(value, allow_nan=False)
