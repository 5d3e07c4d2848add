"""Configuration of the closed-loop testbed: one frozen dataclass per component (STYLE §2).

The vehicle's geometry (footprint, wheelbase, curvature bound) comes from `np_sim.vehicle.VehicleSpec`; these
configs hold only what the spec does not: masses, wheels, actuators, rates, gains and tolerances.
"""

from __future__ import annotations

import math

from dataclasses import dataclass, field, replace

from np_sim.config import config_from_dict
from np_sim.vehicle import VehicleSpec


@dataclass(frozen=True)
class VehicleModelConfig:
    """Physical parameters of the MJCF vehicle beyond `VehicleSpec` (see models/mjcf/vehicle_template.xml)."""

    timestep_s: float = 0.004
    """MuJoCo integration step (s)."""
    chassis_mass_kg: float = 1500.0
    """Mass of the chassis (kg)."""
    com_height_m: float = 0.55
    """Height of the chassis centre of mass above the ground (m)."""
    wheel_mass_kg: float = 20.0
    """Mass of each wheel (kg)."""
    knuckle_mass_kg: float = 5.0
    """Mass of each front steering knuckle (kg); its inertia is that of a 0.2 m solid sphere."""
    wheel_radius_m: float = 0.33
    """Tyre radius (m)."""
    tyre_width_m: float = 0.22
    """Tyre width (m), visual only."""
    wheel_inset_m: float = 0.2
    """Lateral distance from the body side to a wheel centre (m); track = width − 2·inset."""
    ground_clearance_m: float = 0.15
    """Height of the chassis box bottom above the ground (m)."""
    body_height_m: float = 1.5
    """Height of the chassis box top above the ground (m)."""
    tyre_friction: float = 1.0
    """Tyre–ground sliding friction coefficient."""
    wheel_damping: float = 0.5
    """Rolling resistance as viscous damping on each wheel hinge (N·m·s/rad)."""
    wheel_armature: float = 0.05
    """Rotor inertia added to each wheel hinge (kg·m²)."""
    steer_kp: float = 3000.0
    """Steering servo stiffness (N·m/rad)."""
    steer_kv: float = 150.0
    """Steering servo damping (N·m·s/rad)."""
    steer_damping: float = 5.0
    """Steering hinge damping (N·m·s/rad)."""
    steer_armature: float = 0.5
    """Steering hinge armature (kg·m²)."""
    steer_margin: float = 0.1
    """The mechanical steering reaches the curvature (1 + margin)·κ_max, leaving feedback authority on plans that
    steer at the planners' bound κ_max (0 = exactly the spec's bicycle angle atan(κ_max·L))."""
    steer_rate_max_rps: float = 0.8
    """Largest bicycle steering-angle rate the controller may command (rad/s)."""
    drive_torque_max_nm: float = 1500.0
    """Largest drive or brake torque per rear wheel (N·m)."""
    chase_back_m: float = 9.0
    """Chase camera distance behind the reference point (m)."""
    chase_up_m: float = 5.0
    """Chase camera height above the wheel centres (m)."""
    chase_pitch_deg: float = 25.0
    """Chase camera pitch below the horizon (deg)."""


@dataclass(frozen=True)
class PlantConfig:
    """How the simulated vehicle differs from the one planned and tracked for (`tracking.disturbance`): a payload
    and a longer body exist only in the MuJoCo model; the planners, the controllers' feed-forward mass and the
    footprint checks keep `VehicleSpec` and the nominal masses. The defaults are no difference."""

    payload_kg: float = 0.0
    """A point mass carried on the vehicle's centre line at the centre-of-mass height (kg)."""
    payload_x_m: float = 0.0
    """Where the payload sits, ahead of the reference point (m; 0 = over the rear axle)."""
    extra_length_m: float = 0.0
    """The chassis box is this much longer than ``VehicleSpec.length_m``, half at each end, without added mass
    (a tow bar, a bike rack); its contacts are the run's body contacts (m)."""

    def __post_init__(self) -> None:
        if not (self.payload_kg >= 0 and self.extra_length_m >= 0 and math.isfinite(self.payload_x_m)):
            raise ValueError(f"PlantConfig: expected payload_kg >= 0, extra_length_m >= 0 and a finite payload_x_m, "
                             f"got {self.payload_kg!r}, {self.extra_length_m!r}, {self.payload_x_m!r}")

    def body(self, spec: VehicleSpec) -> VehicleSpec:
        """The simulated body's footprint: ``spec`` with each overhang ``extra_length_m / 2`` longer."""
        if not self.extra_length_m:
            return spec
        half = 0.5 * self.extra_length_m
        return replace(spec, front_overhang_m=spec.front_overhang_m + half, rear_overhang_m=spec.rear_overhang_m + half)


