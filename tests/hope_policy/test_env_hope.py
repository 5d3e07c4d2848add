"""Adapted HOPE environment: gymnasium conformance, HOPE action → arc against a fine integration of HOPE's bicycle
model, hard termination, success, timeout, observation parts against independent computations, determinism."""

import dataclasses
import math

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env
from shapely.geometry import LineString, Point, Polygon

from hope_policy.config import HopeEnvConfig
from hope_policy.env import HopeParkingEnv, HopeVectorEnv
from hope_policy.spaces import action_to_arc, observation_space
from np_sim.bev import render_bev
from np_sim.errors import ConfigError
from np_sim.examples import example_scenes
from np_sim.lidar import cast_rays, footprint_ranges
from np_sim.observation import static_slots
from np_sim.config import ObservationConfig
from np_sim.scene import Scene

OPEN_LOT = {"boundary": [[-30, -30], [30, -30], [30, 30], [-30, 30]], "obstacles": [],
            "target": [0.0, 0.0, math.pi / 2]}
# HOPE configs.py vehicle_base: footprint range per beam of HOPE's 4.69 × 1.94 rectangle (first 45 beams; the rest
# mirror them)
HOPE_BASE_HEAD = [3.76, 3.765160020952183, 3.7807111311588217, 3.806868872962891, 3.8440006366925097,
                  3.7477922060015847, 3.138985938174796, 2.706715266336576, 2.3848355355070114, 2.1366085866477085,
                  1.9400000000000004, 1.7809961050133638, 1.6502625682029572, 1.5413452571937767]
NO_EXTRAS = HopeEnvConfig(rs_takeover=False)


def open_lot(obstacles=()):
    return Scene.from_dict({**OPEN_LOT, "obstacles": [{"polygon": o} for o in obstacles]})


def hope_bicycle(pose, steer, speed, duration=0.5, substeps=20000):
    """HOPE's KSModel.step: forward Euler of x' = v cos θ, y' = v sin θ, θ' = v tan δ / L, here finely stepped."""
    x, y, th = pose
    dt = duration / substeps
    for _ in range(substeps):
        x, y, th = x + speed * math.cos(th) * dt, y + speed * math.sin(th) * dt, th + speed * math.tan(steer) / 2.8 * dt
    return np.array([x, y, math.atan2(math.sin(th), math.cos(th))])


@pytest.mark.filterwarnings("ignore:.*Box observation space m..imum value is .*infinity:UserWarning")
@pytest.mark.parametrize("config", [HopeEnvConfig(), HopeEnvConfig.backbone("vertices"), HopeEnvConfig.backbone("bev")])
def test_passes_gymnasium_env_checker(config):
    check_env(HopeParkingEnv(example_scenes(), config), skip_render_check=True)


def test_action_is_the_arc_of_hopes_bicycle_model():
    env = HopeParkingEnv(open_lot(), NO_EXTRAS)
    rng = np.random.default_rng(0)
    for a in [*rng.uniform(-1, 1, (6, 2)), (1.0, 1.0), (-1.0, -1.0), (0.0, 0.5), (0.3, 0.0)]:
        start = np.array([-10.0, -12.0, rng.uniform(-math.pi, math.pi)])
        env.reset(seed=1, options={"start": start})
        a = np.asarray(a, np.float32)
        _, _, _, _, info = env.step(a)  # the episode may end by a Hermite connection; the arc is executed first
        expected = hope_bicycle(start, float(a[0]) * 0.75, float(a[1]) * 2.5)
        assert not info["collision"]
        np.testing.assert_allclose(info["pose"][:2], expected[:2], atol=1e-4)
        assert abs(math.remainder(info["pose"][2] - expected[2], 2 * math.pi)) < 1e-4
        np.testing.assert_allclose(info["executed_action"], a, atol=1e-12 if a[1] else 1.0)


def test_learned_curvature_bound_is_hopes():
    arcs = action_to_arc(np.array([[1.0, 1.0], [-1.0, -1.0], [1.0, -0.2]]), HopeEnvConfig())
    np.testing.assert_allclose(np.abs(arcs[:, 0]), math.tan(0.75) / 2.8)
    np.testing.assert_allclose(arcs[:, 1], [1.25, -1.25, -0.25])


def test_footprint_ranges_match_hopes_table_and_shapely():
    b = footprint_ranges(HopeEnvConfig().vehicle, 120)
    # HOPE's rectangle has a 0.93 m rear overhang and 1.94 m width; ours 0.929 and 1.942
    np.testing.assert_allclose(b[:len(HOPE_BASE_HEAD)], HOPE_BASE_HEAD, atol=0.01)
    box = Polygon(HopeEnvConfig().vehicle.footprint_local()).exterior
    for i in range(0, 120, 7):
        ray = LineString([(0, 0), (10 * math.cos(2 * math.pi * i / 120), 10 * math.sin(2 * math.pi * i / 120))])
        assert b[i] == pytest.approx(ray.intersection(box).distance(Point(0, 0)), abs=1e-9)


