"""Arc kinematics of the NeuralParker action (paper eq:arc, spec §2).

Under eq:arc the heading changes by −sgn(κ)·|lκ| whatever the gear, so the *physical* steering curvature a
tracker must command (positive = left turn) is ``steer_curvature = −sgn(l)·κ``. The arc (κ, l) is retraced
exactly by (−κ, −l).
"""

from __future__ import annotations

import math

import numpy as np

from np_sim.kernels.kinematics import arc_point, sample_arc_into, wrap_angle

__all__ = ["arc_step", "sample_arc", "steer_curvature", "wrap_angle"]


def _pose3(pose) -> tuple[float, float, float]:
    p = np.asarray(pose, dtype=float)
    if p.shape != (3,) or not np.all(np.isfinite(p)):
        raise ValueError(f"pose: expected a finite [x, y, θ] of shape (3,), got {pose!r}")
    return float(p[0]), float(p[1]), float(p[2])


def arc_step(pose, kappa: float, length: float) -> np.ndarray:
    """Pose [x, y, θ] reached by the arc (κ, l) from ``pose`` (paper eq:arc); θ wrapped to (−π, π]."""
    return np.array(arc_point(*_pose3(pose), float(kappa), float(length)))


def sample_arc(pose, kappa: float, length: float, n: int = 30) -> np.ndarray:
    """(n, 3) poses at arc lengths l·j/n, j = 1..n, along the arc (κ, l) (paper eq:arc); the last row is the end."""
    if int(n) < 1:
        raise ValueError(f"sample_arc: n must be >= 1, got {n}")
    out = np.empty((int(n), 3))
    sample_arc_into(*_pose3(pose), float(kappa), float(length), out)
    return out


def steer_curvature(kappa, length):
    """Physical steering curvature c = −sgn(l)·κ (positive = left) of the arc (κ, l) (spec §2)."""
    return -np.sign(length) * np.asarray(kappa, dtype=float)


def heading_gap(theta: float, target_theta: float) -> float:
    """|θ − θ_target| wrapped to [0, π] (rad): how far a heading is from a target's, either way round."""
    return abs(math.remainder(float(theta) - float(target_theta), 2.0 * math.pi))
