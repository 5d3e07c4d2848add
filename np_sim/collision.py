"""Path validity under the two collision conventions (spec §2), over the compiled kernels.

* ``"reference_point"`` (paper): every sampled reference point strictly inside the boundary and strictly outside
  every obstacle;
* ``"footprint"``: the full vehicle rectangle at every sample strictly inside the boundary and disjoint from every
  obstacle.
"""

from __future__ import annotations

import numpy as np

from np_sim.config import Convention
from np_sim.errors import ConfigError
from np_sim.kernels.collision import poses_valid
from np_sim.scene import Scene
from np_sim.scene_arrays import packed_scene
from np_sim.vehicle import VehicleSpec


def path_valid(scene: Scene, poses, convention: Convention = "reference_point",
               vehicle: VehicleSpec | None = None) -> bool:
    """True when every pose row (x, y, θ) is valid in ``scene`` under ``convention``.

    Rows of (x, y) are accepted for the reference-point convention (heading is irrelevant there).
    """
    if convention not in ("reference_point", "footprint"):
        raise ConfigError(f"path_valid: convention must be 'reference_point' or 'footprint', got {convention!r}")
    p = np.array(poses, dtype=float)  # a writeable copy: numba compiles a read-only array as another type
    if p.ndim != 2 or p.shape[1] not in (2, 3):
        raise ValueError(f"path_valid: expected poses of shape (N, 3) (or (N, 2) for reference points), got {p.shape}")
    if p.shape[1] == 2:
        if convention == "footprint":
            raise ValueError("path_valid: the footprint convention needs headings, got (N, 2) points")
        p = np.concatenate([p, np.zeros((len(p), 1))], axis=1)
    if not np.all(np.isfinite(p)):
        raise ValueError("path_valid: poses contain non-finite values")
    local = (VehicleSpec() if vehicle is None else vehicle).footprint_local()
    return bool(poses_valid(packed_scene(scene).geometry, 0, np.ascontiguousarray(p), convention == "footprint", local))
