"""Disturbances of the closed loop (beyond the paper): one factor at a time, for the robustness study
(`experiments.robustness`, docs/robustness.md).

A `Disturbance` is a factor of ``FACTORS``, its magnitude (``value``; 0 = no change at all: the run is the
undisturbed one, bit for bit) and a seed. It acts in one of three places:

* the **physical vehicle** (`Disturbance.tracker`): tyre friction, a payload that shifts the centre of mass, a
  chassis body longer than the planned `VehicleSpec` (`tracking.config.PlantConfig`). The planners, the
  controllers' feed-forward masses and the footprint checks keep the nominal vehicle; MuJoCo simulates the other
  one, and its chassis box is what body contacts are measured with;
* the **vehicle's sensing** (`Disturbance.perceive`, `RunHooks.sensed`): the detections the planner gets, and the
  localisation error of the pose that both the planner and the controller use (the simulator keeps the truth);
* the **actuation** (`RunHooks.actuate`): the command delayed by k control periods, or a steering actuator slower
  than the one the controller and the speed profile assume.

Levels (mild / moderate / severe) and why:

* ``detection_noise`` — σ = 0.05 / 0.15 / 0.30 m: each detected object shifted by an isotropic Gaussian offset.
  The clips' own vertex jitter is a few centimetres; 0.15 m is a typical camera-radar fusion error at parking
  range, 0.30 m a poor monocular estimate.
* ``detection_drop`` — p = 0.1 / 0.3 / 0.5: each detection of a frame missed independently (occlusion, a
  detector's false negatives); a missed object is absent from that frame's scene.
* ``pose_noise`` — σ = 0.05 / 0.10 / 0.20 m: the localisation estimate, updated at 10 Hz and held in between,
  is the truth plus white noise (σ on x and y, σ · 0.1 rad/m on the heading: 0.3° / 0.6° / 1.1°) plus a
  random-walk drift whose standard deviation reaches σ after 30 s. 0.05 m is a good RTK-GNSS / lidar map match,
  0.20 m with a drifting heading an odometry-only estimate.
* ``latency`` — 0.1 / 0.2 / 0.3 s: steering and drive commands reach the actuators this much later (k = 5 / 10 /
  15 control periods of 0.02 s): a drive-by-wire bus and slow servo firmware; 0.3 s is the issue's bound.
* ``steer_rate`` — 25 / 50 / 75 % slower: the steering actuator turns the wheels at most (1 − value) of the
  ``VehicleModelConfig.steer_rate_max_rps`` the controller and the profile assume (0.6 / 0.4 / 0.2 rad/s of
  0.8): the profile ramps at 60 % of the nominal rate, so mild barely binds and severe binds on every ramp.
* ``friction`` — μ down by 30 / 45 / 60 %: 0.7 / 0.55 / 0.4 of the nominal 1.0 (damp asphalt, wet asphalt,
  wet leaves or packed snow).
* ``payload`` — +20 / 40 / 60 % of the chassis mass (300 / 600 / 900 kg) as a point load over the rear axle:
  the centre of mass moves 0.24 / 0.40 / 0.53 m rearwards (a full boot and rear seats, a trailer-like load).
* ``body_length`` — +3.3 / 6.7 / 10 % of the length (0.16 / 0.31 / 0.47 m for the default spec), half at each
  end: a tow bar, a bike rack, a longer vehicle than the one planned for.
"""

from __future__ import annotations

import dataclasses
import math
import zlib
from collections import deque
from dataclasses import dataclass

import numpy as np
import shapely

from np_sim.errors import ConfigError
from np_sim.scene import CircleObstacle, PolygonObstacle, Scene, obstacle_shape
from tracking.config import TrackerConfig

LEVELS = ("mild", "moderate", "severe")
"""The disturbed levels, beside the undisturbed run ('none', value 0)."""


