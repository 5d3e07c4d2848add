"""tracking.disturbance: each factor changes what it should and nothing else (real MuJoCo, no mocks)."""

import dataclasses
import json
import math

import mujoco
import numpy as np
import pytest
import shapely

from experiments.closed_loop import clip_rows
from np_sim.clips import load_clips
from np_sim.errors import ConfigError
from np_sim.planners import HybridAStar
from tracking.clip_run import ClipRunConfig, ReplanningLoop
from tracking.config import PlantConfig, TrackerConfig
from tracking.disturbance import FACTORS, LEVELS, Disturbance
from tracking.executor import execute
from tracking.mjcf import ackermann_angles, half_track_m, vehicle_xml
from tracking.observer import RunObserver
from tracking.world import build_world

from tracking_helpers import open_scene, plan_end, plan_from_arcs

TIMING = ("plan_time_median_ms", "plan_time_first_ms", "plan_time_max_ms", "plan_times_ms", "wall_time_s",
          "realtime_factor")
"""Record columns measured on the wall clock."""
CLIP = "eval-1000016"
"""A short clip Hybrid A* parks in closed loop."""


@pytest.fixture(scope="module")
def clip():
    return next(c for c in load_clips("eval") if c.name == CLIP)


class Commands(RunObserver):
    """Per control step: the controller's command, what the actuators got (world ctrl), the pose the controller
    saw and the true pose after the step."""

    def __init__(self):
        self.command, self.ctrl, self.seen, self.truth, self.t = [], [], [], [], []

    def on_start(self, world, plan, segments):
        self.truth.append(world.pose())

    def on_step(self, t, world, state, command, target_speed):
        self.command.append(command)
        self.ctrl.append(world.data.ctrl.copy())
        self.seen.append(np.array(state.pose, float))
        self.truth.append(world.pose())
        self.t.append(t)


def _drive(hooks=None):
    plan = plan_from_arcs([[0.3, 6.0], [-0.3, 4.0]])
    observer = Commands()
    execute(open_scene(plan_end(plan)), plan, observer=observer, hooks=hooks)
    return observer


@pytest.mark.parametrize("factor", list(FACTORS))
def test_a_zero_level_is_no_change_at_all(factor, clip):
    none = Disturbance(factor, 0.0, seed=3)
    config = TrackerConfig()
    assert none.tracker(config) is config and none.hooks(CLIP, config) is None
    ids, polygons = clip.detections(5)
    assert none.perceive(CLIP, 5, ids, polygons) == (ids, polygons)
    assert none.setting == "none"


def test_a_zero_level_reproduces_the_undisturbed_clip_records_exactly(clip):
    planners = {"hybrid_astar": HybridAStar(convention="footprint")}
    base = clip_rows(clip, planners, "lqr", None, False)
    zero = clip_rows(clip, planners, "lqr", None, False, disturbance=Disturbance("latency", 0.0, seed=1))
    untimed = [json.dumps({k: v for k, v in r.items() if k not in TIMING}, sort_keys=True) for r in base + zero]
    assert untimed[0] == untimed[1] and base[0]["footprint_success"] == 1


def test_a_latency_of_k_periods_delays_the_commanded_steering_by_exactly_k_periods():
    k = 5  # 0.1 s of 0.02 s control periods
    config = TrackerConfig()
    ideal = _drive()
    late = _drive(Disturbance("latency", 0.1, seed=0).hooks("run", config))
    half_track = half_track_m(config.vehicle, config.model)
    sent = np.array(late.command)
    left, right = ackermann_angles(sent, config.vehicle.wheelbase_m, half_track)
    ctrl = np.array(late.ctrl)
    np.testing.assert_allclose(ctrl[k:, 0], left[:-k], rtol=0, atol=1e-12)
    np.testing.assert_allclose(ctrl[k:, 1], right[:-k], rtol=0, atol=1e-12)
    assert np.all(ctrl[:k] == 0.0)  # straight wheels, no torque until the first command arrives
    assert np.any(ctrl[k:, 2] != 0.0) and not np.allclose(ctrl[k:, 0], left[k:], atol=1e-6)
    ideal_left, _ = ackermann_angles(np.array(ideal.command), config.vehicle.wheelbase_m, half_track)
    np.testing.assert_allclose(np.array(ideal.ctrl)[:, 0], ideal_left, rtol=0, atol=1e-12)  # no delay without it


def test_a_latency_that_is_no_whole_number_of_periods_is_refused():
    with pytest.raises(ConfigError, match="whole number"):
        Disturbance("latency", 0.03).hooks("run", TrackerConfig())