@dataclass(frozen=True)
class WorldConfig:
    """How a scene becomes a MuJoCo world (extruded obstacles, boundary walls, ground)."""

    obstacle_height_m: float = 2.0
    """Height of extruded obstacles and circle cylinders (m)."""
    wall_height_m: float = 1.0
    """Height of the boundary walls (m)."""
    wall_thickness_m: float = 0.5
    """Thickness of the boundary walls, built outside the boundary (m)."""
    solid_obstacles: bool = True
    """True: obstacles, movers and walls are MuJoCo collision geoms that push the vehicle back. False (detection
    only): they do not collide; every control step the chassis's signed distance to each one near it is measured
    (``mujoco.mj_geomDistance``) and an overlap is recorded as a body contact, so the vehicle drives on through
    it (MuJoCo's margin/gap cannot do this: a penetrating contact is always active)."""


@dataclass(frozen=True)
class SpeedProfileConfig:
    """Speed profile of a gear segment: at rest at both ends, bounded speed, acceleration and steering rate."""

    forward_speed_mps: float = 2.0
    """Cruise speed in forward gear (m/s)."""
    reverse_speed_mps: float = 1.5
    """Cruise speed in reverse gear (m/s)."""
    accel_mps2: float = 1.0
    """Acceleration and deceleration bound along the path (m/s²)."""
    lateral_accel_mps2: float = 1.0
    """Lateral acceleration bound v²·|c| (m/s²)."""
    steer_window_m: float = 1.0
    """Path window over which a steering change is ramped in (m)."""
    steer_rate_share: float = 0.6
    """Share of the steering rate limit the profile plans the ramps with; the rest is left to feedback."""
    creep_speed_mps: float = 0.15
    """Least target speed until the end of a segment is reached (m)."""


@dataclass(frozen=True)
class LQRConfig:
    """LQR on the kinematic path-error model with a steering lag (see `tracking.controllers.lqr.lqr_gain`).

    Weights chosen on Hybrid A* plans from 81 seeded (seed 7) starts of the Factorial *train* scenes, never on the
    frozen test starts."""

    q_lateral: float = 1.0
    """Weight on the squared lateral error (1/m²)."""
    q_heading: float = 1.0
    """Weight on the squared heading error (1/rad²)."""
    r_curvature: float = 1.0
    """Weight on the squared curvature correction (m²)."""
    steer_time_constant_s: float = 0.3
    """First-order time constant τ of the steering response in the model (s)."""
    speed_grid_mps: tuple[float, ...] = (0.1, 0.2, 0.35, 0.5, 0.75, 1.0, 1.5, 2.0, 2.5, 3.0)
    """Speeds |v| at which gains are computed per gear; gains in between are interpolated (m/s)."""


@dataclass(frozen=True)
class StanleyConfig:
    """Stanley steering (Hoffmann et al. 2007) with curvature feed-forward."""

    gain: float = 1.5
    """Cross-track gain k of atan(k·e / (k_s + |v|)) (1/s)."""
    softening_mps: float = 0.5
    """Softening speed k_s (m/s)."""


@dataclass(frozen=True)
class PurePursuitConfig:
    """Pure pursuit on the rear axle (Coulter 1992), look-ahead growing with speed."""

    lookahead_min_m: float = 1.5
    """Look-ahead distance at standstill (m)."""
    lookahead_gain_s: float = 0.5
    """Added look-ahead per unit speed (s)."""


