"""Configuration of the adapted HOPE environment (paper §IV-B, App. B "Adaptation of HOPE"; spec §7).

Defaults are HOPE's published numbers (``jiamiya/HOPE`` ``src/configs.py``) with the paper's three task-side
changes: hard reference-point collision and boundary termination, Reeds–Shepp candidates checked under the
benchmark convention, and the fixed nine-candidate Hermite terminator. ``HopeEnvConfig()`` is the complete adapted
baseline; ``HopeEnvConfig.backbone(added_input)`` is a HOPE-style representation variant of paper Table III (mask and
RS takeover off, geodesic start curriculum at scale 0.05). ``from_dict`` rejects unknown keys and wrong types with
the field path.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass, field
from typing import Any, Literal

from np_policy.config import check_types
from np_sim.bev import BevConfig
from np_sim.config import ConnectorConfig, ObservationConfig, config_from_dict
from np_sim.curriculum import CurriculumSchedule
from np_sim.errors import ConfigError
from np_sim.vehicle import VehicleSpec

AddedInput = Literal["none", "bev", "vertices"]
ADDED_INPUTS = ("none", "bev", "vertices")

HOPE_ACTIONS = ("sampled", "mean")
"""How the adapted HOPE's planner picks each action (`hope_policy.planner`): HOPE's evaluation draw, or the mean."""


def _check_fields(obj: Any, positive: tuple[str, ...] = (), nonnegative: tuple[str, ...] = ()) -> None:
    """Type check every non-dataclass field of the frozen config ``obj`` (``check_types``), then the ranges."""
    cls = type(obj)
    scalars = {f.name: getattr(obj, f.name) for f in dataclasses.fields(cls)
               if not dataclasses.is_dataclass(getattr(obj, f.name))}
    check_types(cls, scalars)
    for name in positive + nonnegative:
        value = getattr(obj, name)
        low_ok = value > 0 if name in positive else value >= 0
        if not (math.isfinite(value) and low_ok):
            bound = "> 0" if name in positive else ">= 0"
            raise ConfigError(f"{cls.__name__}.{name}: expected a finite number {bound}, got {value!r}")


@dataclass(frozen=True)
class HopeRewardConfig:
    """HOPE's reward (``car_parking_base.py`` ``_get_reward``, ``env_wrapper.py`` ``reward_shaping``, REWARD_WEIGHT and
    REWARD_RATIO of ``configs.py``); HOPE's RS-distance and angle terms have weight 0 there and are left out."""

    time_cost_weight: float = 1.0
    """REWARD_WEIGHT['time_cost'] on −tanh(t / time_scale_steps)."""
    time_scale_steps: float = 2000.0
    """10 · TOLERANT_TIME: the step count scale of the time cost."""
    distance_weight: float = 5.0
    """REWARD_WEIGHT['dist_reward'] on the normalised decrease of the distance to the target."""
    distance_norm_min_m: float = 10.0
    """The distance reward divides by max(|start − target|, this) (m)."""
    box_union_weight: float = 10.0
    """REWARD_WEIGHT['box_union_reward'] on the increase of the best footprint–target IoU so far."""
    success_reward: float = 50.0
    """Reward on arrival (HOPE Status.ARRIVED), before the ratio."""
    collision_reward: float = -50.0
    """Reward on a hard collision (HOPE Status.COLLIDED), before the ratio."""
    boundary_reward: float = -50.0
    """Reward on leaving the boundary (HOPE Status.OUTBOUND), before the ratio."""
    timeout_reward: float = -1.0
    """Reward when the step budget runs out (HOPE Status.OUTTIME), before the ratio."""
    reward_ratio: float = 0.1
    """REWARD_RATIO: every reward above is multiplied by it."""

    def __post_init__(self) -> None:
        _check_fields(self, positive=("time_scale_steps", "distance_norm_min_m", "reward_ratio"))


