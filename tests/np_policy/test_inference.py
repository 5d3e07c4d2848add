"""CompiledActor: the numba mean action equals the torch ActorCritic's to float32 rounding, for every stream
configuration (full, no LiDAR, ego + LiDAR only) and fusion depth; its compiled mean rollout equals a per-arc loop
of the whole network bit for bit."""

import numpy as np
import pytest
import torch

from np_policy.bench_update import synthetic_obs
from np_policy.config import NetworkConfig
from np_policy.inference import TORCH_BATCH, CompiledActor
from np_policy.network import ActorCritic
from np_sim.config import EnvConfig, ObservationConfig
from np_sim.env_core import BatchCore
from np_sim.kernels import step as K
from np_sim.scene import PolygonObstacle, Scene

CONFIGS = {
    "full": (ObservationConfig(), NetworkConfig()),
    "no_lidar_site": (ObservationConfig(use_lidar=False, max_obstacles=10, vertices_per_obstacle=5,
                                        max_boundary_segments=20), NetworkConfig()),
    "ego_lidar_only": (ObservationConfig(use_obstacles=False, use_boundary=False), NetworkConfig()),
    "depth2_2heads": (ObservationConfig(), NetworkConfig(fusion_depth=2, token_heads=2)),
}


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_compiled_mean_action_matches_torch(name):
    obs_config, net_config = CONFIGS[name]
    torch.manual_seed(0)
    model = ActorCritic(obs_config, net_config).eval()
    with torch.no_grad():  # a larger actor output than at init, so the clip to [−1, 1] is exercised too
        model.actor[-1].weight.mul_(300.0)
    g = torch.Generator().manual_seed(1)
    obs = synthetic_obs(obs_config, 32, g)
    expected = model.mean_action(obs).numpy()
    actor = CompiledActor(model)
    got = np.stack([actor(o) for o in obs.numpy()])
    assert got.dtype == np.float32
    np.testing.assert_allclose(got, expected, atol=2e-5, rtol=1e-4)
    small = TORCH_BATCH - 1  # below the threshold: the compiled kernel, bit for bit
    np.testing.assert_array_equal(actor.batch(obs.numpy()[:small]), got[:small])
    batched = actor.batch(obs.numpy())  # 32 rows: torch's batched forward
    assert batched.dtype == np.float32
    np.testing.assert_allclose(batched, got, atol=2e-5, rtol=1e-4)
    assert (np.abs(expected) == 1.0).any() and (np.abs(expected) < 1.0).any()


def test_wrong_observation_shape_is_a_clear_error():
    actor = CompiledActor(ActorCritic(ObservationConfig(), NetworkConfig()))
    with pytest.raises(ValueError, match=r"expected one observation of shape \(484,\), got \(2, 484\)"):
        actor(np.zeros((2, 484), np.float32))

    with pytest.raises(ValueError, match=r"expected observations of shape \(B, 484\), got \(484,\)"):
        actor.batch(np.zeros(484, np.float32))


@pytest.mark.parametrize("name", sorted(CONFIGS))
def test_the_compiled_rollout_plays_the_whole_network_at_every_arc_bit_for_bit(name):
    """``mean_rollout`` computes the geometry token once per rollout (the slots are the scene's); it plays exactly
    the arcs of a loop that evaluates the whole network at every arc and steps the env, for every stream
    configuration: with and without LiDAR, without any geometry slot, with two fusion blocks."""
    obs_config, net_config = CONFIGS[name]
    torch.manual_seed(2)
    model = ActorCritic(obs_config, net_config).eval()
    with torch.no_grad():  # arcs long and curved enough to wander through the lot for many steps
        model.actor[-1].weight.mul_(10.0)
    actor = CompiledActor(model)
    core = BatchCore([_lot()], 1, EnvConfig(observation=obs_config), None)
    start = np.array([-10.0, -12.0, 3.0])
    assert actor.plays_rollout(core)
    core.reset_envs(np.arange(1), np.random.default_rng(0), 0, start)
    rolled = actor.mean_rollout(core)
    core.reset_envs(np.arange(1), np.random.default_rng(0), 0, start)
    stepped = []
    while True:
        action = actor(core.obs[0]).astype(np.float64)
        stepped.append(action)
        core.step(action[None])
        if core.R[0, K.R_TERMINATED] > 0 or core.R[0, K.R_TRUNCATED] > 0:
            break
    assert len(stepped) > 10, len(stepped)
    np.testing.assert_array_equal(rolled, np.array(stepped))


def _lot() -> Scene:
    """A walled lot, a wall between the start side and the target (no early connection) and a box, within every
    configuration's slots."""
    boundary = np.array([[-40.0, -30.0], [40.0, -30.0], [40.0, 30.0], [-40.0, 30.0]])
    boxes = (np.array([[0.0, -30.0], [2.0, -30.0], [2.0, 20.0], [0.0, 20.0]]),
             np.array([[-25.0, 4.0], [-20.0, 4.0], [-20.0, 7.0], [-25.0, 7.0]]))
    return Scene(boundary=boundary, obstacles=tuple(PolygonObstacle(b) for b in boxes),
                 target=np.array([10.0, -6.0, 0.0]), start_region=None, name="lot")