def test_a_slower_steering_actuator_turns_at_its_reduced_rate():
    config = TrackerConfig()
    hooks = Disturbance("steer_rate", 0.5).hooks("run", config)
    L = config.vehicle.wheelbase_m
    angles = [math.atan(L * hooks.actuate(0.1, 100.0)[0]) for _ in range(40)]
    step = 0.5 * config.model.steer_rate_max_rps * config.executor.control_dt_s  # 0.4 rad/s × 0.02 s
    np.testing.assert_allclose(np.diff([0.0, *angles])[:30], step, rtol=1e-9)
    assert angles[-1] == pytest.approx(math.atan(0.1 * L))  # then holds the commanded angle (after 35 steps)
    assert hooks.actuate(0.0, 7.0)[1] == 7.0  # the torque passes unchanged


def test_pose_noise_reaches_the_controller_while_the_simulator_keeps_the_truth():
    hooks = Disturbance("pose_noise", 0.1, seed=4).hooks("run", TrackerConfig())
    run = _drive(hooks)
    before = np.array(run.truth[:-1])  # the true pose before each step
    times = np.array([0.0, *run.t[:-1]])
    expected = before + np.array([hooks.pose_error(t) for t in times])
    np.testing.assert_array_equal(np.array(run.seen), expected)
    assert np.max(np.abs(np.array(run.seen) - before)[:, :2]) > 0.05


def test_the_localisation_error_is_seeded_held_per_update_and_independent_of_call_order():
    config = TrackerConfig()
    later_first = Disturbance("pose_noise", 0.2, seed=1).hooks(CLIP, config).pose_error
    ordered = Disturbance("pose_noise", 0.2, seed=1).hooks(CLIP, config).pose_error
    times = np.arange(0.0, 60.0, 0.02)
    late = later_first(59.99)
    errors = np.array([ordered(t) for t in times])
    np.testing.assert_array_equal(late, ordered(59.99))
    np.testing.assert_array_equal(errors, [later_first(t) for t in times])
    assert np.all(errors[1:5] == errors[0])  # held for the 0.1 s between updates
    other_seed = Disturbance("pose_noise", 0.2, seed=2).hooks(CLIP, config).pose_error
    other_clip = Disturbance("pose_noise", 0.2, seed=1).hooks("eval-1000009", config).pose_error
    assert not np.array_equal(other_seed(1.0), ordered(1.0)) and not np.array_equal(other_clip(1.0), ordered(1.0))


def test_the_localisation_error_has_the_level_sigma_and_a_drift():
    error = Disturbance("pose_noise", 0.2, seed=0).hooks("run", TrackerConfig()).pose_error
    samples = np.array([error(0.1 * n) for n in range(3000)])
    jumps = np.diff(samples, axis=0)  # white noise differences: sd √2·σ (the drift step is tiny)
    assert np.std(jumps[:, 0]) / math.sqrt(2) == pytest.approx(0.2, rel=0.05)
    assert np.std(jumps[:, 2]) / math.sqrt(2) == pytest.approx(0.02, rel=0.05)


def test_detection_noise_is_seeded_rigid_and_of_the_level_sigma(clip):
    noise = Disturbance("detection_noise", 0.15, seed=7)
    ids, polygons = clip.detections(3)
    a = noise.perceive(CLIP, 3, ids, polygons)
    np.testing.assert_array_equal(a[1], noise.perceive(CLIP, 3, ids, polygons)[1])
    assert not np.array_equal(a[1], Disturbance("detection_noise", 0.15, seed=8).perceive(CLIP, 3, ids, polygons)[1])
    assert not np.array_equal(a[1], noise.perceive(CLIP, 4, ids, polygons)[1])
    offsets = a[1] - polygons
    assert np.array_equal(a[0], ids) and np.allclose(offsets, offsets[:, :1])  # each object moved rigidly
    shifts = np.concatenate([(noise.perceive(CLIP, f, *clip.detections(f))[1] - clip.detections(f)[1])[:, 0]
                             for f in range(clip.n_frames)])
    assert np.std(shifts) == pytest.approx(0.15, rel=0.08) and abs(np.mean(shifts)) < 0.02


def test_a_shifted_detection_never_covers_the_target(clip):
    ids, polygons = clip.detections(0)
    target = shapely.Polygon(TrackerConfig().vehicle.footprint(clip.target))
    big = Disturbance("detection_noise", 0.3, seed=0)
    for frame in range(40):
        moved = big.perceive(CLIP, frame, ids, polygons, keep_clear=target)[1]
        assert not np.any(shapely.intersects(shapely.polygons(moved), target))


