"""The target frame (paper eq:target-frame): target at the origin, target heading along +y."""

from __future__ import annotations

import math

import numpy as np

from np_sim.kinematics import wrap_angle


def to_target_frame(points, target) -> np.ndarray:
    """q̃ = R(π/2 − θ^g)(q − p^g) for points (..., 2) and target (x, y, θ) (paper eq:target-frame)."""
    q = np.asarray(points, float) - np.asarray(target[:2], float)
    a = 0.5 * math.pi - float(target[2])
    c, s = math.cos(a), math.sin(a)
    return np.stack([c * q[..., 0] - s * q[..., 1], s * q[..., 0] + c * q[..., 1]], axis=-1)


def from_target_frame(points, target) -> np.ndarray:
    """Inverse of ``to_target_frame``: q = p^g + R(θ^g − π/2) q̃."""
    q = np.asarray(points, float)
    a = float(target[2]) - 0.5 * math.pi
    c, s = math.cos(a), math.sin(a)
    return np.stack([c * q[..., 0] - s * q[..., 1] + target[0], s * q[..., 0] + c * q[..., 1] + target[1]], axis=-1)


def place(local, poses) -> np.ndarray:
    """Points ``local`` (k, 2) of a body frame (x forward, y left) placed at ``poses``: (k, 2) for one pose
    (x, y, θ), (n, k, 2) for poses of shape (n, 3); p = (x, y) + R(θ) q."""
    q = np.asarray(local, float)
    p = np.asarray(poses, float)
    c, s = np.cos(p[..., 2])[..., None], np.sin(p[..., 2])[..., None]
    x = p[..., 0:1] + c * q[:, 0] - s * q[:, 1]
    y = p[..., 1:2] + s * q[:, 0] + c * q[:, 1]
    return np.stack([x, y], axis=-1)


def pose_to_target_frame(pose, target) -> np.ndarray:
    """(x̃, ỹ, θ̃) with θ̃ = wrap(θ − θ^g + π/2) (paper eq:target-frame)."""
    xy = to_target_frame(np.asarray(pose[:2], float), target)
    return np.array([xy[0], xy[1], wrap_angle(float(pose[2]) - float(target[2]) + 0.5 * math.pi)])