def test_observation_parts_against_direct_computation():
    scene = example_scenes()[0]
    env = HopeParkingEnv(scene, HopeEnvConfig())
    obs, _ = env.reset(seed=4)
    pose = env.core.S[0, :3].copy()
    lidar = cast_rays(scene, pose) - footprint_ranges(env.config.vehicle, 120)
    np.testing.assert_allclose(obs["lidar"], lidar, atol=1e-5)
    assert obs["lidar"].min() < 10 and obs["lidar"].dtype == np.float32
    gx, gy, gth = scene.target
    bearing = math.atan2(gy - pose[1], gx - pose[0]) - pose[2]
    expected = [math.hypot(gx - pose[0], gy - pose[1]), math.cos(bearing), math.sin(bearing),
                math.cos(gth - pose[2]), math.sin(gth - pose[2])]  # (cos φ, sin φ): HOPE's repeated cos fixed
    np.testing.assert_allclose(obs["target"], expected, atol=1e-5)


def test_vertices_input_is_the_benchmark_slots_and_absent_parts_are_absent():
    scene = example_scenes()[1]
    env = HopeParkingEnv(scene, HopeEnvConfig.backbone("vertices"))
    obs, _ = env.reset(seed=0)
    assert set(obs) == {"lidar", "target", "vertices"}
    np.testing.assert_array_equal(obs["vertices"], static_slots(scene, ObservationConfig()).astype(np.float32))
    assert set(observation_space(HopeEnvConfig())) == {"lidar", "target", "action_mask"}


def test_bev_input_is_the_rendered_raster_with_the_trajectory_tail():
    scene = example_scenes()[2]
    env = HopeParkingEnv(scene, HopeEnvConfig.backbone("bev"))
    obs, _ = env.reset(seed=3)
    assert obs["bev"].shape == (3, 64, 64) and obs["bev"].dtype == np.uint8
    poses = [env.core.S[0, :3].copy()]
    for _ in range(3):
        obs, _, terminated, truncated, info = env.step(np.array([0.2, -0.3], np.float32))
        assert not (terminated or truncated)
        poses.append(info["pose"])
    np.testing.assert_array_equal(obs["bev"], render_bev(scene, poses[-1], tail=np.array(poses[:-1])))
    no_tail = HopeParkingEnv(scene, dataclasses.replace(HopeEnvConfig.backbone("bev"), bev_tail=False))
    no_tail.reset(options={"start": poses[0]})
    for _ in range(3):
        obs, *_ = no_tail.step(np.array([0.2, -0.3], np.float32))
    np.testing.assert_array_equal(obs["bev"], render_bev(scene, poses[-1]))


def test_boundary_and_obstacle_failures_terminate_hard():
    box = [[-25.0, -28.6], [-23.0, -28.6], [-23.0, -27.0], [-25.0, -27.0]]
    env = HopeParkingEnv(open_lot([box]), NO_EXTRAS)
    env.reset(options={"start": [-29.0, -20.0, math.pi]})  # 1 m from the west wall, facing it
    _, reward, terminated, truncated, info = env.step(np.array([0.0, 1.0], np.float32))
    assert terminated and not truncated and info["collision"] and info["out_of_bounds"] and not info["success"]
    assert reward == pytest.approx(-5.0)
    assert info["plan"].reason == "boundary" and not info["plan"].success
    env.reset(options={"start": [-24.0, -26.0, -math.pi / 2]})  # 1 m north of the box, facing it
    _, reward, terminated, _, info = env.step(np.array([0.0, 1.0], np.float32))
    assert terminated and info["collision"] and not info["out_of_bounds"]
    assert reward == pytest.approx(-5.0) and info["plan"].reason == "collision"


def test_direct_success_and_the_episode_plan():
    env = HopeParkingEnv(open_lot(), NO_EXTRAS)
    env.reset(options={"start": [0.0, -1.0, math.pi / 2]})
    _, reward, terminated, _, info = env.step(np.array([0.0, 0.8], np.float32))  # 1 m straight ahead
    assert terminated and info["success"] and info["hermite_index"] == -1
    assert reward == pytest.approx(5.0)
    plan = info["plan"]
    assert plan.success and plan.hermite is None
    np.testing.assert_allclose(plan.arcs, [[0.0, 1.0]], atol=1e-12)


