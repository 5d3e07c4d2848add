"""One plan validator with three rules, selectable by name (spec §2 conventions, paper eq:arc, eq:hermite).

* ``"paper"``: the benchmark's scoring rule for the reference-point convention, the env's own check: the
  reference point at the ``samples_per_arc`` poses l·j/n, j = 1..n, of each arc (the compiled ``arc_valid`` the env
  steps with, paper: n = 30) and at every stored sample of the Hermite segment (the connector's N = 100 points),
  strictly inside the boundary and strictly outside every obstacle; the start pose as well.
* ``"footprint_sampled"``: the same samples with the full vehicle rectangle (heading along the cubic's tangent on
  the Hermite segment, + π when reversing): the footprint convention exactly as the env scores it.
* ``"exact"``: the body (``convention``: the rectangle, or the reference point) swept continuously along every arc
  and the Hermite cubic, tested analytically against polygons, circles and the boundary
  (``np_sim.kernels.swept``: vertex-crosses-edge tests for the rigid arc motions, certified bisection with a
  motion bound for the cubic); a contact, or a near miss closer than ``EXACT_TOLERANCE_M``, is a violation.

``validate_plan`` returns a ``ValidationResult``: the valid flag and, for an invalid plan, the first violation
(segment, parameter along it, what was hit and where). A plan is validated as drawn, whatever its success flag.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from np_sim.config import Convention, EpisodeConfig
from np_sim.errors import ConfigError
from np_sim.kernels import swept
from np_sim.kernels.collision import arc_valid
from np_sim.kernels.kinematics import arc_point
from np_sim.kinematics import heading_gap
from np_sim.plan import Plan, hermite_coefficients
from np_sim.scene import CircleObstacle, PolygonObstacle, Scene
from np_sim.scene_arrays import packed_scene
from np_sim.vehicle import VehicleSpec

RULES = ("paper", "footprint_sampled", "exact")
"""The rule names ``validate_plan`` accepts."""
EXACT_TOLERANCE_M = swept.EXACT_TOLERANCE_M
"""Contacts and near misses at or below this distance (m) violate the exact rule."""
HERMITE_MAX_PIECES = 200_000
"""Pieces the exact rule may certify on one Hermite segment before it reports the segment undecided (invalid)."""


@dataclass(frozen=True)
class Violation:
    """Where a plan first breaks its rule."""

    segment: int
    """Index of the arc in ``plan.arcs``; ``len(plan.arcs)`` for the Hermite segment; −1 for the start pose."""
    parameter: float
    """Fraction of the arc's length (u ∈ [0, 1]) or Hermite parameter t ∈ [0, 1] of the first violation."""
    what: str
    """'boundary', 'obstacle' or 'undecided' (an exact Hermite piece that could not be certified either way)."""
    obstacle: int | None
    """Index into ``scene.obstacles`` of the obstacle hit, or None."""
    position: tuple[float, float]
    """World point (m) of the contact (exact rule) or of the reference point at the failing sample."""

    def describe(self) -> str:
        """One line for logs and error messages."""
        where = "start pose" if self.segment < 0 else f"segment {self.segment} at parameter {self.parameter:.4f}"
        what = self.what if self.obstacle is None else f"obstacle {self.obstacle}"
        return f"{where}: {what} at ({self.position[0]:.4f}, {self.position[1]:.4f})"


@dataclass(frozen=True)
class ValidationResult:
    """The answer of ``validate_plan``."""

    valid: bool
    """The plan satisfies the rule."""
    rule: str
    """The rule checked (one of ``RULES``)."""
    convention: Convention
    """The body checked: 'reference_point' or 'footprint'."""
    violation: Violation | None = None
    """The first violation of an invalid plan, else None."""

    def __bool__(self) -> bool:
        return self.valid


def scoring_rule(convention: Convention) -> str:
    """The rule a planner of ``convention`` is scored by: 'paper' (reference point) or 'footprint_sampled'."""
    if convention not in ("reference_point", "footprint"):
        raise ConfigError(f"scoring_rule: convention must be 'reference_point' or 'footprint', got {convention!r}")
    return "paper" if convention == "reference_point" else "footprint_sampled"


