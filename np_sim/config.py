"""Configuration dataclasses of the planning environment (spec §5). Defaults are the paper's numbers.

Every paper ablation is a ``dataclasses.replace`` of these (no LiDAR, fixed vs ensemble connector,
footprint vs reference-point checks), never a fork. ``from_dict`` rejects unknown keys.
"""

from __future__ import annotations

import dataclasses
import typing
from dataclasses import dataclass, field
from typing import Any, Literal

import numpy as np

from np_sim.errors import ConfigError
from np_sim.scene import SceneCapacity
from np_sim.vehicle import VehicleSpec

Convention = Literal["reference_point", "footprint"]
ConnectorMode = Literal["ensemble", "fixed"]
CONNECTOR_VARIANTS = ("fixed", "ensemble", "centred")
"""What a planner's ``connector`` override may name: the two modes, or ``"centred"`` (`ConnectorConfig.variant`)."""


@dataclass(frozen=True)
class ObservationConfig:
    """Which observation streams exist and their capacities (paper §III-B, App. A Table IV)."""

    use_obstacles: bool = True
    """Include the obstacle-vertex slots s^p, s^o."""
    use_boundary: bool = True
    """Include the boundary-segment slots s^b."""
    use_lidar: bool = True
    """Include the rectified LiDAR clearances s^ℓ."""
    max_obstacles: int = 20
    """Obstacle slots (object budget); a scene with more raises CapacityError."""
    vertices_per_obstacle: int = 8
    """Vertices per obstacle slot; shorter polygons repeat their vertices cyclically, circles are octagons."""
    max_boundary_segments: int = 10
    """Boundary slots of (x0, y0, x1, y1)."""
    sentinel: float = -1.0e4
    """Value of every unused slot entry."""
    n_beams: int = 120
    """LiDAR beams over 360°, beam 0 along the heading, counter-clockwise."""
    lidar_range_m: float = 10.0
    """LiDAR range cap (m)."""
    flat: bool = True
    """Flat Box observation (True) or a Dict of the streams (False)."""
    use_bev: bool = False
    """Include the BEV latent s^bev (paper App. B, the NeuralParker-backbone BEV control): the frozen encoder of
    ``bev_encoder_file`` applied to the ego-aligned raster (`np_sim.bev`, no trajectory tail) at every step;
    replaces the vertex slots, so ``use_obstacles`` and ``use_boundary`` must be off."""
    bev_encoder_file: str = ""
    """Pretrained BEV autoencoder file (``python -m np_policy.pretrain_bev``); required when ``use_bev``."""
    bev_latent_dim: int = 128
    """Size of the BEV latent; must equal the encoder's."""

    def __post_init__(self) -> None:
        if self.use_bev and not self.bev_encoder_file:
            raise ConfigError("ObservationConfig.bev_encoder_file: use_bev needs the pretrained autoencoder file "
                              "(python -m np_policy.pretrain_bev), got none")
        if self.use_bev and (self.use_obstacles or self.use_boundary):
            raise ConfigError("ObservationConfig.use_bev: the BEV latent replaces the vertex slots; set "
                              "use_obstacles and use_boundary to false")

    def capacity(self) -> SceneCapacity:
        """The scene limits this observation imposes."""
        return SceneCapacity(self.max_obstacles, self.vertices_per_obstacle, self.max_boundary_segments)


@dataclass(frozen=True)
class ConnectorConfig:
    """The in-loop Hermite terminal connector (paper §III-D, App. A Table IV)."""

    mode: ConnectorMode = "ensemble"
    """'ensemble' (81 candidates, eq:mincost) or 'fixed' (9 candidates, first feasible)."""
    offsets_m: tuple[float, ...] = (-0.1, 0.0, 0.1)
    """Lateral endpoint offsets in the target frame (m), outer candidate order."""
    headings_deg: tuple[float, ...] = (80.0, 90.0, 100.0)
    """Terminal headings in the target frame (deg; 90 = the target heading)."""
    scales: tuple[float, ...] = (0.8, 1.0, 1.2)
    """Independent tangent scales at both endpoints (ensemble only)."""
    n_samples: int = 100
    """Points per candidate for feasibility and curvature."""
    kappa_max: float = 0.68
    """Curvature bound on every sampled κ̄ (1/m)."""
    selection_kappa_weight: float = 10.0
    """c_sel on Δκ_H in eq:mincost."""
    selection_length_weight: float = 10.0
    """Weight on L_H in eq:mincost."""
    selection_constant: float = 5.0
    """Constant of eq:mincost."""
    heading_gate: bool = True
    """Only connect when sin θ̃ > 0 at the reached state."""

    def variant(self, name: str) -> "ConnectorConfig":
        """This connector as ``name`` (one of `CONNECTOR_VARIANTS`): ``"fixed"`` / ``"ensemble"`` set the mode;
        ``"centred"`` (beyond the paper) is the fixed mode with the same nine candidates tried target-aligned first
        — offsets by |offset|, headings by |heading − 90°|, ties in the listed order — so the first feasible one
        ends on the target pose when that one is feasible, where the paper's order (80° first) ends 10° off it,
        exactly at the closed loop's parking tolerance. Which starts connect does not change (any feasible
        candidate connects); only the chosen terminal segment does."""
        if name not in CONNECTOR_VARIANTS:
            raise ConfigError(f"connector: expected one of {CONNECTOR_VARIANTS}, got {name!r}")
        if name != "centred":
            return dataclasses.replace(self, mode=name)
        return dataclasses.replace(self, mode="fixed", offsets_m=tuple(sorted(self.offsets_m, key=abs)),
                                   headings_deg=tuple(sorted(self.headings_deg, key=lambda h: abs(h - 90.0))))

    def arrays(self):
        """(offsets, headings_rad, scales0, scales1) as float arrays for the kernels."""
        scales = np.array(self.scales, float) if self.mode == "ensemble" else np.array([1.0])
        return (np.array(self.offsets_m, float), np.radians(np.array(self.headings_deg, float)), scales, scales.copy())

    @property
    def n_candidates(self) -> int:
        """How many terminal Hermite candidates one connection tries (paper §III-D: offsets × headings, and with
        the ensemble × the scale pairs)."""
        n_scales = len(self.scales) ** 2 if self.mode == "ensemble" else 1
        return len(self.offsets_m) * len(self.headings_deg) * n_scales


