"""The site's rule for a scene with more obstacles than the observation has slots (spec §4, paper App. C).

A recorded parking lot holds 60–120 parked cars near the route; the policy has ``max_obstacles`` slots (20 on the
benchmarks, 10 at the site). Under this rule the policy's obstacle slots hold the ``max_obstacles`` obstacles
nearest to the vehicle's current reference point (Euclidean distance to the observed polygon, 0 inside; ties by
scene order), nearest first, re-selected after every arc from the pose it reached: the delivery site's clips keep
the ten detections nearest the vehicle the same way (`np_sim.clips.Clip.frame_scene`). Everything else stays on
the whole scene: the LiDAR (a range sensor, it sees every object within its range), the arc and connector
collision checks of the rollout, and every validation of a plan. A scene within the slots is observed exactly as
before (scene order, computed once), so its plans are unchanged. The polygon-vertex and boundary-segment limits
are not relaxed: a scene beyond them is still a `CapacityError`.
"""

from __future__ import annotations

import dataclasses
import weakref

import numpy as np

from np_sim.config import ObservationConfig
from np_sim.frames import to_target_frame
from np_sim.kernels.nearest import point_polygon_distances
from np_sim.observation import boundary_slots
from np_sim.scene import Scene


def exceeds_slots(scene: Scene, config: ObservationConfig) -> bool:
    """The observation encodes obstacles and ``scene`` has more of them than its ``max_obstacles`` slots."""
    return config.use_obstacles and len(scene.obstacles) > config.max_obstacles


class NearestObjects:
    """The obstacle slots of an over-capacity scene as a function of the vehicle pose (module docstring). It keeps
    no reference to the scene, so that `nearest_objects` can cache it by the scene."""

    def __init__(self, scene: Scene, config: ObservationConfig):
        # every limit but the obstacle count still holds (CapacityError naming it otherwise)
        scene.check_capacity(dataclasses.replace(config.capacity(), max_obstacles=len(scene.obstacles)),
                             source=scene.name or "<scene>")
        self.config = config
        polygons = scene.polygons_for_observation()
        self._counts = np.array([len(p) for p in polygons], np.int64)
        self._verts = np.zeros((len(polygons), int(self._counts.max()), 2))
        for j, p in enumerate(polygons):
            self._verts[j, : len(p)] = p
        cyclic = np.arange(config.vertices_per_obstacle)[None, :] % self._counts[:, None]
        local = to_target_frame(self._verts, scene.target)
        self._rows = np.take_along_axis(local, cyclic[:, :, None], axis=1).reshape(len(polygons), -1)
        self._static = self._static_row(scene)

    def indices(self, poses) -> np.ndarray:
        """(m, max_obstacles) scene indices of the obstacles each pose row (x, y[, θ]) observes, nearest first."""
        xy = np.ascontiguousarray(np.atleast_2d(np.asarray(poses, np.float64))[:, :2])
        distance = np.empty((len(xy), len(self._counts)))
        point_polygon_distances(xy, self._verts, self._counts, distance)
        return np.argsort(distance, axis=1, kind="stable")[:, : self.config.max_obstacles]

    def slots(self, poses) -> np.ndarray:
        """(m, max_obstacles · 2 · vertices) target-frame obstacle slots of each pose row (the observation's
        obstacle part, `np_sim.observation.obstacle_slots` layout)."""
        index = self.indices(poses)
        return self._rows[index].reshape(len(index), -1)

    def static_row(self) -> np.ndarray:
        """The scene-constant tail of the flat observation with the obstacle slots at the sentinel (they are
        written per pose by ``slots``) and the boundary slots as usual."""
        return self._static

    def _static_row(self, scene: Scene) -> np.ndarray:
        parts = []
        if self.config.use_obstacles:
            parts.append(np.full(self.config.max_obstacles * 2 * self.config.vertices_per_obstacle,
                                 self.config.sentinel))
        if self.config.use_boundary:
            bare = Scene(scene.boundary, (), scene.target, None, name=scene.name)
            parts.append(boundary_slots(bare, self.config).reshape(-1))
        return np.concatenate(parts) if parts else np.zeros(0)


_SELECTORS: "weakref.WeakKeyDictionary[Scene, dict[ObservationConfig, NearestObjects]]" = weakref.WeakKeyDictionary()


def nearest_objects(scene: Scene, config: ObservationConfig) -> NearestObjects:
    """``NearestObjects(scene, config)``, cached per scene object and observation config (scenes are immutable;
    a planner call builds several rollout envs on one scene)."""
    by_config = _SELECTORS.setdefault(scene, {})
    if config not in by_config:
        by_config[config] = NearestObjects(scene, config)
    return by_config[config]