def validate_plan(scene: Scene, plan: Plan, rule: str = "exact", *, convention: Convention = "footprint",
                  vehicle: VehicleSpec | None = None,
                  samples_per_arc: int = EpisodeConfig.samples_per_arc) -> ValidationResult:
    """Check ``plan`` in ``scene`` under ``rule`` (module docstring); ``convention`` applies to the exact rule
    ('paper' is the reference point, 'footprint_sampled' the rectangle); ``vehicle`` sets the rectangle."""
    if rule not in RULES:
        raise ConfigError(f"validate_plan: rule must be one of {RULES}, got {rule!r}")
    if rule != "exact":
        convention = "reference_point" if rule == "paper" else "footprint"
    elif convention not in ("reference_point", "footprint"):
        raise ConfigError(f"validate_plan: convention must be 'reference_point' or 'footprint', got {convention!r}")
    if not (isinstance(samples_per_arc, int) and samples_per_arc >= 1):
        raise ConfigError(f"validate_plan: samples_per_arc must be an integer >= 1, got {samples_per_arc!r}")
    geo = packed_scene(scene).geometry
    local = (VehicleSpec() if vehicle is None else vehicle).footprint_local()
    footprint = convention == "footprint"
    arcs = np.asarray(plan.arcs, float).reshape(-1, 2)
    start = np.array(plan.start, float)  # a writeable copy: numba compiles a read-only array as another type
    if start.shape != (3,) or not (np.all(np.isfinite(start)) and np.all(np.isfinite(arcs))):
        raise ValueError(f"validate_plan: expected a finite start [x, y, θ] and finite (κ, l) arcs, got start "
                         f"{start.tolist()} and {len(arcs)} arcs ({int(np.sum(~np.isfinite(arcs)))} non-finite values)")
    check = _exact_segments if rule == "exact" else _sampled_segments
    found = check(geo, start, arcs, plan, footprint, local, samples_per_arc)
    violation = None if found is None else _violation(scene, *found)
    return ValidationResult(valid=violation is None, rule=rule, convention=convention, violation=violation)


def _sampled_segments(geo, start, arcs, plan, footprint, local, n):
    """(segment, parameter, hit) of the first pose the env's sampled check rejects, or None."""
    corners = np.empty((4, 2))
    if swept.first_invalid_pose(geo, 0, start[None, :], footprint, local) >= 0:
        return -1, 0.0, _offender(geo, start, footprint, local)
    x, y, th = start
    for i, (kappa, length) in enumerate(arcs):
        if not arc_valid(geo, 0, x, y, th, kappa, length, n, footprint, local, corners):
            poses = np.array([arc_point(x, y, th, kappa, length * (j + 1) / n) for j in range(n)])
            j = swept.first_invalid_pose(geo, 0, poses, footprint, local)
            return i, (j + 1) / n, _offender(geo, poses[j], footprint, local)
        x, y, th = arc_point(x, y, th, kappa, length)
    if plan.hermite is None:
        return None
    poses = _hermite_poses(plan)
    j = swept.first_invalid_pose(geo, 0, poses, footprint, local)
    if j < 0:
        return None
    return len(arcs), j / max(len(poses) - 1, 1), _offender(geo, poses[j], footprint, local)


def _hermite_poses(plan: Plan) -> np.ndarray:
    """(N, 3) stored Hermite samples with the heading of the cubic's tangent at t_j = j/(N−1) (+ π reversing)."""
    pts = np.asarray(plan.hermite.points, float)
    c = hermite_coefficients(pts)
    t = np.linspace(0.0, 1.0, len(pts))[:, None]
    d1 = c[1] + t * (2.0 * c[2] + 3.0 * t * c[3])
    heading = np.arctan2(d1[:, 1], d1[:, 0]) + (0.0 if plan.hermite.forward else math.pi)
    return np.ascontiguousarray(np.column_stack([pts, heading]))


def _offender(geo, pose, footprint, local) -> np.ndarray:
    """The hit record (kind, packed index, x, y) of what a rejected pose touches."""
    hit = np.array([swept.KIND_NONE, -1.0, pose[0], pose[1]])
    swept.body_clear(geo, 0, _body(pose, footprint, local), 4 if footprint else 1, 0.0, hit)
    hit[2:] = pose[:2]
    return hit


def _body(pose, footprint: bool, local: np.ndarray) -> np.ndarray:
    """(4, 2) body at ``pose`` as the kernels take it: the rectangle's corners, or the point in row 0."""
    body = np.zeros((4, 2))
    if footprint:
        swept.footprint_corners(pose[0], pose[1], pose[2], local, body)
    else:
        body[0] = pose[:2]
    return body


