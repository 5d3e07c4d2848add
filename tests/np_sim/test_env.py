"""Environments: gymnasium compliance, batched = single, determinism, rewards on hand-computed episodes, layout."""

import dataclasses
import math

import numpy as np
import pytest
from gymnasium.utils.env_checker import check_env

from np_sim.config import ConnectorConfig, EnvConfig, EpisodeConfig, ObservationConfig
from np_sim.env import ParkingEnv, ParkingVectorEnv
from np_sim.errors import CapacityError, ConfigError
from np_sim.examples import example_scenes
from np_sim.lidar import cast_rays, footprint_ranges
from np_sim.observation import observation_sections
from reward_oracle import hermite_score, step_reward, success_reward  # tests/reward_oracle.py
from np_sim.scene import Scene

OPEN_LOT = {"boundary": [[-20, -25], [20, -25], [20, 25], [-20, 25]], "obstacles": [],
            "target": [0.0, 0.0, math.pi / 2]}


def action(kappa, length):
    return np.array([kappa / 0.68, length / 10.0], np.float32)


@pytest.mark.filterwarnings("ignore:.*Box observation space m..imum value is .*infinity:UserWarning")
@pytest.mark.parametrize("flat", [True, False])
def test_passes_gymnasium_env_checker(flat):
    # the unbounded Box is deliberate: target-frame coordinates (m) have no natural bound
    config = EnvConfig(observation=ObservationConfig(flat=flat))
    env = ParkingEnv(example_scenes(), config)
    check_env(env, skip_render_check=True)


def test_vector_env_equals_single_env_step_by_step():
    scenes = example_scenes()
    rng = np.random.default_rng(3)
    n = 6
    venv = ParkingVectorEnv(scenes, n, seed=11)
    obs_v, _ = venv.reset()
    starts = venv.core.S[:, :3].copy()
    kscene = venv.core.S[:, 10].astype(int)
    singles = []
    for i in range(n):
        env = ParkingEnv(scenes)
        o, _ = env.reset(options={"scene_index": kscene[i], "start": starts[i]})
        np.testing.assert_array_equal(o, obs_v[i])
        singles.append(env)
    alive = np.ones(n, bool)
    for _ in range(25):
        acts = rng.uniform(-1, 1, (n, 2)).astype(np.float32)
        obs_v, rew_v, term_v, trunc_v, info = venv.step(acts)
        for i in np.flatnonzero(alive):
            o, r, te, tr, inf = singles[i].step(acts[i])
            final = info["final_obs"][i] if (term_v[i] or trunc_v[i]) else obs_v[i]
            np.testing.assert_array_equal(o, final)
            assert r == rew_v[i] or math.isclose(r, float(rew_v[i]), rel_tol=1e-6)
            assert (te, tr) == (term_v[i], trunc_v[i])
            assert inf["hermite_index"] == info["hermite_index"][i]
            if te or tr:
                alive[i] = False


def test_same_seed_same_starts_and_trajectory():
    scenes = example_scenes()
    runs = []
    for _ in range(2):
        venv = ParkingVectorEnv(scenes, 16, seed=5)
        venv.reset()
        rng = np.random.default_rng(0)
        trace = []
        for _ in range(30):
            o, r, *_ = venv.step(rng.uniform(-1, 1, (16, 2)).astype(np.float32))
            trace.append((o.copy(), r.copy()))
        runs.append(trace)
    for (o1, r1), (o2, r2) in zip(*runs):
        np.testing.assert_array_equal(o1, o2)
        np.testing.assert_array_equal(r1, r2)


def test_hand_computed_episode_with_reversal_and_hermite_success():
    env = ParkingEnv(Scene.from_dict(OPEN_LOT))
    env.reset(options={"start": [0.0, -14.0, -math.pi / 2]})  # facing away: the gate is closed
    _, r1, te, tr, info = env.step(action(0.0, -3.0))  # reverse 3 m straight towards the target
    assert r1 == pytest.approx(-10 * 3 - 5)
    assert not te and not tr and info["hermite_index"] == -1
    np.testing.assert_allclose(info["pose"], [0.0, -11.0, -math.pi / 2], atol=1e-12)
    _, r2, te, tr, info = env.step(action(0.34, 5.0))  # forward right turn: heading swings past the gate
    step2 = -0.05 * 0.34 - 10 * 5 - 5 - 100
    assert step2 == pytest.approx(step_reward(0.34, 5.0, 0.0, -3.0))
    assert te and info["success"] and info["hermite_index"] >= 0
    p_h = -(0.05 * info["hermite_delta_kappa"] + 10 * info["hermite_length"] + 5)
    assert p_h == pytest.approx(hermite_score(info["hermite_delta_kappa"], info["hermite_length"], ensemble=True))
    succ = 1250.5 - 20 * 1 - abs(0.34 - 0.0) + 1.5 * max(p_h, -500)
    assert succ == pytest.approx(success_reward([[0.0, -3.0], [0.34, 5.0]], max(p_h, -500)))
    assert r2 == pytest.approx(step2 + succ, rel=1e-6)
    assert info["reversals"] == 1  # the Hermite segment is driven forward after a forward arc: no extra reversal
    assert info["path_length"] == pytest.approx(8.0 + info["hermite_length"])


