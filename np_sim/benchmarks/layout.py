"""Layout distance between scenes and the structural-disjointness floor of a benchmark (paper §IV-A: the test
scenes are "structurally disjoint" from the training scenes, spec §4.1 "different layouts, not re-seeded copies").

**Layout distance.** Each scene's layout is the set of its outlines — every obstacle's boundary (a circle as
the circle itself) and the scene boundary — expressed in the scene's own target frame
(`np_sim.frames.to_target_frame`, paper eq:target-frame) and sampled every ``spacing_m`` along each edge. The
distance of two scenes is the symmetric Hausdorff distance of their sample sets:

    d(A, B) = max( max_{a ∈ A} min_{b ∈ B} ‖a − b‖,  max_{b ∈ B} min_{a ∈ A} ‖a − b‖ ).

It is zero for the same layout whatever the world placement, and at least δ when some wall, parked car, bin or
boundary corner of one scene has nothing within δ in the other.

**Disjointness floor.** For a benchmark, the floor is min over test scenes of the distance to the nearest
training scene of the same cell; the generators guarantee it exceeds `DISJOINTNESS_FLOOR_M` (they also keep the
scenes of one cell that far apart within a split) by regenerating a scene that comes too close.
"""

from __future__ import annotations

from collections.abc import Sequence

import numpy as np

from np_sim.frames import to_target_frame
from np_sim.scene import CircleObstacle, PolygonObstacle, Scene

DISJOINTNESS_FLOOR_M = 2.0
"""Documented floor (m) of the layout distance between a scene and every other scene of its cell."""


def _sample_ring(vertices: np.ndarray, spacing_m: float) -> np.ndarray:
    """Points every ≤ ``spacing_m`` along the closed polygon ``vertices`` (k, 2), vertices included."""
    a = np.asarray(vertices, float)
    b = np.roll(a, -1, axis=0)
    pieces = []
    for p, q in zip(a, b):
        n = max(1, int(np.ceil(np.hypot(*(q - p)) / spacing_m - 1e-9)))
        t = np.arange(n)[:, None] / n
        pieces.append(p + t * (q - p))
    return np.concatenate(pieces)


def layout_points(scene: Scene, spacing_m: float = 0.25) -> np.ndarray:
    """(n, 2) samples of the scene's obstacle and boundary outlines in its target frame (see module docstring);
    a circle is sampled on itself at ≥ 16 angles fixed in the target frame, so the samples move with the layout."""
    target = np.asarray(scene.target, float)
    rings = [to_target_frame(o.vertices, target) for o in scene.obstacles if isinstance(o, PolygonObstacle)]
    rings.append(to_target_frame(np.asarray(scene.boundary, float), target))
    parts = [_sample_ring(r, spacing_m) for r in rings]
    for o in scene.obstacles:
        if isinstance(o, CircleObstacle):
            n = max(16, int(np.ceil(2 * np.pi * o.radius / spacing_m)))
            angles = 2 * np.pi * np.arange(n) / n
            centre = to_target_frame(o.center, target)
            parts.append(centre + o.radius * np.stack([np.cos(angles), np.sin(angles)], axis=1))
    return np.concatenate(parts)


def _directed(a: np.ndarray, b: np.ndarray, chunk: int = 2048) -> float:
    """max over a of the distance to the nearest point of b (nearest found by the expanded square form, its
    distance then recomputed exactly, so identical sets give exactly 0)."""
    worst = 0.0
    b2 = (b * b).sum(axis=1)
    for i in range(0, len(a), chunk):
        block = a[i: i + chunk]
        d2 = (block * block).sum(axis=1)[:, None] + b2[None, :] - 2.0 * block @ b.T
        nearest = b[np.argmin(d2, axis=1)]
        worst = max(worst, float(np.hypot(*(block - nearest).T).max()))
    return worst


def hausdorff(a: np.ndarray, b: np.ndarray) -> float:
    """Symmetric Hausdorff distance (m) between point sets a (n, 2) and b (m, 2)."""
    return max(_directed(a, b), _directed(b, a))


def layout_distance(a: Scene, b: Scene, spacing_m: float = 0.25) -> float:
    """Layout distance (m) between two scenes: Hausdorff distance of their target-frame outlines (module docs)."""
    return hausdorff(layout_points(a, spacing_m), layout_points(b, spacing_m))


def nearest_train_distances(train: Sequence[Scene], test: Sequence[Scene], spacing_m: float = 0.25) -> np.ndarray:
    """Per test scene, the layout distance (m) to the nearest training scene with the same ``cell`` tag (inf when
    the cell has no training scene)."""
    cache = {id(s): layout_points(s, spacing_m) for s in list(train) + list(test)}
    out = np.full(len(test), np.inf)
    for i, t in enumerate(test):
        for s in train:
            if s.tags.get("cell") == t.tags.get("cell"):
                out[i] = min(out[i], hausdorff(cache[id(t)], cache[id(s)]))
    return out


def disjointness_floor(train: Sequence[Scene], test: Sequence[Scene], spacing_m: float = 0.25) -> float:
    """The structural-disjointness floor (m): min over test scenes of the distance to the nearest same-cell
    training scene (module docstring)."""
    return float(nearest_train_distances(train, test, spacing_m).min())