@dataclass(frozen=True)
class RewardConfig:
    """Step, success and failure rewards (paper eq:step-reward, eq:terminal-reward)."""

    kappa_change_weight: float = 0.05
    """Weight on |κ_t − κ_{t−1}| per arc."""
    length_weight: float = 10.0
    """Weight on |l_t| per arc (per m)."""
    step_penalty: float = 5.0
    """Constant cost per arc."""
    reversal_penalty: float = 100.0
    """Cost of a gear change between consecutive arcs."""
    short_arc_weight: float = 2.0
    """Weight of the squared shortfall below ``short_arc_m``."""
    short_arc_m: float = 0.5
    """Arcs shorter than this (m) pay the short-arc term."""
    success_bonus: float = 1250.5
    """Constant of r^succ."""
    success_reversal_weight: float = 20.0
    """Weight on N_rev in r^succ."""
    success_kappa_weight: float = 1.0
    """Weight on Δκ_eff (eq:effective-kappa) in r^succ."""
    hermite_weight: float = 1.5
    """Weight of the Hermite score p_H in r^succ."""
    hermite_kappa_weight: float = 0.05
    """Weight on Δκ_H inside p_H."""
    hermite_length_weight: float = 10.0
    """Weight on L_H inside p_H."""
    hermite_constant: float = 5.0
    """Constant inside p_H."""
    hermite_floor: float = -500.0
    """Floor of p_H, applied with the ensemble connector only."""
    failure_penalty: float = -2501.0
    """Added on collision or boundary failure."""


@dataclass(frozen=True)
class EpisodeConfig:
    """Action bounds, tolerances and length of an episode (paper §III-A, Table IV)."""

    max_arcs: int = 200
    """Arcs per episode before truncation."""
    max_length_m: float = 10.0
    """|l| bound (m); the normalised action a_1 ∈ [−1, 1] maps to l = a_1 · max_length_m."""
    samples_per_arc: int = 30
    """Reference points checked along each learned arc."""
    position_tolerance_m: float = 0.1
    """Success radius around the target (m)."""
    heading_tolerance_deg: float = 10.0
    """Success heading tolerance (deg)."""


@dataclass(frozen=True)
class EnvConfig:
    """The full environment; the default is the paper's NeuralParker configuration (vertices + LiDAR, ensemble)."""

    vehicle: VehicleSpec = field(default_factory=VehicleSpec)
    observation: ObservationConfig = field(default_factory=ObservationConfig)
    connector: ConnectorConfig = field(default_factory=ConnectorConfig)
    reward: RewardConfig = field(default_factory=RewardConfig)
    episode: EpisodeConfig = field(default_factory=EpisodeConfig)
    collision: Convention = "reference_point"
    """'reference_point' (paper) or 'footprint' (full rectangle) for arcs and Hermite candidates."""

    def __post_init__(self) -> None:
        if self.collision not in ("reference_point", "footprint"):
            raise ConfigError(f"EnvConfig.collision: expected 'reference_point' or 'footprint', got {self.collision!r}")
        if self.connector.mode not in ("ensemble", "fixed"):
            raise ConfigError(f"ConnectorConfig.mode: expected 'ensemble' or 'fixed', got {self.connector.mode!r}")
        if self.connector.kappa_max > self.vehicle.kappa_max:
            raise ConfigError(
                f"ConnectorConfig.kappa_max={self.connector.kappa_max} exceeds "
                f"VehicleSpec.kappa_max={self.vehicle.kappa_max}"
            )

    def for_vehicle(self, vehicle: VehicleSpec) -> "EnvConfig":
        """This env for ``vehicle``: its footprint (checks, LiDAR ranges b_i), its κ_max as the action bound, and
        that κ_max as the connector's curvature bound κ̄ too (the paper's 0.68 is the default vehicle's)."""
        return dataclasses.replace(self, vehicle=vehicle,
                                   connector=dataclasses.replace(self.connector, kappa_max=vehicle.kappa_max))

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (JSON-safe)."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "EnvConfig":
        """Inverse of ``to_dict``; unknown keys are a ConfigError naming the field path."""
        return config_from_dict(cls, data)


def config_from_dict(cls, data, path: str | None = None):
    """Build the frozen config dataclass ``cls`` from a mapping, recursing into fields typed as dataclasses; lists
    become tuples. An unknown key or a non-mapping is a ConfigError naming its field path (``EnvConfig.reward``)."""
    path = cls.__name__ if path is None else path
    if not isinstance(data, dict):
        raise ConfigError(f"{path}: expected a mapping, got {type(data).__name__}")
    names = {f.name for f in dataclasses.fields(cls)}
    unknown = sorted(set(data) - names)
    if unknown:
        raise ConfigError(f"{path}: unknown key(s) {unknown}; expected some of {sorted(names)}")
    hints = typing.get_type_hints(cls)
    kwargs = {}
    for name, value in data.items():
        if dataclasses.is_dataclass(hints[name]):
            kwargs[name] = config_from_dict(hints[name], value, f"{path}.{name}")
        else:
            kwargs[name] = tuple(value) if isinstance(value, list) else value
    return cls(**kwargs)
