"""np_sim.validate: the paper rule, the sampled footprint rule and the exact swept rule.

The oracle is written without the code under test: poses along an arc from its closed form (the heading turns
at −κ per metre, the position is the integral of the unit heading), the body as a shapely polygon at every
sample 1 mm apart (farthest body point), and shapely distances. Between two such samples the body moves less
than δ = 1 mm, so a contact at the samples proves a violation, and a violation proves a sample within δ.
"""

import math

import numpy as np
import pytest
import shapely
from hypothesis import given, settings
from hypothesis import strategies as st

from np_sim.errors import ConfigError
from np_sim.plan import HermiteSegment, Plan
from np_sim.scene import Scene
from np_sim.validate import RULES, validate_plan
from np_sim.vehicle import VehicleSpec

LOCAL = VehicleSpec().footprint_local()
RHO = float(np.max(np.hypot(LOCAL[:, 0], LOCAL[:, 1])))
STEP_M = 1e-3


def _scene(obstacles, boundary=((-30, -30), (30, -30), (30, 30), (-30, 30))) -> Scene:
    return Scene.from_dict({"boundary": [list(p) for p in boundary], "obstacles": obstacles,
                            "target": [25.0, 25.0, 0.0]})


def _poses(start, kappa, length, n):
    """Closed-form poses along the arc at u = 0..1 (n + 1 of them): θ(u) = θ0 − κ|l|u and (x, y) the integral of
    sgn(l)·(cos θ, sin θ) over |l|u metres: |l|u·sinc(κ|l|u/2) along the mean heading (κ = 0 included)."""
    x0, y0, th0 = start
    u = np.linspace(0.0, 1.0, n + 1)
    turn = kappa * abs(length) * u
    mid = th0 - 0.5 * turn
    along = length * u * np.sinc(0.5 * turn / np.pi)
    return np.column_stack([x0 + along * np.cos(mid), y0 + along * np.sin(mid), th0 - turn])


def _bodies(poses, footprint):
    if not footprint:
        return shapely.points(poses[:, :2])
    c, s = np.cos(poses[:, 2])[:, None], np.sin(poses[:, 2])[:, None]
    xs = poses[:, :1] + c * LOCAL[:, 0] - s * LOCAL[:, 1]
    ys = poses[:, 1:2] + s * LOCAL[:, 0] + c * LOCAL[:, 1]
    return shapely.polygons(np.stack([xs, ys], axis=-1))


def _brute_hit(scene, poses, footprint, slack):
    """Some body at ``poses`` comes within ``slack`` of an obstacle or of the boundary line (or leaves it)."""
    bodies = _bodies(poses, footprint)
    inside = shapely.Polygon(scene.boundary)
    if not np.all(shapely.contains_properly(inside, bodies)):
        return True
    if np.any(shapely.distance(inside.exterior, bodies) <= slack):
        return True
    for o in scene.obstacles:
        if hasattr(o, "vertices"):
            d = shapely.distance(shapely.Polygon(o.vertices), bodies)
        else:
            d = shapely.distance(shapely.Point(o.center), bodies) - o.radius
        if np.any(d <= slack):
            return True
    return False


def _check_against_brute_force(scene, start, kappa, length, footprint):
    plan = Plan(start=np.array(start), arcs=np.array([[kappa, length]]), success=True)
    convention = "footprint" if footprint else "reference_point"
    exact = validate_plan(scene, plan, "exact", convention=convention)
    travel = abs(length) + (RHO * abs(kappa * length) if footprint else 0.0)
    poses = _poses(start, kappa, length, max(1, math.ceil(travel / STEP_M)))
    if _brute_hit(scene, poses, footprint, 0.0):
        assert not exact.valid
    if not exact.valid:
        assert _brute_hit(scene, poses, footprint, STEP_M + 1e-9)
        # the reported contact parameter is where a sample within δ sits
        u = exact.violation.parameter
        n = len(poses) - 1
        near = poses[max(0, math.floor(u * n) - 1): math.ceil(u * n) + 2]
        assert _brute_hit(scene, near, footprint, STEP_M + 1e-6)
    return exact


def _corner_triangle(apex, direction, size):
    """A thin triangle with its apex at ``apex``, extending ``size`` m along the unit ``direction``."""
    ax, ay = apex
    dx, dy = direction
    base = (ax + size * dx, ay + size * dy)
    return {"polygon": [list(apex), [base[0] - 0.3 * size * dy, base[1] + 0.3 * size * dx],
                        [base[0] + 0.3 * size * dy, base[1] - 0.3 * size * dx]]}


