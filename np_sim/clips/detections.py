"""The detection (noise) model of the clips: how a clip's recorded detections are drawn from its ground truth.

Per object and frame: its outline resampled to exactly five vertices (`five_vertex_outline`), Gaussian vertex
jitter (sd per clip, truncated), rounded to the centimetre; drop-outs follow a two-state Markov chain per object
and whole frames are missed (never frame 0). Detections never overlap the target footprint, nor the start
footprint at frame 0: a jitter draw that would, or that would make a non-simple polygon, is retried at half the
jitter, down to none.
"""

from __future__ import annotations

import math
from typing import Sequence

import numpy as np
import shapely
from shapely.geometry import Polygon as ShapelyPolygon

from np_sim.clips.config import ClipConfig
from np_sim.clips.model import TrackedObject
from np_sim.errors import SceneError
from np_sim.frames import place

JITTER_SCALES = (1.0, 0.5, 0.25, 0.0)
"""Fractions of a detection's jitter tried in turn until its polygon is usable (the last: no jitter)."""


def five_vertex_outline(outline: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """The outline (k, 2) as exactly five vertices, same frame, drawing one number from ``rng``.

    k = 5: unchanged. k = 4 (rectangles): one vertex inserted on the longest edge at 30–70 % of its length (the
    outline is unchanged). k > 5 (round objects): the regular pentagon circumscribed about the circle centred at
    the vertex mean through the farthest vertex, rotated by a random angle (covers the object). k = 3: the
    longest edge split at 30–70 %, then the longest edge of the result at its midpoint.
    """
    k = len(outline)
    u = float(rng.random())
    if k == 5:
        return outline.copy()
    if k > 5:
        centre = outline.mean(axis=0)
        radius = float(np.max(np.linalg.norm(outline - centre, axis=1))) / math.cos(math.pi / 5)
        angles = 2.0 * np.pi * (u + np.arange(5)) / 5
        return centre + radius * np.stack([np.cos(angles), np.sin(angles)], axis=1)
    points = [np.asarray(p, dtype=np.float64) for p in outline]
    fraction = 0.3 + 0.4 * u
    while len(points) < 5:
        lengths = [np.linalg.norm(points[(i + 1) % len(points)] - points[i]) for i in range(len(points))]
        i = int(np.argmax(lengths))
        new = points[i] + fraction * (points[(i + 1) % len(points)] - points[i])
        points.insert(i + 1, new)
        fraction = 0.5
    return np.array(points)


def draw_detections(rng: np.random.Generator, objects: Sequence[TrackedObject], n_frames: int,
                    target_fp: ShapelyPolygon, start_fp: ShapelyPolygon, config: ClipConfig) -> dict:
    """A clip's recorded detections (this module's docstring), drawn from ``rng``: the per-clip jitter sd,
    drop-out onset and missed-frame probability, then the detections of every frame. Returns the `Clip` fields
    ``frame_missed``, ``det_offsets``, ``det_object``, ``det_vertices_cm``, ``jitter_sd_m`` and ``dropout_onset``.
    """
    jitter_sd = round(float(rng.uniform(*config.jitter_sd_range_m)), 4)
    dropout_onset = round(float(rng.uniform(*config.dropout_onset_range)), 4)
    missed = rng.random(n_frames) < float(rng.uniform(*config.missed_frame_range))
    missed[0] = False
    visible = _visibility(rng, n_frames, len(objects), dropout_onset, config.dropout_persistence) & ~missed[:, None]
    vertices_cm = _jittered_vertices_cm(rng, objects, n_frames, jitter_sd, target_fp, start_fp, config)
    frames, ids = np.nonzero(visible)  # row-major: sorted by frame, then object id
    return {
        "frame_missed": missed,
        "det_offsets": np.concatenate([[0], np.cumsum(np.bincount(frames, minlength=n_frames))]),
        "det_object": ids.astype(np.int32),
        "det_vertices_cm": vertices_cm[ids, frames].astype(np.int16),
        "jitter_sd_m": jitter_sd,
        "dropout_onset": dropout_onset,
    }


def _visibility(rng: np.random.Generator, n_frames: int, n_obj: int, onset: float, persistence: float) -> np.ndarray:
    """(n_frames, n_obj) bool: the drop-out chain per object (visible → dropped with ``onset``, dropped → dropped
    with ``persistence``), frame 0 drawn from visible."""
    u = rng.random((n_frames, n_obj))
    visible = np.ones((n_frames, n_obj), dtype=bool)
    state = u[0] >= onset
    visible[0] = state
    for i in range(1, n_frames):
        state = np.where(state, u[i] >= onset, u[i] >= persistence)
        visible[i] = state
    return visible


def _jittered_vertices_cm(rng: np.random.Generator, objects: Sequence[TrackedObject], n_frames: int,
                          jitter_sd: float, target_fp: ShapelyPolygon, start_fp: ShapelyPolygon,
                          config: ClipConfig) -> np.ndarray:
    """(n_obj, n_frames, 5, 2) int64 jittered five-vertex outlines (cm) of every object in every frame, each a
    simple polygon clear of the target footprint (and of the start footprint in frame 0), with
    `JITTER_SCALES` of its jitter."""
    n_obj = len(objects)
    base = np.empty((n_obj, n_frames, 5, 2))
    for j, obj in enumerate(objects):
        five = five_vertex_outline(obj.outline, rng)
        poses = obj.poses if obj.moving else np.repeat(obj.poses, n_frames, axis=0)
        base[j] = place(five, poses)
    noise = jitter_sd * np.clip(rng.standard_normal((n_obj, n_frames, 5, 2)), -config.jitter_truncation_sd,
                                config.jitter_truncation_sd)
    cm = np.zeros((n_obj, n_frames, 5, 2), dtype=np.int64)
    todo = np.ones((n_obj, n_frames), dtype=bool)
    protect_start = np.zeros((n_obj, n_frames), dtype=bool)
    protect_start[:, 0] = True
    for scale in JITTER_SCALES:
        trial = np.rint((base[todo] + scale * noise[todo]) * 100.0).astype(np.int64)
        polygons = shapely.polygons(trial / 100.0)
        ok = shapely.is_valid(polygons) & (shapely.area(polygons) > 0)
        ok &= ~np.any(np.all(trial == np.roll(trial, -1, axis=1), axis=2), axis=1)
        ok &= ~shapely.intersects(polygons, target_fp)
        ok &= ~(protect_start[todo] & shapely.intersects(polygons, start_fp))
        index = np.argwhere(todo)
        accepted = index[ok] if scale > 0.0 else index
        cm[accepted[:, 0], accepted[:, 1]] = trial[ok] if scale > 0.0 else trial
        todo[accepted[:, 0], accepted[:, 1]] = False
        if not todo.any():
            break
    if np.abs(cm).max(initial=0) > np.iinfo(np.int16).max:
        raise SceneError("clip detections: a coordinate exceeds the int16 centimetre range")
    return cm
