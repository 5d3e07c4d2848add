"""Hermite terminal connector (paper §III-D: eq:hermite, eq:hermite-kappa, eq:mincost).

``connect`` is the connector of the environment, exposed for planners and tests; the environment calls the same
kernels (``np_sim.kernels.hermite``) inside its compiled step.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from np_sim.config import ConnectorConfig, Convention
from np_sim.errors import ConfigError
from np_sim.kinematics import wrap_angle
from np_sim.frames import from_target_frame, pose_to_target_frame
from np_sim.kernels.hermite import build_candidates, discrete_curvature_kernel, hermite_basis, select_candidate
from np_sim.scene import Scene
from np_sim.scene_arrays import packed_scene
from np_sim.vehicle import VehicleSpec


def hermite_curve(g0, g1, d0, d1, n: int = 100) -> np.ndarray:
    """(n, 2) points g(t_j), t_j = j/(n−1), of the cubic Hermite curve eq:hermite with endpoints g0, g1 and
    tangents d0, d1."""
    if int(n) < 2:
        raise ValueError(f"hermite_curve: n must be >= 2, got {n}")
    b, _ = hermite_basis(int(n))
    g = np.array([np.asarray(v, float) for v in (g0, g1, d0, d1)])  # (4, 2)
    return b.T @ g


def discrete_curvature(points, kappa0: float):
    """eq:hermite-kappa on sampled points (N, 2): returns (κ̄ (N−2,), Δκ_H, L_H).

    κ̄_j = ‖v̂_{j+1} − v̂_j‖/(Δt‖v_j‖) ≥ 0, Δκ_H = |κ0 − κ̄_0| + Σ_{j=1}^{N−3}|κ̄_j − κ̄_{j−1}| with κ0 the signed
    curvature of the preceding action arc, L_H the polyline length.
    """
    pts = np.ascontiguousarray(points, dtype=float)
    if pts.ndim != 2 or pts.shape[1] != 2 or pts.shape[0] < 3:
        raise ValueError(f"discrete_curvature: expected points of shape (N >= 3, 2), got {pts.shape}")
    n = pts.shape[0]
    kbar = np.empty(n - 2)
    _, dk, length = discrete_curvature_kernel(np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1]),
                                              float(kappa0), kbar, np.empty(n - 1), np.empty(n - 1), np.empty(n - 1))
    return kbar, dk, length


@dataclass(frozen=True)
class Connection:
    """A selected Hermite terminal segment."""

    points: np.ndarray
    """(N, 2) world-frame samples; the first is the connected pose's position, the last the terminal point."""
    forward: bool
    """Drive direction along the segment."""
    length: float
    """Sampled length L_H (m)."""
    delta_kappa: float
    """Δκ_H of eq:hermite-kappa (1/m)."""
    kbar_max: float
    """Largest sampled curvature κ̄ (1/m)."""
    cost: float
    """Selection cost of eq:mincost."""
    offset_m: float
    """Lateral endpoint offset in the target frame (m)."""
    heading_rad: float
    """Terminal heading in the target frame (rad; π/2 = target heading)."""
    scales: tuple[float, float]
    """Tangent scales (s0, s1)."""
    index: int
    """Candidate index in the connector's order."""
    terminal_pose: np.ndarray
    """World pose [x, y, θ] at the end of the segment."""


