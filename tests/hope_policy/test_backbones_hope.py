"""Tests of the HOPE-style backbones of Table III (paper §V-C, App. B "Controlled Representation Inputs"): the
sweep's config files against the paper's rows, the network's branches per added input (sizes counted by hand from
the paper's numbers), the action mask and the RS takeover off, the vertex branch's running statistics against numpy
over the observations a collect produced and their trip through the checkpoint, and one PPO update per input
through the trainer and the planner."""

from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import numpy as np
import pytest
import torch

from cli_helpers import one_error_line
from hope_policy.checkpoint import load_hope_checkpoint, save_hope_checkpoint
from hope_policy.config import HopeEnvConfig
from hope_policy.inputs import PolicyInputs
from hope_policy.network import HopeActorCritic
from hope_policy.planner import HopePlanner
from hope_policy.ppo import HopePPOConfig
from hope_policy.spaces import observation_space
from hope_policy.train import HopeTrainConfig, HopeTrainer, main, train
from np_policy.bev_encoder import KIND, BevAutoencoder, PretrainConfig, load_frozen_encoder
from np_policy.checkpoint import save_checkpoint
from np_sim.benchmarks import load_benchmark
from np_sim.errors import ConfigError
from np_sim.starts import UniformStartSampler

CONFIGS = Path(__file__).resolve().parents[2] / "checkpoints" / "configs"


@pytest.fixture(scope="module")
def autoencoder(tmp_path_factory) -> Path:
    """An untrained autoencoder file in the pretraining's format (the wiring needs its shapes, not its training)."""
    path = tmp_path_factory.mktemp("ae") / "ae.pt"
    config = PretrainConfig(benchmark="factorial", images=10)
    model = BevAutoencoder(config.network, config.raster.size_px)
    save_checkpoint(path, {"kind": KIND, "model": model.state_dict(), "config": config.to_dict(), "metrics": []})
    return path


def backbone_config(added: str, autoencoder: Path | None = None, **overrides) -> HopeTrainConfig:
    """The Table III row on the Factorial scenes with two envs, batches of 16 and one epoch of minibatches of 8."""
    return HopeTrainConfig(num_envs=2, curriculum_pool=8, curriculum_region="lot", env=HopeEnvConfig.backbone(added),
                           bev_encoder_file=str(autoencoder) if added == "bev" else "",
                           ppo=HopePPOConfig(batch_size=16, minibatch_size=8, epochs=1), **overrides)


def linear(n_in, n_out):
    return n_in * n_out + n_out


def test_the_sweep_files_are_the_paper_rows():
    recipe = json.loads((CONFIGS / "recipe.json").read_text())
    for added in ("none", "bev", "vertices"):
        data = json.loads((CONFIGS / f"topology_hope_{added}.json").read_text())
        config = HopeTrainConfig.from_dict({**data, "benchmark": "topology"})
        env = config.env
        assert config.episodes == 10_000 and env.added_input == added
        assert not env.action_mask and not env.rs_takeover and env.connector.mode == "fixed"
        assert env.curriculum.enabled and env.curriculum.start_fraction == 0.05
        # the curriculum of the NeuralParker rows (checkpoints/configs/recipe.json): the whole lot, 1,024 starts
        assert (config.curriculum_region, config.curriculum_pool) == (recipe["curriculum_region"],
                                                                      recipe["curriculum_pool"])
        assert env == HopeEnvConfig.backbone(added)