def test_dropped_detections_keep_the_others_unchanged_at_the_level_rate(clip):
    drop = Disturbance("detection_drop", 0.3, seed=2)
    kept, total = 0, 0
    for frame in range(clip.n_frames):
        ids, polygons = clip.detections(frame)
        out_ids, out_polygons = drop.perceive(CLIP, frame, ids, polygons)
        mask = np.isin(ids, out_ids)
        np.testing.assert_array_equal(out_polygons, polygons[mask])
        kept, total = kept + len(out_ids), total + len(ids)
    assert 1 - kept / total == pytest.approx(0.3, abs=0.03)


def test_the_planner_gets_the_perturbed_detections_and_the_mislocalised_pose(clip):
    config = ClipRunConfig()
    drop = Disturbance("detection_drop", 0.5, seed=0)
    loop = ReplanningLoop(clip, HybridAStar(convention="footprint"), config, disturbance=drop)
    plain = ReplanningLoop(clip, HybridAStar(convention="footprint"), config)
    frame, scene = loop.frame_scene(1.0, clip.start)
    _, undisturbed = plain.frame_scene(1.0, clip.start)
    held = clip.detection_frame(frame)
    expected = clip.frame_scene(frame, pose=clip.start, detections=drop.perceive(CLIP, held, *clip.detections(held)))
    vertices = [[o.vertices.tolist() for o in s.obstacles] for s in (scene, expected, undisturbed)]
    assert vertices[0] == vertices[1] != vertices[2]
    hooks = Disturbance("pose_noise", 0.1, seed=0).hooks(CLIP, config.tracker)
    noisy = ReplanningLoop(clip, HybridAStar(convention="footprint"), config, hooks=hooks)
    np.testing.assert_array_equal(noisy.sensed(clip.start, 2.0), clip.start + hooks.pose_error(2.0))


def _model_fields(config: TrackerConfig) -> dict[str, np.ndarray]:
    model = mujoco.MjModel.from_xml_string(vehicle_xml(config.vehicle, config.model, config.plant))
    return {n: getattr(model, n).copy() for n in dir(model)
            if not n.startswith("_") and isinstance(getattr(model, n, None), np.ndarray)}


DERIVED_FROM_MASS = {"actuator_acc0", "body_invweight0", "body_subtreemass", "bvh_aabb", "cam_poscom0", "dof_M0",
                     "dof_invweight0", "dof_length"}
"""Model fields MuJoCo derives from the bodies' masses and inertias when it compiles."""
DERIVED_FROM_SIZE = {"bvh_aabb", "dof_length", "geom_aabb", "geom_rbound"}
"""Model fields MuJoCo derives from the geoms' sizes."""


def test_the_tyres_contact_friction_is_the_tyre_friction():
    """What MuJoCo uses at each tyre–ground contact (``data.contact.friction``, after it combines the two geoms'
    parameters) is the configured tyre friction, nominal and lowered: the ground's default μ = 1 must not win."""
    for config in (TrackerConfig(), Disturbance.at("friction", "severe").tracker(TrackerConfig())):
        world = build_world(open_scene((0.0, 0.0, 0.0)), [0.0, 0.0, 0.0], config)
        for _ in range(50):  # settle onto the ground
            mujoco.mj_step(world.model, world.data)
        ground = mujoco.mj_name2id(world.model, mujoco.mjtObj.mjOBJ_GEOM, "ground")
        contacts = [world.data.contact[i] for i in range(world.data.ncon)]
        tyres = [c.friction[0] for c in contacts if ground in (c.geom1, c.geom2)]
        assert len(tyres) == 4 and np.allclose(tyres, config.model.tyre_friction)


def test_lower_friction_changes_the_tyre_friction_and_nothing_else():
    base = _model_fields(TrackerConfig())
    low = _model_fields(Disturbance.at("friction", "severe").tracker(TrackerConfig()))
    assert {n for n in base if not np.array_equal(base[n], low[n])} == {"geom_friction"}
    changed = np.flatnonzero(np.any(base["geom_friction"] != low["geom_friction"], axis=1))
    assert len(changed) == 4 and np.allclose(low["geom_friction"][changed, 0], 0.4)  # the four tyres, μ 1 → 0.4
    np.testing.assert_array_equal(low["geom_friction"][changed, 1:], base["geom_friction"][changed, 1:])


