"""The perception model of the closed loop on a clip (spec §8 "Closed loop on a clip"; beyond the paper): which
detections the planner gets at a frame.

The paper's vehicle planned on each frame's raw detections (`np_sim.clips.Clip.frame_scene`, a window of one
frame). `tracked_detections` filters them over the last K received frames, one track per object id, and
`perceived_scene` turns either into the scene the planner plans in (``ClipRunConfig.track_window``,
``--set clip_run.track_window=K`` of ``python -m experiments.closed_loop --clips``).
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np
import shapely
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.clips import Clip
from np_sim.errors import ConfigError
from np_sim.scene import Scene
from np_sim.vehicle import VehicleSpec


def tracked_detections(clip: Clip, frame: int, window: int,
                       vehicle: VehicleSpec | None = None) -> tuple[np.ndarray, np.ndarray]:
    """Detections of ``clip`` filtered over the last ``window`` non-missed frames up to ``frame`` (a track per
    object id): every object detected in any of them, placed at the centroid of its latest detection, with the
    vertex-wise mean of its centred detections in the window as its shape. Averaging k detections divides the
    vertex jitter's sd by √k; an object that drops out is held at its last detection for the rest of the window.
    ``window=1`` is `Clip.detections` of `Clip.detection_frame` (the raw perception). A filtered outline that is
    not a simple polygon (a turning mover's averaged shape can fold) or would overlap the target footprint of
    ``vehicle`` (default `VehicleSpec()`) is replaced by the object's latest detection, which is neither (the
    clip's construction), so every frame stays a valid scene with a free target as in the raw clip. Returns ids
    (n,) in id order and polygons (n, 5, 2) in metres."""
    if int(window) < 1:
        raise ConfigError(f"tracked_detections: window must be >= 1 frame, got {window!r}")
    frames, f = [], clip.detection_frame(frame)
    while f >= 0 and len(frames) < int(window):
        if not clip.frame_missed[f]:
            frames.append(f)
        f -= 1
    latest: dict[int, np.ndarray] = {}
    shapes: dict[int, list[np.ndarray]] = {}
    for f in frames:  # newest first
        for object_id, polygon in zip(*clip.detections(f)):
            latest.setdefault(int(object_id), polygon)
            shapes.setdefault(int(object_id), []).append(polygon - polygon.mean(axis=0))
    ids = np.array(sorted(latest), dtype=np.int32)
    polygons = np.array([latest[i].mean(axis=0) + np.mean(shapes[i], axis=0) for i in ids]).reshape(-1, 5, 2)
    if len(ids):
        target = ShapelyPolygon((VehicleSpec() if vehicle is None else vehicle).footprint(clip.target))
        shapes_now = shapely.polygons(polygons)
        unusable = shapely.intersects(shapes_now, target) | ~shapely.is_valid(shapes_now)
        for k in np.flatnonzero(unusable):
            polygons[k] = latest[int(ids[k])]
    return ids, polygons


def perceived_scene(clip: Clip, frame: int, *, pose=None, track_window: int = 1,
                    vehicle: VehicleSpec | None = None) -> Scene:
    """The scene the planner plans in at ``frame`` from ``pose`` (default the clip start): `Clip.frame_scene` of
    the raw detections held at that frame when ``track_window`` is 1, else of `tracked_detections` over
    ``track_window`` frames (tagged ``track_window``); the ten nearest to ``pose`` either way."""
    if track_window == 1:
        return clip.frame_scene(frame, pose=pose, vehicle=vehicle)
    detections = tracked_detections(clip, frame, track_window, vehicle)
    scene = clip.frame_scene(frame, pose=pose, vehicle=vehicle, detections=detections)
    return replace(scene, tags={**scene.tags, "track_window": int(track_window)})