@dataclass(frozen=True)
class LongitudinalConfig:
    """PI speed control with acceleration feed-forward, output = drive force along the heading."""

    kp_per_s: float = 3.0
    """Proportional gain on the speed error, as an acceleration per m/s (1/s)."""
    ki_per_s2: float = 0.5
    """Integral gain on the speed error (1/s²)."""
    integral_limit_mps2: float = 0.5
    """Bound of the integral term, as an acceleration (m/s²)."""


@dataclass(frozen=True)
class ExecutorConfig:
    """Closed-loop run: control rate, end conditions and logging."""

    control_dt_s: float = 0.02
    """Control period (s); the physics substeps = control_dt_s / timestep_s."""
    reference_ds_m: float = 0.05
    """Reference path sample spacing (m)."""
    goal_position_tol_m: float = 0.3
    """Executed parking success: final reference point within this distance of the target (m)."""
    goal_heading_tol_deg: float = 10.0
    """Executed parking success: final heading within this angle of the target (deg)."""
    segment_end_tol_m: float = 0.05
    """A gear segment ends when the remaining path is below this (m) and the vehicle is at rest."""
    rest_speed_mps: float = 0.05
    """Speed under which the vehicle counts as at rest (m/s)."""
    steer_settle_rad: float = 0.05
    """At the start of a segment the vehicle waits until the steering is within this of the reference (rad)."""
    timeout_factor: float = 2.0
    """Timeout = factor × profile duration + margin (s)."""
    timeout_margin_s: float = 15.0
    """Timeout margin (s)."""
    stop_on_contact: bool = True
    """End the run at the first body contact (reason 'contact')."""
    curvature_tolerance: float = 0.05
    """Relative excess of |steer_curvature| over κ_max accepted as sampling noise before 'steering_limit'."""
    replan_period_s: float = 0.1
    """Period of the replanning callback in replanning mode (s)."""
    max_time_s: float = 120.0
    """Timeout of a replanning run (s)."""
    hold_max_s: float = 5.0
    """Replanning mode: how long a vehicle that finished its plan short of the parking tolerance stands and waits
    for a new plan before the run ends ('not_parked') (s)."""
    render_fps: float = 10.0
    """Rendered frames per second of sim time when rendering."""
    render_width: int = 320
    """Rendered frame width (px)."""
    render_height: int = 240
    """Rendered frame height (px)."""
    log_every: int = 5
    """Log the vehicle footprint to Rerun every this many control steps (scalars are logged every step)."""


@dataclass(frozen=True)
class TrackerConfig:
    """Everything the executor uses; `from_dict` rejects unknown keys."""

    vehicle: VehicleSpec = field(default_factory=VehicleSpec)
    """Footprint, wheelbase and curvature bound (the single source, spec §3)."""
    model: VehicleModelConfig = field(default_factory=VehicleModelConfig)
    """MJCF physics beyond the spec."""
    world: WorldConfig = field(default_factory=WorldConfig)
    """Scene extrusion."""
    profile: SpeedProfileConfig = field(default_factory=SpeedProfileConfig)
    """Speed profile and steering feed-forward window."""
    lqr: LQRConfig = field(default_factory=LQRConfig)
    """LQR lateral controller."""
    stanley: StanleyConfig = field(default_factory=StanleyConfig)
    """Stanley lateral controller."""
    pure_pursuit: PurePursuitConfig = field(default_factory=PurePursuitConfig)
    """Pure-pursuit lateral controller."""
    longitudinal: LongitudinalConfig = field(default_factory=LongitudinalConfig)
    """Speed controller."""
    executor: ExecutorConfig = field(default_factory=ExecutorConfig)
    """Closed-loop run settings."""
    plant: PlantConfig = field(default_factory=PlantConfig)
    """The simulated vehicle's differences from ``vehicle`` and ``model`` (default none)."""

    @classmethod
    def from_dict(cls, data) -> "TrackerConfig":
        """Build from a nested mapping; an unknown key is a ConfigError naming its field path."""
        return config_from_dict(cls, data)