def test_direct_terminal_success_has_no_hermite_term():
    env = ParkingEnv(Scene.from_dict(OPEN_LOT))
    env.reset(options={"start": [0.05, -2.0, math.pi / 2]})
    _, r, te, _, info = env.step(action(0.0, 2.0))
    assert te and info["success"] and info["hermite_index"] == -1
    assert r == pytest.approx(-10 * 2 - 5 + 1250.5)


def test_collision_and_timeout():
    env = ParkingEnv(Scene.from_dict(OPEN_LOT))
    env.reset(options={"start": [0.0, -14.0, -math.pi / 2]})
    _, r, te, tr, info = env.step(action(0.0, 10.0))  # 10 m forward leaves the lot at y = −25? no: −24
    assert not te
    _, r, te, tr, info = env.step(action(0.0, 10.0))  # now through the boundary
    assert te and not tr and info["collision"] and not info["success"]
    assert r == pytest.approx(-10 * 10 - 5 - 2501)
    short = EnvConfig(episode=EpisodeConfig(max_arcs=3))
    env = ParkingEnv(Scene.from_dict(OPEN_LOT), short)
    env.reset(options={"start": [0.0, -10.0, -math.pi / 2]})
    flags = [env.step(action(0.0, s))[2:4] for s in (1.0, -1.0, 1.0)]
    assert flags == [(False, False), (False, False), (False, True)]


def test_observation_layout_and_sentinels():
    scene = Scene.from_dict(dict(OPEN_LOT, obstacles=[{"polygon": [[5, 5], [7, 5], [6, 7]]}, {"circle": [-6, 8, 1.0]}]))
    config = EnvConfig()
    env = ParkingEnv(scene, config)
    pose = np.array([3.0, -6.0, 2.0])
    obs, _ = env.reset(options={"start": pose})
    sec = observation_sections(config.observation)
    assert obs.shape == (4 + 120 + 320 + 40,)
    # ego in the target frame: target at the origin heading +y is the world frame rotated by 0
    np.testing.assert_allclose(obs[0:4], [3.0, -6.0, math.cos(2.0), math.sin(2.0)], atol=1e-6)
    lidar = obs[slice(*sec["lidar"])]
    np.testing.assert_allclose(lidar, np.maximum(cast_rays(scene, pose) - footprint_ranges(), 0), atol=1e-5)
    obstacles = obs[slice(*sec["obstacles"])].reshape(20, 16)
    np.testing.assert_allclose(obstacles[0], [5, 5, 7, 5, 6, 7] * 2 + [5, 5, 7, 5], atol=1e-6)  # cyclic repeat
    octagon = obstacles[1].reshape(8, 2)
    np.testing.assert_allclose(np.hypot(octagon[:, 0] + 6, octagon[:, 1] - 8), 1.0, atol=1e-5)
    assert np.all(obstacles[2:] == -1e4)
    boundary = obs[slice(*sec["boundary"])].reshape(10, 4)
    assert np.all(boundary[4:] == -1e4) and np.all(boundary[:4] != -1e4)


def test_ablation_configs_change_the_layout():
    no_lidar = EnvConfig(observation=ObservationConfig(use_lidar=False))
    env = ParkingEnv(example_scenes(), no_lidar)
    assert env.observation_space.shape == (4 + 320 + 40,)
    ego_lidar = EnvConfig(observation=ObservationConfig(use_obstacles=False, use_boundary=False))
    assert ParkingEnv(example_scenes(), ego_lidar).observation_space.shape == (124,)


def test_capacity_overflow_raises_when_the_env_is_built():
    many = [{"circle": [-15 + 1.4 * i, 20.0, 0.5]} for i in range(21)]
    scene = Scene.from_dict(dict(OPEN_LOT, obstacles=many))
    with pytest.raises(CapacityError, match="21.*20|20.*21"):
        ParkingVectorEnv([scene], 2)


def test_bad_actions_and_starts_are_errors():
    env = ParkingVectorEnv([Scene.from_dict(OPEN_LOT)], 2)
    env.reset()
    with pytest.raises(ValueError, match=r"outside the action space"):
        env.step(np.array([[0.0, 1.5], [0.0, 0.0]], np.float32))
    with pytest.raises(ValueError, match=r"shape \(2, 2\)"):
        env.step(np.zeros((3, 2), np.float32))
    with pytest.raises(ConfigError, match="in collision"):
        env.reset(options={"start": [[30.0, 0.0, 0.0], [0.0, 0.0, 0.0]]})


def test_config_round_trip_and_unknown_keys():
    config = EnvConfig(connector=ConnectorConfig(mode="fixed"), collision="footprint")
    assert EnvConfig.from_dict(config.to_dict()) == config
    bad = config.to_dict()
    bad["reward"]["lenght_weight"] = 3
    with pytest.raises(ConfigError, match=r"EnvConfig.reward: unknown key\(s\) \['lenght_weight'\]"):
        EnvConfig.from_dict(bad)
    assert dataclasses.replace(config, collision="reference_point").collision == "reference_point"