def test_a_corner_between_two_paper_samples_passes_the_paper_rule_and_fails_the_exact_one():
    # the reference point drives 3 m along +x (samples every 0.1 m); a triangle pokes 1 mm across y = 0 at x = 0.15
    scene = _scene([{"polygon": [[0.14, -1.0], [0.16, -1.0], [0.15, 0.001]]}])
    plan = Plan(start=np.zeros(3), arcs=np.array([[0.0, 3.0]]), success=True)
    assert validate_plan(scene, plan, "paper").valid
    exact = validate_plan(scene, plan, "exact", convention="reference_point")
    assert not exact.valid
    v = exact.violation
    # the triangle's left edge meets y = 0 at x = 0.15 − 0.01·0.001/1.001 (hand-derived)
    assert v.segment == 0 and v.what == "obstacle" and v.obstacle == 0
    assert v.parameter * 3.0 == pytest.approx(0.15 - 0.01 * 0.001 / 1.001, abs=1e-9)


def test_a_disc_between_samples_is_found_at_its_first_contact():
    # disc (0.15, 0.004) r = 0.005: samples at x = 0.1, 0.2 are 5 cm away; contact first at x = 0.15 − 0.003
    scene = _scene([{"circle": [0.15, 0.004, 0.005]}])
    plan = Plan(start=np.zeros(3), arcs=np.array([[0.0, 3.0]]), success=True)
    assert validate_plan(scene, plan, "paper").valid
    exact = validate_plan(scene, plan, "exact", convention="reference_point")
    assert not exact.valid and exact.violation.obstacle == 0
    assert exact.violation.parameter * 3.0 == pytest.approx(0.147, abs=1e-8)  # contact within eps = 1 nm


def test_the_paper_rule_rejects_the_first_sample_inside_an_obstacle():
    scene = _scene([{"polygon": [[1.25, -1.0], [1.35, -1.0], [1.35, 1.0], [1.25, 1.0]]}])
    plan = Plan(start=np.zeros(3), arcs=np.array([[0.0, 1.0], [0.0, 2.0]]), success=True)
    result = validate_plan(scene, plan, "paper")
    # second arc starts at x = 1; its samples are every 2/30 m: the first inside [1.25, 1.35] is j = 4 (x = 1.2667)
    assert not result.valid and result.violation.segment == 1
    assert result.violation.parameter == pytest.approx(4 / 30)
    assert result.violation.position[0] == pytest.approx(1.0 + 8 / 30)


def test_touching_an_edge_is_a_violation_and_clearing_it_is_not():
    square = {"polygon": [[1.0, 0.0], [2.0, 0.0], [2.0, 1.0], [1.0, 1.0]]}
    along_edge = Plan(start=np.array([0.0, 0.0, 0.0]), arcs=np.array([[0.0, 3.0]]), success=True)
    below = Plan(start=np.array([0.0, -1e-6, 0.0]), arcs=np.array([[0.0, 3.0]]), success=True)
    scene = _scene([square])
    assert not validate_plan(scene, along_edge, "exact", convention="reference_point").valid
    assert validate_plan(scene, below, "exact", convention="reference_point").valid


def test_a_corner_sweeping_out_of_the_boundary_between_samples_is_found():
    # turning on the spot is impossible; a tight forward left turn (κ < 0) swings the rear-right corner outward
    wall = 1.0 + 0.5 * VehicleSpec().width_m + 0.02
    scene = _scene([], boundary=((-30, -wall), (30, -wall), (30, 30), (-30, 30)))
    kappa = -VehicleSpec().kappa_max
    exact = _check_against_brute_force(scene, (0.0, -1.0, 0.0), kappa, 3.0, True)
    sampled = validate_plan(scene, Plan(start=np.array([0.0, -1.0, 0.0]), arcs=np.array([[kappa, 3.0]]),
                                        success=True), "footprint_sampled")
    assert not exact.valid and exact.violation.what == "boundary"
    assert sampled.valid == (not _brute_hit(scene, _poses((0.0, -1.0, 0.0), kappa, 3.0, 30)[1:], True, 0.0))


@settings(max_examples=60, deadline=None, derandomize=True)
@given(x=st.floats(-2, 2), y=st.floats(-2, 2), th=st.floats(-math.pi, math.pi), kappa=st.floats(-0.25, 0.25),
       length=st.floats(-6, 6).filter(lambda v: abs(v) > 0.05), u=st.floats(0, 1), corner=st.integers(0, 3),
       offset=st.floats(-0.004, 0.004), angle=st.floats(-math.pi, math.pi), circle=st.booleans(),
       footprint=st.booleans())