@dataclass(frozen=True)
class HopeEnvConfig:
    """The adapted HOPE task (paper App. B); the default is the complete adapted baseline."""

    vehicle: VehicleSpec = field(default_factory=VehicleSpec)
    """Footprint of the hard checks, the LiDAR footprint ranges b_i, the mask and the box-union reward."""
    max_steer_rad: float = 0.75
    """VALID_STEER bound on the front-wheel angle δ (rad); learned curvature bound tan(δ_max)/wheelbase."""
    max_speed_mps: float = 2.5
    """VALID_SPEED bound on the speed v (m/s)."""
    rollout_s: float = 0.5
    """NUM_STEP × STEP_LENGTH = 10 × 0.05 s: how long one action is held (s); arc length l = v · rollout_s."""
    samples_per_arc: int = 30
    """Reference points of each learned arc or RS chunk checked against the scene."""
    max_steps: int = 200
    """TOLERANT_TIME: actions per episode before truncation."""
    position_tolerance_m: float = 0.1
    """Benchmark success radius around the target (m)."""
    heading_tolerance_deg: float = 10.0
    """Benchmark success heading tolerance (deg)."""
    collision: Literal["reference_point", "footprint"] = "reference_point"
    """Hard-check convention of arcs, RS candidates and Hermite candidates (paper: reference point)."""
    action_mask: bool = True
    """HOPE's 42-anchor LiDAR action mask: computed and put in the observation (``action_mask`` key)."""
    mask_iterations: int = 10
    """Poses per anchor rollout in the mask (HOPE ``ActionMask.n_iter``)."""
    mask_upsample: int = 10
    """Angular up-sampling of beams and swept distances in the mask (HOPE ``up_sample_rate``)."""
    mask_filter_width: int = 5
    """Width of the minimum filter over neighbouring steering anchors (HOPE ``post_process``)."""
    rs_takeover: bool = True
    """Shortest-first Reeds–Shepp takeover near the target."""
    rs_max_dist_m: float = 10.0
    """RS_MAX_DIST: RS candidates are searched when the target is closer than this (m)."""
    rs_spacing_m: float = 0.1
    """Spacing of the points at which RS candidates are generated and checked (m)."""
    rs_length_ratio: float = 1.6
    """Shortest-first search stops at a candidate longer than this × the shortest (from the third on)."""
    added_input: AddedInput = "none"
    """Added scene input of the representation variants: 'none', 'bev' or 'vertices'."""
    bev: BevConfig = field(default_factory=BevConfig)
    """The BEV raster of the 'bev' input (``np_sim.bev``: ego-aligned 64 × 64 RGB, HOPE's scale and colours)."""
    bev_tail: bool = True
    """Draw the trajectory tail (up to ``bev.tail_poses`` poses) in the BEV, as the HOPE-style control does."""
    observation: ObservationConfig = field(default_factory=ObservationConfig)
    """LiDAR beams and range, and the slot capacities of the 'vertices' input (its other fields are unused)."""
    connector: ConnectorConfig = field(default_factory=lambda: ConnectorConfig(mode="fixed"))
    """The attached Hermite terminator: the fixed nine candidates, 0.68 1/m cap on the terminator only."""
    curriculum: CurriculumSchedule = field(default_factory=lambda: CurriculumSchedule(enabled=False))
    """Start curriculum for the trainer (off for the complete baseline; geodesic at 0.05 for the backbones)."""
    reward: HopeRewardConfig = field(default_factory=HopeRewardConfig)
    """HOPE's reward terms and terminal rewards."""

    def __post_init__(self) -> None:
        _check_fields(self, positive=("max_steer_rad", "max_speed_mps", "rollout_s", "position_tolerance_m",
                                      "heading_tolerance_deg", "rs_max_dist_m", "rs_spacing_m", "rs_length_ratio"))
        for name in ("samples_per_arc", "max_steps", "mask_iterations", "mask_upsample", "mask_filter_width"):
            if getattr(self, name) < 1:
                raise ConfigError(f"HopeEnvConfig.{name}: expected an integer >= 1, got {getattr(self, name)!r}")
        if not self.max_steer_rad < 0.5 * math.pi:
            raise ConfigError(
                f"HopeEnvConfig.max_steer_rad: expected a steering angle below π/2, got {self.max_steer_rad}")
        if self.connector.kappa_max > self.vehicle.kappa_max:
            raise ConfigError(f"HopeEnvConfig.connector.kappa_max={self.connector.kappa_max} exceeds "
                              f"HopeEnvConfig.vehicle.kappa_max={self.vehicle.kappa_max}")
        if self.connector.mode not in ("fixed", "ensemble"):
            raise ConfigError(
                f"HopeEnvConfig.connector.mode: expected 'fixed' or 'ensemble', got {self.connector.mode!r}")

    @property
    def kappa_max(self) -> float:
        """Learned-action curvature bound tan(δ_max) / wheelbase (1/m): ≈ 0.333 for HOPE's numbers."""
        return math.tan(self.max_steer_rad) / self.vehicle.wheelbase_m

    @property
    def max_length_m(self) -> float:
        """Longest arc of one action, v_max · rollout_s (m): 1.25 for HOPE's numbers."""
        return self.max_speed_mps * self.rollout_s

    @classmethod
    def backbone(cls, added_input: str = "none", **overrides: Any) -> "HopeEnvConfig":
        """A HOPE-style representation variant (paper App. B, Table III): mask and RS takeover disabled, fixed
        Hermite kept, geodesic start curriculum at scale 0.05, and ``added_input`` as the only difference."""
        if added_input not in ADDED_INPUTS:
            raise ConfigError(f"HopeEnvConfig.added_input: expected one of {ADDED_INPUTS}, got {added_input!r}")
        return cls(action_mask=False, rs_takeover=False, added_input=added_input,
                   curriculum=CurriculumSchedule(enabled=True, start_fraction=0.05), **overrides)

    def to_dict(self) -> dict[str, Any]:
        """Plain nested dict (JSON-safe)."""
        return dataclasses.asdict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> "HopeEnvConfig":
        """Inverse of ``to_dict``; unknown keys and values of the wrong type are a ConfigError naming the field."""
        check_types(cls, data)
        return config_from_dict(cls, data)
