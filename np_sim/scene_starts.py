"""The start poses of a user's scene: the file's explicit ``starts``, or ``n`` drawn reproducibly from its start region.

A scene file may list start poses (``"starts"``) or describe where starts come from: the start region (a polygon or
a box; absent = the whole boundary) and a heading range (``"start_headings"``; absent = any heading). `scene_starts`
returns the explicit starts when the file has them and otherwise draws ``n``: position uniform over the region
(candidates outside it are redrawn), heading uniform over the range, and a start in collision under the planner's
convention rejected and counted. The draws come from ``numpy.random.default_rng(seed)`` alone, so the same file,
``n`` and seed give the same starts whatever other files are run beside it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import shapely
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.collision import path_valid
from np_sim.config import Convention
from np_sim.errors import ConfigError, SceneError
from np_sim.scene import Scene
from np_sim.vehicle import VehicleSpec


@dataclass(frozen=True)
class SceneStarts:
    """Start poses of one scene and where they came from."""

    poses: np.ndarray
    """(n, 3) start poses x (m), y (m), θ (rad) of the reference point."""
    source: str
    """'file' (the scene's explicit starts) or 'drawn' (from its start region)."""
    rejected: int = 0
    """Drawn candidates inside the region rejected as in collision under ``convention`` (0 for 'file')."""
    convention: Convention = "footprint"
    """The collision convention every start is free under."""


def _free(scene: Scene, pose: np.ndarray, convention: Convention, vehicle: VehicleSpec) -> bool:
    """The pose is valid in ``scene`` under ``convention`` (the check a planner makes of its start)."""
    return path_valid(scene, pose[None, :], convention, vehicle)


def explicit_starts(scene: Scene, convention: Convention = "footprint", vehicle: VehicleSpec | None = None,
                    source: str | None = None) -> SceneStarts:
    """The scene's explicit starts, each checked free under ``convention`` (SceneError naming ``starts[i]``)."""
    vehicle = VehicleSpec() if vehicle is None else vehicle
    source = source or scene.name or "<scene>"
    if scene.starts is None or len(scene.starts) == 0:
        raise SceneError(f"{source}: starts: the scene lists no explicit starts")
    for index, pose in enumerate(scene.starts):
        if not _free(scene, pose, convention, vehicle):
            raise SceneError(f"{source}: starts[{index}]: the start ({', '.join(f'{v:g}' for v in pose)}) is in "
                             f"collision under the {convention} convention")
    return SceneStarts(np.array(scene.starts), "file", 0, convention)


def draw_starts(scene: Scene, n: int, seed: int = 0, convention: Convention = "footprint",
                vehicle: VehicleSpec | None = None, max_candidates: int = 100_000,
                source: str | None = None) -> SceneStarts:
    """``n`` starts drawn from the start region and heading range (module docstring), free under ``convention``.

    SceneError naming the scene when ``max_candidates`` region candidates give fewer than ``n`` free starts."""
    if isinstance(n, bool) or int(n) != n or n < 1:
        raise ConfigError(f"draw_starts: n must be a positive integer, got {n!r}")
    vehicle = VehicleSpec() if vehicle is None else vehicle
    source = source or scene.name or "<scene>"
    region = ShapelyPolygon(scene.boundary if scene.start_region is None else scene.start_region)
    xmin, ymin, xmax, ymax = region.bounds
    lo, hi = (-math.pi, math.pi) if scene.start_headings is None else map(float, scene.start_headings)
    rng = np.random.default_rng(seed)
    poses, rejected, candidates = [], 0, 0
    while len(poses) < n:
        if candidates >= max_candidates:
            raise SceneError(f"{source}: start_region: only {len(poses)} of {n} starts free under the {convention} "
                             f"convention in {candidates} candidates ({rejected} in collision); the region is "
                             "mostly blocked")
        u = rng.random((64, 3))
        xy = np.column_stack([xmin + u[:, 0] * (xmax - xmin), ymin + u[:, 1] * (ymax - ymin)])
        for (x, y), inside, v in zip(xy, shapely.contains_xy(region, xy[:, 0], xy[:, 1]), u[:, 2]):
            if not inside or len(poses) == n or candidates >= max_candidates:
                continue
            candidates += 1
            pose = np.array([x, y, math.remainder(lo + v * (hi - lo), 2.0 * math.pi)])
            if _free(scene, pose, convention, vehicle):
                poses.append(pose)
            else:
                rejected += 1
    return SceneStarts(np.array(poses), "drawn", rejected, convention)


def scene_starts(scene: Scene, n: int | None = None, seed: int = 0, convention: Convention = "footprint",
                 vehicle: VehicleSpec | None = None, source: str | None = None) -> SceneStarts:
    """The scene's explicit starts when it lists some, else ``n`` drawn ones (``draw_starts``); ConfigError when
    the scene lists none and ``n`` is None."""
    if scene.starts is not None and len(scene.starts):
        return explicit_starts(scene, convention, vehicle, source)
    if n is None:
        raise ConfigError(f"{source or scene.name or '<scene>'}: the scene lists no starts; give a number of starts "
                          "to draw from its start region (--starts N)")
    return draw_starts(scene, n, seed, convention, vehicle, source=source)