def test_exact_rule_agrees_with_1mm_shapely_sampling_near_corners(x, y, th, kappa, length, u, corner, offset, angle,
                                                                  circle, footprint):
    # an obstacle apex (or a disc edge) placed within a few millimetres of where a body point passes
    pose = _poses((x, y, th), kappa, length, 1)[0] if u == 0 else _poses((x, y, th), kappa, length * u, 1)[1]
    lx, ly = LOCAL[corner] if footprint else (0.0, 0.0)
    px = pose[0] + math.cos(pose[2]) * lx - math.sin(pose[2]) * ly
    py = pose[1] + math.sin(pose[2]) * lx + math.cos(pose[2]) * ly
    direction = (math.cos(angle), math.sin(angle))
    apex = (px + offset * direction[0], py + offset * direction[1])
    if circle:
        obstacle = {"circle": [apex[0] + 0.3 * direction[0], apex[1] + 0.3 * direction[1], 0.3]}
    else:
        obstacle = _corner_triangle(apex, direction, 1.0)
    scene = _scene([obstacle])
    start = (x, y, th)
    if _brute_hit(scene, _poses(start, kappa, length, 0)[:1], footprint, 0.0):
        return  # a start in collision is the static test's business
    _check_against_brute_force(scene, start, kappa, length, footprint)


def _cubic_plan(start_xy, end_xy, d0, d1, forward=True):
    t = np.linspace(0.0, 1.0, 100)[:, None]
    h = [2 * t**3 - 3 * t**2 + 1, 3 * t**2 - 2 * t**3, t**3 - 2 * t**2 + t, t**3 - t**2]
    pts = h[0] * start_xy + h[1] * end_xy + h[2] * d0 + h[3] * d1
    heading = math.atan2(d0[1], d0[0]) + (0.0 if forward else math.pi)
    seg = HermiteSegment(points=pts, forward=forward, length=1.0, delta_kappa=0.0)
    return Plan(start=np.array([*start_xy, heading]), hermite=seg, success=True), pts


@settings(max_examples=12, deadline=None, derandomize=True)
@given(bend=st.floats(-6, 6), offset=st.floats(-0.01, 0.01), j=st.integers(5, 990), footprint=st.booleans(),
       forward=st.booleans())
def test_exact_hermite_rule_agrees_with_dense_shapely_sampling(bend, offset, j, footprint, forward):
    start, end = np.array([0.0, 0.0]), np.array([8.0, 3.0])
    d0, d1 = np.array([8.0, bend]), np.array([8.0, -bend])
    sign = 1.0 if forward else -1.0
    plan, _ = _cubic_plan(start, end, sign * d0, sign * d1, forward)
    t = np.linspace(0.0, 1.0, 8001)[:, None]
    h = [2 * t**3 - 3 * t**2 + 1, 3 * t**2 - 2 * t**3, t**3 - 2 * t**2 + t, t**3 - t**2]
    xy = h[0] * start + h[1] * end + sign * (h[2] * d0 + h[3] * d1)
    dxy = np.gradient(xy, axis=0)
    poses = np.column_stack([xy, np.arctan2(dxy[:, 1], dxy[:, 0]) + (0.0 if forward else math.pi)])
    # a disc whose edge sits within a centimetre of a sampled body point (rear-left corner or the point)
    lx, ly = LOCAL[3] if footprint else (0.0, 0.0)
    p = poses[j * 8]
    cx = p[0] + math.cos(p[2]) * lx - math.sin(p[2]) * ly
    cy = p[1] + math.sin(p[2]) * lx + math.cos(p[2]) * ly
    normal = np.array([-math.sin(p[2]), math.cos(p[2])]) * (1 if ly >= 0 else -1)
    centre = np.array([cx, cy]) + (0.2 + offset) * normal
    scene = _scene([{"circle": [*centre.tolist(), 0.2]}])
    exact = validate_plan(scene, plan, "exact", convention="footprint" if footprint else "reference_point")
    step = np.max(np.hypot(*np.diff(poses[:, :2], axis=0).T)) + RHO * np.max(np.abs(np.diff(np.unwrap(poses[:, 2]))))
    if _brute_hit(scene, poses, footprint, 0.0):
        assert not exact.valid
    if not exact.valid:
        assert exact.violation.what != "undecided"
        assert _brute_hit(scene, poses, footprint, step + 1e-6)


def test_unknown_rule_and_convention_are_errors_naming_the_choices():
    plan = Plan(start=np.zeros(3))
    with pytest.raises(ConfigError, match="rule must be one of"):
        validate_plan(_scene([]), plan, "dense")
    with pytest.raises(ConfigError, match="convention must be"):
        validate_plan(_scene([]), plan, "exact", convention="wheels")
    assert set(RULES) == {"paper", "footprint_sampled", "exact"}
    with pytest.raises(ValueError, match="finite start"):
        validate_plan(_scene([]), Plan(start=np.zeros(3), arcs=np.array([[np.nan, 1.0]])), "paper")