class CandidateSet:
    """Scratch buffers and the candidate grid of one connector config (reused across calls)."""

    def __init__(self, config: ConnectorConfig):
        self.config = config
        self.offsets, self.headings, self.scales0, self.scales1 = config.arrays()
        n = config.n_candidates
        self.basis, self.dbasis = hermite_basis(config.n_samples)
        self.pts = np.empty((n, 2, config.n_samples))  # (candidate, x/y, sample)
        self.kbar_max = np.empty(n)
        self.dk = np.empty(n)
        self.lengths = np.empty(n)
        self.costs = np.empty(n)

    def build(self, pose_t: np.ndarray, kappa0: float, forward: bool) -> int:
        """Fill the buffers for a target-frame pose; returns the candidate count."""
        c = self.config
        return build_candidates(
            pose_t[0], pose_t[1], pose_t[2], forward, float(kappa0), self.offsets, self.headings, self.scales0,
            self.scales1, self.basis, c.selection_kappa_weight, c.selection_length_weight, c.selection_constant,
            self.pts, self.kbar_max, self.dk, self.lengths, self.costs,
        )

    def decode(self, index: int) -> tuple[int, int, int, int]:
        """(offset, heading, scale0, scale1) indices of a candidate index."""
        n1, n0, nh = len(self.scales1), len(self.scales0), len(self.headings)
        return index // (n1 * n0 * nh), (index // (n1 * n0)) % nh, (index // n1) % n0, index % n1


def connect(
    scene: Scene,
    pose,
    prev_kappa: float,
    mode: str = "ensemble",
    *,
    config: ConnectorConfig | None = None,
    convention: Convention = "reference_point",
    vehicle: VehicleSpec | None = None,
) -> Connection | None:
    """Terminal Hermite connection from ``pose`` to the scene's target, or None.

    Gate: only when sin θ̃ > 0 at ``pose`` (config.heading_gate). Direction: forward tangents when ỹ < 0, reverse
    otherwise. ``mode="ensemble"``: the feasible candidate of least eq:mincost among 81; ``mode="fixed"``: the first
    feasible of the 9 baseline candidates (offsets outer, headings inner).
    """
    if mode not in ("ensemble", "fixed"):
        raise ConfigError(f"connect: mode must be 'ensemble' or 'fixed', got {mode!r}")
    if convention not in ("reference_point", "footprint"):
        raise ConfigError(f"connect: convention must be 'reference_point' or 'footprint', got {convention!r}")
    config = ConnectorConfig(mode=mode) if config is None else config
    if config.mode != mode:
        raise ConfigError(f"connect: mode={mode!r} disagrees with config.mode={config.mode!r}")
    vehicle = VehicleSpec() if vehicle is None else vehicle
    target = np.array(scene.target, float)  # a writeable copy: numba compiles a read-only array as another type
    pose_t = pose_to_target_frame(np.asarray(pose, float), target)
    if config.heading_gate and not math.sin(pose_t[2]) > 0.0:
        return None
    forward = bool(pose_t[1] < 0.0)
    cands = _candidate_sets(config)
    n = cands.build(pose_t, prev_kappa, forward)
    arrays = packed_scene(scene)
    idx = select_candidate(
        arrays.geometry, 0, target, pose_t[0], pose_t[1], pose_t[2], forward, cands.offsets, cands.headings,
        cands.scales0, cands.scales1, cands.dbasis, cands.pts, cands.kbar_max, cands.costs, n, mode == "ensemble",
        config.kappa_max, convention == "footprint", vehicle.footprint_local(),
    )
    if idx < 0:
        return None
    io, ih, i0, i1 = cands.decode(idx)
    return Connection(
        points=from_target_frame(cands.pts[idx].T, target),
        forward=forward,
        length=float(cands.lengths[idx]),
        delta_kappa=float(cands.dk[idx]),
        kbar_max=float(cands.kbar_max[idx]),
        cost=float(cands.costs[idx]),
        offset_m=float(cands.offsets[io]),
        heading_rad=float(cands.headings[ih]),
        scales=(float(cands.scales0[i0]), float(cands.scales1[i1])),
        index=int(idx),
        terminal_pose=np.array([*from_target_frame(cands.pts[idx, :, -1], target),
                                wrap_angle(float(cands.headings[ih]) + float(target[2]) - 0.5 * math.pi)]),
    )


_CANDIDATE_SETS: dict[ConnectorConfig, CandidateSet] = {}


def _candidate_sets(config: ConnectorConfig) -> CandidateSet:
    if config not in _CANDIDATE_SETS:
        _CANDIDATE_SETS[config] = CandidateSet(config)
    return _CANDIDATE_SETS[config]