def _exact_segments(geo, start, arcs, plan, footprint, local, n):
    """(segment, parameter, hit) of the first exact violation, or None."""
    hit = np.array([swept.KIND_NONE, -1.0, 0.0, 0.0])
    if not swept.body_clear(geo, 0, _body(start, footprint, local), 4 if footprint else 1, 0.0, hit):
        return -1, 0.0, hit
    x, y, th = start
    for i, (kappa, length) in enumerate(arcs):
        u = swept.swept_arc_contact(geo, 0, x, y, th, kappa, length, footprint, local, EXACT_TOLERANCE_M, True,
                                    hit)
        if u >= 0.0:
            return i, u, hit
        x, y, th = arc_point(x, y, th, kappa, length)
    if plan.hermite is None:
        return None
    coeffs = hermite_coefficients(plan.hermite.points)
    t = swept.hermite_contact(geo, 0, coeffs, not plan.hermite.forward, footprint, local, HERMITE_MAX_PIECES, hit)
    return None if t < 0.0 else (len(arcs), t, hit)


def _violation(scene: Scene, segment: int, parameter: float, hit: np.ndarray) -> Violation:
    """The Violation of a hit record, packed obstacle indices mapped back to ``scene.obstacles``."""
    kind = int(hit[0])
    obstacle = None
    if kind in (swept.KIND_POLYGON, swept.KIND_CIRCLE):
        cls = PolygonObstacle if kind == swept.KIND_POLYGON else CircleObstacle
        obstacle = [i for i, o in enumerate(scene.obstacles) if isinstance(o, cls)][int(hit[1])]
    what = {swept.KIND_BOUNDARY: "boundary", swept.KIND_UNDECIDED: "undecided", swept.KIND_POLYGON: "obstacle",
            swept.KIND_CIRCLE: "obstacle"}.get(kind, "unidentified")
    return Violation(segment=int(segment), parameter=float(parameter), what=what, obstacle=obstacle,
                     position=(float(hit[2]), float(hit[3])))


END_POSE_SLACK = 1e-6
"""Rounding allowance on the success tolerances (m, and rad on the heading): the connector's edge candidates end
exactly at them (0.1 m, 10°)."""


def end_pose_error(scene: Scene, plan: Plan) -> tuple[float, float]:
    """(distance in m, |heading difference| in rad) of ``plan``'s end pose from ``scene.target``: the last pose of
    `Plan.sample` (the arcs integrated with eq:arc, then the Hermite cubic's end and end tangent, eq:hermite)."""
    end = plan.sample(1.0)[-1, :3]
    target = np.asarray(scene.target, float)
    return float(np.hypot(*(end[:2] - target[:2]))), heading_gap(end[2], target[2])


def ends_at_target(scene: Scene, plan: Plan, episode: EpisodeConfig | None = None) -> bool:
    """``plan`` ends within the episode's success tolerances of the target (``END_POSE_SLACK`` for rounding):
    the other half of a success, checked from the plan itself rather than from the planner's own flag."""
    episode = EpisodeConfig() if episode is None else episode
    distance, heading = end_pose_error(scene, plan)
    return (distance <= episode.position_tolerance_m + END_POSE_SLACK
            and heading <= math.radians(episode.heading_tolerance_deg) + END_POSE_SLACK)


def plan_valid(scene: Scene, plan: Plan, rule: str, convention: Convention = "footprint",
               vehicle: VehicleSpec | None = None) -> bool:
    """A successful plan that ends at the target (``ends_at_target``, the benchmarks' tolerances) and passes
    ``validate_plan(...)``; False for a failed one (nothing to validate)."""
    return (bool(plan.success) and ends_at_target(scene, plan)
            and validate_plan(scene, plan, rule, convention=convention, vehicle=vehicle).valid)


def validation_failure(scene: Scene, plan: Plan, convention: Convention, vehicle: VehicleSpec | None = None,
                       samples_per_arc: int = EpisodeConfig.samples_per_arc) -> str:
    """'' when ``plan`` passes the rule a planner of ``convention`` is scored by (``scoring_rule``) and, under the
    footprint convention, the exact rule too; else 'validation: ' with the rule and its first violation. What
    every planner checks before it claims a success."""
    rules = [scoring_rule(convention)] + (["exact"] if convention == "footprint" else [])
    for rule in rules:
        result = validate_plan(scene, plan, rule, convention=convention, vehicle=vehicle,
                               samples_per_arc=samples_per_arc)
        if not result.valid:
            return f"validation: {rule} rule, {result.violation.describe()}"
    return ""