@pytest.mark.parametrize("convention", ["reference_point", "footprint"])
def test_the_scoring_rule_accepts_exactly_what_the_env_accepts(convention):
    # random arcs played in the env; after every step the plan so far (with the env's Hermite segment on a
    # connected success) passes the scoring rule iff the env did not report a collision
    from np_sim.config import EnvConfig
    from np_sim.env import ParkingEnv
    from np_sim.examples import example_scenes
    from np_sim.frames import from_target_frame
    from np_sim.kernels import step as K
    from np_sim.starts import UniformStartSampler
    from np_sim.validate import scoring_rule

    scenes = [s for s in example_scenes() if s.tags.get("expect") != "no_path"]
    config = EnvConfig(collision=convention)
    rng = np.random.default_rng(3)
    outcomes = set()
    for k, scene in enumerate(scenes[:4]):
        env = ParkingEnv(scene, config)
        for start in UniformStartSampler([scene])(rng, np.zeros(6, np.int64)):
            env.reset(options={"start": start})
            arcs = []
            while True:
                action = rng.uniform(-1, 1, 2) * np.array([1.0, 0.3])
                _, _, term, trunc, info = env.step(action)
                arcs.append(action * np.array([config.vehicle.kappa_max, config.episode.max_length_m]))
                h = int(env.core.R[0, K.R_HERMITE])
                hermite = None if h < 0 else HermiteSegment(
                    points=from_target_frame(env.core.h_pts[0, h].T, scene.target),
                    forward=bool(env.core.R[0, K.R_H_FORWARD] > 0), length=1.0, delta_kappa=0.0)
                plan = Plan(start=start, arcs=np.array(arcs), hermite=hermite, success=True)
                valid = validate_plan(scene, plan, scoring_rule(convention)).valid
                assert valid == (not info["collision"])
                outcomes.add((valid, hermite is not None))
                if term or trunc:
                    break
    assert outcomes == {(False, False), (True, False), (True, True)}  # collisions, free arcs, connected successes


def _at(target) -> Scene:
    scene = _scene(())
    return Scene(boundary=scene.boundary, obstacles=(), target=np.asarray(target, float), start_region=None)


def test_a_success_counts_only_when_the_plan_ends_within_the_tolerances_of_the_target():
    """``ends_at_target`` / ``plan_valid``: a straight 5 m arc from the origin ends at (5, 0, 0); a quarter circle of
    radius 4 (κ = 0.25, l = 2π; positive κ turns clockwise, θ = θ0 − κ|l|u) ends at (4, −4, −90°); the end is
    compared with targets moved by hand, at the tolerances' edges (0.1 m, 10°: accepted) and beyond them."""
    from np_sim.validate import end_pose_error, ends_at_target, plan_valid

    straight = Plan(start=np.zeros(3), arcs=np.array([[0.0, 5.0]]), success=True)
    quarter = Plan(start=np.zeros(3), arcs=np.array([[0.25, 2 * math.pi]]), success=True)
    assert end_pose_error(_at([5.0, 0.0, 0.0]), straight) == pytest.approx((0.0, 0.0), abs=1e-12)
    assert end_pose_error(_at([4.0, -4.0, -math.pi / 2]), quarter) == pytest.approx((0.0, 0.0), abs=1e-9)
    assert ends_at_target(_at([5.1, 0.0, 0.0]), straight)  # 0.1 m: on the edge
    assert not ends_at_target(_at([5.0, 0.2, 0.0]), straight)
    assert ends_at_target(_at([4.0, -4.0, math.radians(-80.0)]), quarter)  # 10°: on the edge
    assert not ends_at_target(_at([4.0, -4.0, math.radians(-101.0)]), quarter)
    assert plan_valid(_at([5.0, 0.0, 0.0]), straight, "paper")
    assert not plan_valid(_at([5.0, 0.5, 0.0]), straight, "paper")  # collision-free, but it does not park


def test_the_end_pose_of_a_plan_with_a_hermite_segment_is_the_cubic_s_end_and_end_tangent():
    """A reversing Hermite segment sampled from the straight cubic (5, 0) → (3, 0): the body drives backwards along
    −x, so it ends at (3, 0) facing +x (heading 0)."""
    from np_sim.validate import end_pose_error

    t = np.linspace(0.0, 1.0, 100)
    points = np.column_stack([5.0 - 2.0 * t, np.zeros_like(t)])
    plan = Plan(start=np.zeros(3), arcs=np.array([[0.0, 5.0]]), success=True,
                hermite=HermiteSegment(points=points, forward=False, length=2.0, delta_kappa=0.0))
    assert end_pose_error(_at([3.0, 0.0, 0.0]), plan) == pytest.approx((0.0, 0.0), abs=1e-9)