@dataclass(frozen=True)
class Factor:
    """One disturbance factor: where it acts, its magnitudes and how a magnitude reads."""

    name: str
    group: str
    """'perception', 'localisation', 'control' or 'vehicle'."""
    levels: tuple[float, float, float]
    """Magnitudes of the mild, moderate and severe levels (0 = no change)."""
    unit: str
    """How a magnitude reads, a format with ``{v}``."""
    upper: float = math.inf
    """Magnitudes must lie in [0, upper)."""

    def setting(self, value: float) -> str:
        """The physical setting of magnitude ``value``, e.g. 'σ = 0.15 m'."""
        return "none" if value == 0 else self.unit.format(v=value, f=1.0 - value)


FACTORS = {f.name: f for f in (
    Factor("detection_noise", "perception", (0.05, 0.15, 0.30), "σ = {v:g} m"),
    Factor("detection_drop", "perception", (0.1, 0.3, 0.5), "p = {v:g}", upper=1.0),
    Factor("pose_noise", "localisation", (0.05, 0.10, 0.20), "σ = {v:g} m + drift"),
    Factor("latency", "control", (0.1, 0.2, 0.3), "{v:g} s"),
    Factor("steer_rate", "control", (0.25, 0.5, 0.75), "{f:.0%} of the rate", upper=1.0),
    Factor("friction", "vehicle", (0.3, 0.45, 0.6), "μ × {f:g}", upper=1.0),
    Factor("payload", "vehicle", (0.2, 0.4, 0.6), "+{v:.0%} mass"),
    Factor("body_length", "vehicle", (0.033, 0.067, 0.10), "+{v:.1%} length"),
)}
"""The eight factors in study order (module docstring)."""

LOCALISATION_PERIOD_S = 0.1
"""The localisation estimate is updated this often and held in between (s)."""
HEADING_PER_M = 0.1
"""Heading noise per metre of position noise (rad/m)."""
DRIFT_TIME_S = 30.0
"""The drift's standard deviation reaches the position σ after this time (s)."""
_BLOCK = 256
"""Localisation updates drawn at a time (fixed, so a run's errors do not depend on when they are asked for)."""


