"""Scenes packed as padded arrays for the compiled kernels.

A ``SceneArrays`` holds M scenes; kernels receive its ``geometry`` tuple and a scene index. Polygon obstacles
keep their exact vertices, circles stay exact discs for collision checks and become 16-segment rings for ray
casting (paper App. A). All arrays are world frame, float64.
"""

from __future__ import annotations

import weakref
from dataclasses import dataclass

import numpy as np

from np_sim.scene import CircleObstacle, PolygonObstacle, Scene

# Indices into SceneArrays.geometry (a plain tuple, which numba passes and caches without a jitclass).
G_BOUNDARY, G_N_BOUNDARY, G_POLY, G_POLY_NV, G_N_POLY, G_POLY_AABB, G_CIRCLE, G_N_CIRCLE, G_SEGS, G_N_SEGS = range(10)


@dataclass(frozen=True, eq=False)
class SceneArrays:
    """Padded world-frame geometry of M scenes; ``geometry`` is the tuple the kernels take."""

    boundary: np.ndarray  # (M, Bmax, 2)
    n_boundary: np.ndarray  # (M,) int64
    poly: np.ndarray  # (M, Pmax, Vmax, 2) polygon obstacles
    poly_nv: np.ndarray  # (M, Pmax) int64 vertex counts
    n_poly: np.ndarray  # (M,) int64
    poly_aabb: np.ndarray  # (M, Pmax, 4) xmin, ymin, xmax, ymax
    circle: np.ndarray  # (M, Cmax, 3) cx, cy, r
    n_circle: np.ndarray  # (M,) int64
    segs: np.ndarray  # (M, Smax, 4) ray-casting segments: obstacle edges, 16-rings, boundary edges
    n_segs: np.ndarray  # (M,) int64
    targets: np.ndarray  # (M, 3)

    @property
    def geometry(self) -> tuple:
        """The arrays the compiled kernels take, in their order (every field but ``targets``)."""
        return (
            self.boundary,
            self.n_boundary,
            self.poly,
            self.poly_nv,
            self.n_poly,
            self.poly_aabb,
            self.circle,
            self.n_circle,
            self.segs,
            self.n_segs,
        )

    @property
    def n_scenes(self) -> int:
        """M, the number of scenes packed."""
        return int(self.targets.shape[0])


def _rings_segments(rings: list) -> np.ndarray:
    """(Σ n_i, 4) rows x0, y0, x1, y1 of every closed ring's edges, ring by ring: edge j of a ring joins its vertex j
    to vertex j+1, the last one back to vertex 0."""
    verts = np.concatenate([np.asarray(r, float) for r in rings])
    sizes = np.array([len(r) for r in rings])
    ends = np.cumsum(sizes)
    following = np.arange(1, len(verts) + 1)
    following[ends - 1] = ends - sizes  # each ring's last vertex closes to its first
    return np.concatenate([verts, verts[following]], axis=1)


def pack_scenes(scenes: list[Scene] | tuple[Scene, ...]) -> SceneArrays:
    """Pack scenes into padded arrays (no capacity limit here: the observation config checks its own)."""
    if len(scenes) == 0:
        raise ValueError("pack_scenes: expected at least one scene, got an empty list")
    m = len(scenes)
    polys = [[np.asarray(o.vertices, float) for o in s.obstacles if isinstance(o, PolygonObstacle)] for s in scenes]
    circles = [[o for o in s.obstacles if isinstance(o, CircleObstacle)] for s in scenes]
    ray_polys = [s.polygons_for_rays() for s in scenes]
    b_max = max(len(s.boundary) for s in scenes)
    p_max = max(1, max(len(p) for p in polys))
    v_max = max(3, max((len(v) for p in polys for v in p), default=3))
    c_max = max(1, max(len(c) for c in circles))
    seg_counts = [sum(len(v) for v in rp) + len(s.boundary) for rp, s in zip(ray_polys, scenes)]
    s_max = max(seg_counts)

    boundary = np.zeros((m, b_max, 2))
    n_boundary = np.zeros(m, np.int64)
    poly = np.zeros((m, p_max, v_max, 2))
    poly_nv = np.zeros((m, p_max), np.int64)
    n_poly = np.zeros(m, np.int64)
    poly_aabb = np.zeros((m, p_max, 4))
    circle = np.zeros((m, c_max, 3))
    n_circle = np.zeros(m, np.int64)
    segs = np.zeros((m, s_max, 4))
    n_segs = np.zeros(m, np.int64)
    targets = np.zeros((m, 3))
    for k, scene in enumerate(scenes):
        b = np.asarray(scene.boundary, float)
        boundary[k, : len(b)] = b
        n_boundary[k] = len(b)
        if polys[k]:
            # each polygon's rows padded with its first vertex, so that one reduction gives every box
            edge_padded = np.empty((len(polys[k]), v_max, 2))
            for j, v in enumerate(polys[k]):
                poly[k, j, : len(v)] = v
                poly_nv[k, j] = len(v)
                edge_padded[j, : len(v)] = v
                edge_padded[j, len(v):] = v[0]
            poly_aabb[k, : len(polys[k]), :2] = edge_padded.min(axis=1)
            poly_aabb[k, : len(polys[k]), 2:] = edge_padded.max(axis=1)
        n_poly[k] = len(polys[k])
        for j, c in enumerate(circles[k]):
            circle[k, j] = (c.center[0], c.center[1], c.radius)
        n_circle[k] = len(circles[k])
        all_rows = _rings_segments([*ray_polys[k], b])
        segs[k, : len(all_rows)] = all_rows
        n_segs[k] = len(all_rows)
        targets[k] = np.asarray(scene.target, float)
    return SceneArrays(boundary, n_boundary, poly, poly_nv, n_poly, poly_aabb, circle, n_circle, segs, n_segs, targets)


_PACKED: "weakref.WeakKeyDictionary[Scene, SceneArrays]" = weakref.WeakKeyDictionary()


def packed_scene(scene: Scene) -> SceneArrays:
    """``pack_scenes([scene])``, cached per scene object (scenes are immutable)."""
    arrays = _PACKED.get(scene)
    if arrays is None:
        arrays = pack_scenes([scene])
        _PACKED[scene] = arrays
    return arrays
