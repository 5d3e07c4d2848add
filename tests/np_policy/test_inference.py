"""CompiledActor: the numba mean action equals the torch ActorCritic's to float32 rounding, for every stream
configuration (full, no LiDAR, ego + LiDAR only) and fusion depth."""

import numpy as np
import pytest
import torch

from np_policy.bench_update import synthetic_obs
from np_policy.config import NetworkConfig
from np_policy.inference import TORCH_BATCH, CompiledActor
from np_policy.network import ActorCritic
from np_sim.config import ObservationConfig

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