@dataclass(frozen=True)
class Disturbance:
    """One factor of ``FACTORS`` at magnitude ``value`` (0 = none), with the seed of its random draws."""

    factor: str
    value: float
    seed: int = 0

    def __post_init__(self) -> None:
        if self.factor not in FACTORS:
            raise ConfigError(f"Disturbance.factor: expected one of {list(FACTORS)}, got {self.factor!r}")
        upper = FACTORS[self.factor].upper
        if not (isinstance(self.value, (int, float)) and 0.0 <= self.value < upper):
            raise ConfigError(f"Disturbance.value of {self.factor}: expected a number in [0, {upper}), got "
                              f"{self.value!r}")
        if isinstance(self.seed, bool) or not isinstance(self.seed, int) or self.seed < 0:
            raise ConfigError(f"Disturbance.seed: expected an integer >= 0, got {self.seed!r}")

    @classmethod
    def at(cls, factor: str, level: str, seed: int = 0) -> "Disturbance":
        """``factor`` at the named level ('none' or one of ``LEVELS``)."""
        if factor not in FACTORS:
            raise ConfigError(f"factor: expected one of {list(FACTORS)}, got {factor!r}")
        if level != "none" and level not in LEVELS:
            raise ConfigError(f"level: expected 'none' or one of {LEVELS}, got {level!r}")
        return cls(factor, 0.0 if level == "none" else FACTORS[factor].levels[LEVELS.index(level)], seed)

    @property
    def group(self) -> str:
        """Where the factor acts: 'perception', 'localisation', 'control' or 'vehicle'; 'none' at magnitude 0."""
        return FACTORS[self.factor].group if self.value else "none"

    @property
    def setting(self) -> str:
        """The physical setting, e.g. 'μ × 0.55'."""
        return FACTORS[self.factor].setting(self.value)

    def tracker(self, config: TrackerConfig) -> TrackerConfig:
        """``config`` with the physical factors applied (friction, payload, body length); else ``config`` itself."""
        if self.group != "vehicle":
            return config
        model, plant = config.model, config.plant
        if self.factor == "friction":
            model = dataclasses.replace(model, tyre_friction=model.tyre_friction * (1.0 - self.value))
        elif self.factor == "payload":
            plant = dataclasses.replace(plant, payload_kg=plant.payload_kg + self.value * model.chassis_mass_kg,
                                        payload_x_m=0.0)
        else:
            plant = dataclasses.replace(plant, extra_length_m=plant.extra_length_m
                                        + self.value * config.vehicle.length_m)
        return dataclasses.replace(config, model=model, plant=plant)

    def perceive(self, run_key: str, frame: int, ids: np.ndarray, polygons: np.ndarray,
                 keep_clear=None) -> tuple[np.ndarray, np.ndarray]:
        """The detections (ids (n,), polygons (n, k, 2)) of ``frame`` as the disturbed perception reports them:
        each shifted by N(0, σ²) per axis (``detection_noise``) or dropped with probability p
        (``detection_drop``); unchanged for the other factors. Each detection's draws are seeded by (seed,
        ``run_key``, ``frame``, its object id), so they depend neither on the call order nor on the detections'
        order. A shifted detection that would overlap ``keep_clear`` (a shapely geometry, the target footprint: a scene
        must keep its target free) keeps its recorded place."""
        if self.group != "perception":
            return ids, polygons
        shift, draw = self._draws(run_key, frame, ids)
        if self.factor == "detection_drop":
            kept = draw >= self.value
            return ids[kept], polygons[kept]
        moved = polygons + self.value * shift[:, None, :]
        if keep_clear is not None and len(ids):
            blocked = shapely.intersects(shapely.polygons(moved), keep_clear)
            moved[blocked] = polygons[blocked]
        return ids, moved

    def perceive_scene(self, run_key: str, scene: Scene, keep_clear=None) -> Scene:
        """``scene`` as the disturbed perception reports it once, before planning (a frozen-start episode): its
        obstacles, numbered in scene order, shifted or dropped as `perceive` does detections of frame 0 (a circle
        moves its centre); a shifted obstacle that would overlap ``keep_clear`` keeps its place. The boundary and
        the target are map knowledge and stay. ``scene`` itself for the other factors."""
        if self.group != "perception" or not scene.obstacles:
            return scene
        shift, draw = self._draws(run_key, 0, np.arange(len(scene.obstacles)))
        if self.factor == "detection_drop":
            kept = tuple(o for o, d in zip(scene.obstacles, draw) if d >= self.value)
            return dataclasses.replace(scene, obstacles=kept)
        moved = []
        for obstacle, offset in zip(scene.obstacles, self.value * shift):
            new = (CircleObstacle(obstacle.center + offset, obstacle.radius) if isinstance(obstacle, CircleObstacle)
                   else PolygonObstacle(obstacle.vertices + offset))
            blocked = keep_clear is not None and shapely.intersects(obstacle_shape(new), keep_clear)
            moved.append(obstacle if blocked else new)
        return dataclasses.replace(scene, obstacles=tuple(moved))

    def _draws(self, run_key: str, frame: int, ids: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per object: a standard normal 2-D offset and a uniform draw, seeded by (seed, ``run_key``, ``frame``,
        object id) so they depend neither on the call order nor on the objects' order."""
        shift, draw = np.zeros((len(ids), 2)), np.zeros(len(ids))
        for j, object_id in enumerate(ids):
            rng = np.random.default_rng([self.seed, _key(run_key), int(frame), int(object_id)])
            shift[j], draw[j] = rng.normal(0.0, 1.0, 2), rng.random()
        return shift, draw

    def hooks(self, run_key: str, config: TrackerConfig) -> "RunHooks | None":
        """The run-time side of one run (``run_key``: e.g. the clip name; the draws are seeded by it and the seed,
        the same for every planner): a localisation error or an actuator; None for the other factors."""
        if self.group not in ("localisation", "control"):
            return None
        if self.factor == "pose_noise":
            return RunHooks(pose_error=PoseError(self.value, np.random.default_rng([self.seed, _key(run_key)])))
        dt = config.executor.control_dt_s
        if self.factor == "latency":
            periods = round(self.value / dt)
            if periods < 1 or abs(periods * dt - self.value) > 1e-9:
                raise ConfigError(f"latency {self.value} s: expected a whole number (>= 1) of control periods of "
                                  f"{dt} s")
            return RunHooks(actuator=Actuator(delay_periods=periods))
        from tracking.controllers import SteeringLimiter
        from tracking.mjcf import max_steer_rad

        rate = (1.0 - self.value) * config.model.steer_rate_max_rps
        limiter = SteeringLimiter(config.vehicle.wheelbase_m, max_steer_rad(config.vehicle, config.model), rate, dt)
        return RunHooks(actuator=Actuator(rate_limiter=limiter))


def _key(text: str) -> int:
    """A stable integer of ``text`` for seeding (Python's ``hash`` of a string changes between processes)."""
    return zlib.crc32(text.encode())


class PoseError:
    """The localisation error (dx, dy, dθ) of a run as a function of sim time: per 10 Hz update, white noise
    N(0, σ²) (σ · ``HEADING_PER_M`` on the heading) plus a random-walk drift whose sd reaches σ after
    ``DRIFT_TIME_S``; held between updates."""

    def __init__(self, sigma_m: float, rng: np.random.Generator):
        self.sigma = sigma_m * np.array([1.0, 1.0, HEADING_PER_M])
        self.drift_step = self.sigma * math.sqrt(LOCALISATION_PERIOD_S / DRIFT_TIME_S)
        self.rng = rng
        self.errors = np.zeros((0, 3))
        self.drift = np.zeros(3)

    def __call__(self, t: float) -> np.ndarray:
        n = int(math.floor(t / LOCALISATION_PERIOD_S + 1e-9))
        while len(self.errors) <= n:
            steps = self.drift + np.cumsum(self.rng.normal(0.0, 1.0, (_BLOCK, 3)) * self.drift_step, axis=0)
            self.drift = steps[-1]
            self.errors = np.vstack([self.errors, steps + self.rng.normal(0.0, 1.0, (_BLOCK, 3)) * self.sigma])
        return self.errors[n]


class Actuator:
    """What reaches the actuators: the (steering curvature, wheel torque) commands delayed by ``delay_periods``
    control periods (the vehicle at rest, straight wheels and no torque before the first one arrives), or the
    steering through a slower rate limiter (`tracking.controllers.SteeringLimiter`)."""

    def __init__(self, delay_periods: int = 0, rate_limiter=None):
        self.queue = deque([(0.0, 0.0)] * delay_periods)
        self.rate_limiter = rate_limiter

    def __call__(self, curvature: float, torque: float) -> tuple[float, float]:
        if self.queue:
            self.queue.append((curvature, torque))
            curvature, torque = self.queue.popleft()
        if self.rate_limiter is not None:
            curvature = self.rate_limiter(curvature)
        return curvature, torque


@dataclass
class RunHooks:
    """The run-time side of a disturbance for one run, called by `tracking.executor.execute` and
    `tracking.clip_run.ReplanningLoop`."""

    pose_error: PoseError | None = None
    actuator: Actuator | None = None

    def sensed(self, pose: np.ndarray, t: float) -> np.ndarray:
        """The pose the vehicle believes it has at sim time ``t`` when it truly is at ``pose``."""
        return pose if self.pose_error is None else np.asarray(pose, float) + self.pose_error(t)

    def actuate(self, curvature: float, torque: float) -> tuple[float, float]:
        """What reaches the steering servos and the drive motors for the commanded (curvature, torque)."""
        return (curvature, torque) if self.actuator is None else self.actuator(curvature, torque)


__all__ = ["FACTORS", "LEVELS", "Actuator", "Disturbance", "Factor", "PoseError", "RunHooks"]