@pytest.mark.parametrize("added, extra", [("none", 0), ("vertices", 20 * 16 + 10 * 4), ("bev", 128)])
def test_branches_and_parameter_counts_per_added_input(added, extra, autoencoder):
    config = backbone_config(added, autoencoder)
    space = observation_space(config.env)
    assert "action_mask" not in space.spaces
    inputs = PolicyInputs(config.env, config.bev_encoder_file)
    sizes = dict(inputs.modalities(space).sizes)
    assert sizes == {"lidar": 120, "target": 5, **({added: extra} if extra else {})}
    model = HopeActorCritic(inputs.modalities(space))
    d = 128
    embed = linear(120, d) + linear(d, d) + linear(5, d) + linear(d, d)
    # vertices: NeuralParker's slot tokens (obstacle 16 → 64 → 16, boundary 4 → 64 → 16, 30 positions), one
    # attention layer over 16-D tokens (qkv, out, two norms, 32-unit feed-forward), then 16 → 128; bev: tanh, Linear
    slots = linear(16, 64) + linear(64, 16) + linear(4, 64) + linear(64, 16) + 30 * 16
    token_attention = linear(16, 48) + linear(16, 16) + 2 * 16 + linear(16, 32) + linear(32, 16) + 2 * 16
    embed += {"none": 0, "vertices": slots + token_attention + linear(16, d), "bev": linear(128, d)}[added]
    block = 2 * d + d * 768 + linear(256, d) + 2 * d + linear(d, 128) + linear(128, d)
    tokens = 2 + (added != "none")
    actor = embed + block + linear(tokens * d, 128) + linear(128, 2)
    assert sum(p.numel() for p in model.actor.parameters()) == actor
    assert sum(p.numel() for p in model.critic.parameters()) == actor - linear(128, 2) + linear(128, 1)
    assert actor == {"none": 247_170, "vertices": 271_922, "bev": 280_066}[added]  # the figures of the docs
    batch = {key: torch.zeros(3, n) for key, n in sizes.items()}
    assert model.distribution(batch).mean.shape == (3, 2) and model.value(batch).shape == (3,)


def test_bev_inputs_are_the_frozen_encoders_latents(autoencoder):
    inputs = PolicyInputs(HopeEnvConfig.backbone("bev"), str(autoencoder))
    images = np.random.default_rng(0).integers(0, 256, (4, 3, 64, 64), dtype=np.uint8)
    lidar = np.ones((4, 120))
    out = inputs({"bev": images, "lidar": lidar})
    np.testing.assert_array_equal(out["bev"], load_frozen_encoder(autoencoder)(images))
    assert out["bev"].shape == (4, 128) and out["lidar"] is lidar
    other = dataclasses.replace(HopeEnvConfig.backbone("bev"),
                                bev=dataclasses.replace(HopeEnvConfig().bev, tail_poses=5))
    with pytest.raises(ConfigError, match="pretrained on the raster"):
        PolicyInputs(other, str(autoencoder))


def _recorded_collect(trainer: HopeTrainer):
    """One collect with every raw observation the envs returned: (roll, reset observations, per-step records)."""
    resets, steps = [], []
    reset, step = trainer.envs.reset, trainer.envs.step

    def recording_reset(**kwargs):
        obs, info = reset(**kwargs)
        resets.append({k: v.copy() for k, v in obs.items()})
        return obs, info

    def recording_step(actions):
        result = step(actions)
        steps.append((np.array(actions), {k: v.copy() for k, v in result[0].items()}, result[4]))
        return result

    trainer.envs.reset, trainer.envs.step = recording_reset, recording_step
    return trainer.collect(), resets, steps


def test_mask_and_takeover_are_off_and_the_policy_plays_its_gaussian_samples():
    config = dataclasses.replace(backbone_config("none"), num_envs=8,
                                 ppo=HopePPOConfig(batch_size=256, minibatch_size=8))
    roll, _, steps = _recorded_collect(HopeTrainer(config))
    assert "action_mask" not in roll["obs"]
    assert not any(info["rs_takeover"].any() or info["rs_found"].any() for _, _, info in steps)
    played = np.stack([a for a, _, _ in steps])
    np.testing.assert_array_equal(roll["action"], played)  # no chunk replaced an action
    anchors = np.linspace(-1.0, 1.0, 21)  # HOPE's 21 steering anchors, normalised
    steer = played[..., 0][np.abs(played[..., 0]) < 1.0]  # samples beyond the box are clipped onto ±1
    assert len(steer) > 100 and np.all(np.abs(steer[:, None] - anchors).min(-1) > 1e-6)  # not the anchor choice