def test_a_payload_adds_its_mass_and_moves_the_centre_of_mass_rearwards():
    config = TrackerConfig()
    base = _model_fields(config)
    heavy = _model_fields(Disturbance.at("payload", "moderate").tracker(config))
    changed = {n for n in base if not np.array_equal(base[n], heavy[n])}
    assert {"body_mass", "body_ipos", "body_inertia"} <= changed <= {"body_mass", "body_ipos", "body_inertia"} \
        | DERIVED_FROM_MASS
    b = int(np.argmax(base["body_mass"]))  # the vehicle body carries the chassis mass
    assert np.flatnonzero(base["body_mass"] != heavy["body_mass"]).tolist() == [b]
    spec, m_c, m_p = config.vehicle, 1500.0, 600.0
    x_box = (spec.wheelbase_m + spec.front_overhang_m - spec.rear_overhang_m) / 2
    x_com = m_c * x_box / (m_c + m_p)  # the payload sits over the rear axle, x = 0
    assert heavy["body_mass"][b] == pytest.approx(2100.0)
    assert heavy["body_ipos"][b] == pytest.approx([x_com, 0.0, base["body_ipos"][b][2]])
    # about the reference point, then moved to the new centre of mass (parallel axes, the other way round)
    length, width = spec.length_m, spec.width_m
    height = config.model.body_height_m - config.model.ground_clearance_m
    izz_origin = m_c * (length ** 2 + width ** 2) / 12 + m_c * x_box ** 2
    iyy_origin = m_c * (length ** 2 + height ** 2) / 12 + m_c * x_box ** 2
    expected = [m_c * (width ** 2 + height ** 2) / 12, iyy_origin - 2100.0 * x_com ** 2,
                izz_origin - 2100.0 * x_com ** 2]
    assert sorted(heavy["body_inertia"][b]) == pytest.approx(sorted(expected), rel=1e-9)


def test_a_longer_body_lengthens_the_chassis_box_at_both_ends_and_nothing_else():
    config = TrackerConfig()
    base = _model_fields(config)
    longer = _model_fields(Disturbance.at("body_length", "severe").tracker(config))
    assert {n for n in base if not np.array_equal(base[n], longer[n])} <= {"geom_size"} | DERIVED_FROM_SIZE
    g = np.flatnonzero(np.any(base["geom_size"] != longer["geom_size"], axis=1)).tolist()
    assert len(g) == 1 and longer["geom_size"][g[0], 0] == pytest.approx(0.5 * 1.1 * config.vehicle.length_m)
    np.testing.assert_array_equal(longer["geom_pos"], base["geom_pos"])  # centred where it was: half at each end


def test_contacts_are_measured_with_the_longer_body_and_the_controllers_keep_the_nominal_mass():
    config = dataclasses.replace(TrackerConfig(), world=dataclasses.replace(TrackerConfig().world,
                                                                            solid_obstacles=False))
    front = config.vehicle.wheelbase_m + config.vehicle.front_overhang_m
    wall = [[front + 0.1, -3.0], [front + 1.0, -3.0], [front + 1.0, 3.0], [front + 0.1, 3.0]]
    scene = open_scene([-10.0, 0.0, 0.0], obstacles=[{"polygon": wall}])
    nominal = build_world(scene, [0.0, 0.0, 0.0], config)
    longer = build_world(scene, [0.0, 0.0, 0.0], Disturbance.at("body_length", "severe").tracker(config))  # +0.23 m
    assert nominal.body_contacts() == [] and [n for n, _ in longer.body_contacts()] == ["obstacle_0"]
    heavy = build_world(scene, [0.0, 0.0, 0.0], Disturbance.at("payload", "severe").tracker(config))
    assert (heavy.mass_kg, heavy.com_ahead_m, heavy.yaw_inertia_kgm2) == (
        nominal.mass_kg, nominal.com_ahead_m, nominal.yaw_inertia_kgm2)
    assert heavy.model.body_mass.sum() == pytest.approx(nominal.model.body_mass.sum() + 900.0)


def test_the_factor_table_has_three_increasing_levels_and_bad_disturbances_are_refused():
    for factor in FACTORS.values():
        assert len(factor.levels) == len(LEVELS) and 0 < factor.levels[0] < factor.levels[1] < factor.levels[2]
        assert factor.levels[2] < factor.upper
    assert Disturbance.at("friction", "moderate").setting == "μ × 0.55"
    spec = TrackerConfig().vehicle
    assert PlantConfig().body(spec) is spec
    for bad, match in (({"factor": "wind", "value": 0.1}, "factor"), ({"factor": "detection_drop", "value": 1.0},
                                                                      "value"),
                       ({"factor": "latency", "value": -0.1}, "value"),
                       ({"factor": "latency", "value": 0.1, "seed": -1}, "seed")):
        with pytest.raises(ConfigError, match=match):
            Disturbance(**bad)
    with pytest.raises(ConfigError, match="level"):
        Disturbance.at("latency", "extreme")