def test_step_budget_truncates_with_hopes_timeout_reward():
    env = HopeParkingEnv(open_lot(), HopeEnvConfig(rs_takeover=False, max_steps=3))
    env.reset(options={"start": [5.0, -15.0, -math.pi / 2]})  # facing away: the Hermite gate stays closed
    for step in range(3):
        _, reward, terminated, truncated, info = env.step(np.array([0.0, 0.1], np.float32))
    assert truncated and not terminated and not info["success"] and info["n_steps"] == 3
    assert reward == pytest.approx(-0.1)
    assert info["plan"].reason == "timeout" and len(info["plan"].arcs) == 3


def test_vector_env_equals_single_env_and_is_deterministic():
    scenes = example_scenes()
    n = 4
    runs = []
    for _ in range(2):
        venv = HopeVectorEnv(scenes, n, HopeEnvConfig(), seed=7)
        obs, _ = venv.reset()
        rng = np.random.default_rng(2)
        trace = [obs["lidar"].copy()]
        for _ in range(25):
            obs, reward, term, trunc, info = venv.step(rng.uniform(-1, 1, (n, 2)))
            trace += [obs["lidar"].copy(), obs["action_mask"].copy(), reward, info["pose"]]
        runs.append(trace)
    for a, b in zip(*runs):
        np.testing.assert_array_equal(a, b)
    venv = HopeVectorEnv(scenes, n, HopeEnvConfig(), seed=7)
    obs, info = venv.reset()
    starts = venv.core.S[:, :3].copy()
    single = HopeParkingEnv(scenes, HopeEnvConfig())
    for i in range(n):
        s_obs, _ = single.reset(options={"scene_index": int(info["scene_index"][i]), "start": starts[i]})
        for key in s_obs:
            np.testing.assert_array_equal(s_obs[key], obs[key][i])


def test_state_dict_resumes_exactly():
    scenes = example_scenes()
    venv = HopeVectorEnv(scenes, 3, HopeEnvConfig(), seed=5)
    venv.reset()
    rng = np.random.default_rng(0)
    actions = rng.uniform(-1, 1, (30, 3, 2))
    for a in actions[:10]:
        venv.step(a)
    state = venv.state_dict()
    resumed = HopeVectorEnv(scenes, 3, HopeEnvConfig(), seed=99)
    resumed.reset()
    resumed.load_state_dict(state)
    for a in actions[10:]:
        out_a, out_b = venv.step(a), resumed.step(a)
        for key in out_a[0]:
            np.testing.assert_array_equal(out_a[0][key], out_b[0][key])
        np.testing.assert_array_equal(out_a[1], out_b[1])


def test_same_step_autoreset_reports_final_observation_and_plan():
    venv = HopeVectorEnv([open_lot()], 2, NO_EXTRAS, seed=0)
    venv.reset(options={"start": [[0.0, -1.0, math.pi / 2], [10.0, -10.0, 0.0]]})
    obs, _, term, _, info = venv.step(np.array([[0.0, 0.8], [0.0, 0.1]]))
    assert term.tolist() == [True, False] and info["_final_obs"].tolist() == [True, False]
    assert info["plan"][0].success and info["plan"][1] is None
    assert info["final_obs"]["target"][0][0] == pytest.approx(0.0, abs=1e-6)  # ended on the target
    assert obs["target"][0][0] > 0.5  # the row holds the next episode


def test_bad_input_is_one_clear_error():
    env = HopeParkingEnv(open_lot(), NO_EXTRAS)
    env.reset(seed=0)
    with pytest.raises(ValueError, match="outside the action space"):
        env.step(np.array([1.5, 0.0]))
    with pytest.raises(ConfigError, match=r"HopeEnvConfig.mask_iterations: expected an integer"):
        HopeEnvConfig.from_dict({"mask_iterations": 2.0})
    with pytest.raises(ConfigError, match=r"HopeEnvConfig.reward: unknown key\(s\) \['bonus'\]"):
        HopeEnvConfig.from_dict({"reward": {"bonus": 1.0}})
    with pytest.raises(ConfigError, match="added_input: expected one of"):
        HopeEnvConfig(added_input="image")
    with pytest.raises(ConfigError, match="rs_spacing_m: expected a finite number > 0"):
        HopeEnvConfig(rs_spacing_m=0.0)
    assert HopeEnvConfig.from_dict(HopeEnvConfig.backbone("vertices").to_dict()) == HopeEnvConfig.backbone("vertices")


def test_the_shared_step_outcome_reads_the_hope_kernels_result_columns():
    from hope_policy import step as K
    from np_sim.kernels import step as NK

    assert (K.R_REWARD, K.R_TERMINATED, K.R_TRUNCATED) == (NK.R_REWARD, NK.R_TERMINATED, NK.R_TRUNCATED)