def test_vertex_statistics_are_the_stream_statistics_and_travel_in_the_checkpoint(tmp_path):
    trainer = HopeTrainer(backbone_config("vertices"))
    _, resets, steps = _recorded_collect(trainer)
    stream = [resets[0]["vertices"]]  # HOPE's statistics start with the first observation
    for _, obs, info in steps:
        done = info.get("_final_obs", np.zeros(len(obs["vertices"]), bool))
        stream.append(np.where(done[:, None], info["final_obs"]["vertices"], obs["vertices"]) if done.any()
                      else obs["vertices"])
    stream = np.concatenate(stream).astype(np.float64)
    stats = trainer.normaliser.stats["vertices"]
    real = stream != trainer.config.env.observation.sentinel  # empty slots are padding, not coordinates
    assert real.any(0).sum() > 3 * 16 and not real.all()  # slots filled in some scenes and empty in others
    masked = np.ma.masked_array(stream, ~real)
    np.testing.assert_array_equal(stats.count, real.sum(0))
    np.testing.assert_allclose(stats.mean, masked.mean(0).filled(0.0), rtol=1e-9, atol=1e-6)
    np.testing.assert_allclose(stats.std, masked.std(0).filled(0.0), rtol=1e-9, atol=1e-6)
    save_hope_checkpoint(tmp_path / "final.pt", trainer.policy_payload())
    stored = load_hope_checkpoint(tmp_path / "final.pt")["obs_norm"]["vertices"]
    np.testing.assert_array_equal(stored["mean"], stats.mean)
    planner = HopePlanner.from_checkpoint(tmp_path / "final.pt")
    x = stream[:3]
    expected = np.where(real[:3], (x - masked.mean(0).filled(0.0)) / (masked.std(0).filled(0.0) + 1e-8), x)
    np.testing.assert_allclose(planner.normaliser({"vertices": x})["vertices"], expected, rtol=1e-4, atol=1e-4)


@pytest.mark.parametrize("added", ["none", "bev", "vertices"])
def test_one_update_per_input_trains_saves_and_plans(added, autoencoder, tmp_path):
    rows = train(backbone_config(added, autoencoder, episodes=1), tmp_path, progress=False, max_updates=1)
    assert len(rows) == 1 and np.isfinite(rows[0]["actor_loss"]) and np.isfinite(rows[0]["critic_loss"])
    assert rows[0]["curriculum_fraction"] == pytest.approx(0.05)
    planner = HopePlanner.from_checkpoint(tmp_path / ("final.pt" if rows[0]["episodes"] >= 1 else "snapshot.pt"))
    scene = load_benchmark("factorial", "test")[0]
    start = UniformStartSampler([scene])(np.random.default_rng(3), np.array([0]))[0]
    plan = planner.plan(scene, start)
    np.testing.assert_array_equal(plan.start, start)
    assert plan.reason in ("", "boundary", "collision", "timeout") or plan.reason.startswith("validation")


def test_cli_needs_the_autoencoder_exactly_for_the_bev_input(tmp_path, capsys, autoencoder):
    line = one_error_line(capsys, main, ["--out", str(tmp_path / "a"), "--input", "bev"])
    assert "bev_encoder_file" in line
    line = one_error_line(capsys, main, ["--out", str(tmp_path / "b"), "--bev-encoder", str(autoencoder)])
    assert "bev_encoder_file" in line and "'none'" in line
    line = one_error_line(capsys, main, ["--out", str(tmp_path / "c"), "--input", "bev", "--bev-encoder",
                                         str(tmp_path / "absent.pt")])
    assert "absent.pt" in line
    assert not any((tmp_path / name).exists() for name in "abc")
