"""Checkpoint format v2: no code runs from a crafted file, the digest catches flipped bytes, structural and layout
mismatches are CheckpointErrors naming the file, v1 files are refused and upgraded only by the explicit command."""

import dataclasses
import os

import numpy as np
import pytest
import torch

from np_policy.checkpoint import (CHECKPOINT_FORMAT, LEGACY_FORMAT, CheckpointError, load_checkpoint, load_weights,
                                  main, save_checkpoint, write_atomic)
from np_policy.config import PPOConfig, check_types
from np_policy.network import ActorCritic
from np_policy.planner import NeuralParkerPlanner
from np_policy.train import TrainConfig, benchmark_defaults
from np_sim.errors import ConfigError

WEIGHT = torch.arange(64, dtype=torch.float32) * 1.2345 + 0.5
"""A tensor whose bytes are easy to find in the file."""


class _Trap:
    """Unpickling this runs ``open(path, 'w')``: it would create a file."""

    def __init__(self, path):
        self.path = str(path)

    def __reduce__(self):
        return (open, (self.path, "w"))


def _small(tmp_path, name="small.pt", **extra):
    payload = {"model": {"w": WEIGHT.clone()}, "config": {"benchmark": "factorial"}, **extra}
    return save_checkpoint(tmp_path / name, payload)


def test_a_crafted_pickle_is_refused_and_never_run(tmp_path):
    marker = tmp_path / "created_by_the_pickle"
    path = tmp_path / "crafted.pt"
    torch.save({"format": CHECKPOINT_FORMAT, "model": {}, "config": {}, "x": _Trap(marker)}, path)
    with pytest.raises(CheckpointError, match=r"crafted.pt: refused: .*nothing in it was run"):
        load_checkpoint(path)
    assert not marker.exists()
    torch.load(path, weights_only=False)  # the trap is live: an unsafe load does create the file
    assert marker.exists()


def test_the_upgrade_command_refuses_a_file_that_is_not_v1_without_unpickling_it(tmp_path, capsys):
    marker = tmp_path / "created_by_the_pickle"
    path = tmp_path / "crafted.pt"
    torch.save({"format": "something-else", "x": _Trap(marker)}, path)
    assert main(["upgrade", str(path)]) == 2
    assert not marker.exists() and capsys.readouterr().err.startswith(f"error: {path}")


def _tensor_offset(path, tensor):
    data = path.read_bytes()
    offset = data.find(tensor.numpy().tobytes())
    assert offset > 0 and data.count(tensor.numpy().tobytes()) == 1
    return offset


def test_a_flipped_byte_in_a_tensor_is_reported(tmp_path):
    path = _small(tmp_path)
    assert torch.equal(load_checkpoint(path)["model"]["w"], WEIGHT)
    data = bytearray(path.read_bytes())
    data[_tensor_offset(path, WEIGHT) + 17] ^= 0x01
    path.write_bytes(bytes(data))
    raw = torch.load(path, weights_only=True)  # torch itself reads the damaged tensor silently
    assert not torch.equal(raw["model"]["w"], WEIGHT)
    with pytest.raises(CheckpointError, match=r"small.pt: content does not match its SHA-256"):
        load_checkpoint(path)


def test_64_flipped_bytes_anywhere_are_reported(tmp_path):
    path = _small(tmp_path, note="x" * 200, obs=np.linspace(0.0, 1.0, 50))
    clean = path.read_bytes()
    rng = np.random.default_rng(0)
    for trial in range(20):
        data = bytearray(clean)
        for position in rng.choice(len(data), 64, replace=False):
            data[position] ^= 0xFF
        path.write_bytes(bytes(data))
        with pytest.raises(CheckpointError, match=r"small.pt: "):
            load_checkpoint(path)


def test_a_changed_plain_value_is_reported(tmp_path):
    path = _small(tmp_path, epoch=12)
    data = path.read_bytes()
    assert data.count(b"factorial") == 1
    path.write_bytes(data.replace(b"factorial", b"factoriaL"))  # same length, one letter inside the pickle
    with pytest.raises(CheckpointError, match=r"SHA-256|not a readable"):
        load_checkpoint(path)


def test_numpy_arrays_and_rng_states_round_trip(tmp_path):
    rng = np.random.default_rng(7)
    obs = rng.normal(size=(3, 4)).astype(np.float32)
    state = rng.bit_generator.state
    path = _small(tmp_path, obs=obs, rng=state, flags=np.array([True, False]), count=np.float64(2.5))
    back = load_checkpoint(path)
    assert back["obs"].dtype == np.float32 and np.array_equal(back["obs"], obs)
    assert back["rng"] == state and back["flags"].tolist() == [True, False] and back["count"] == 2.5
    assert torch.load(path, weights_only=True)["format"] == CHECKPOINT_FORMAT
    with pytest.raises(CheckpointError, match=r"entry payload.x: object is not storable"):
        _small(tmp_path, "other.pt", x=object())


def test_a_v1_file_is_refused_with_the_upgrade_command_and_upgraded_by_it(tmp_path, capsys):
    obs = np.arange(6, dtype=np.float64).reshape(2, 3)
    path = tmp_path / "old.pt"
    torch.save({"format": LEGACY_FORMAT, "model": {"w": WEIGHT.clone()}, "config": {"seed": 3}, "obs": obs,
                "epoch": 5}, path)
    with pytest.raises(CheckpointError, match=r"old.pt: format 'neuralparker-checkpoint-v1' .* "
                                              r"`python -m np_policy.checkpoint upgrade .*old.pt`"):
        load_checkpoint(path)
    assert main(["upgrade", str(path)]) == 0
    assert "upgraded to neuralparker-checkpoint-v2" in capsys.readouterr().out
    back = load_checkpoint(path)
    assert torch.equal(back["model"]["w"], WEIGHT) and np.array_equal(back["obs"], obs)
    assert back["config"] == {"seed": 3} and back["epoch"] == 5 and "format" not in back
    assert sorted(os.listdir(tmp_path)) == ["old.pt"]  # no temporary file left behind
    assert main(["upgrade", str(path)]) == 0 and "already" in capsys.readouterr().out
    assert main(["check", str(path)]) == 0


def test_missing_file_and_directory_are_named(tmp_path, capsys):
    with pytest.raises(CheckpointError, match=r"nope.pt: checkpoint file not found"):
        load_checkpoint(tmp_path / "nope.pt")
    with pytest.raises(CheckpointError, match=r"expected a checkpoint file, found a directory"):
        load_checkpoint(tmp_path)
    assert main(["check", str(tmp_path / "nope.pt")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("error: ") and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_shape_and_key_mismatches_name_the_file_and_the_key(tmp_path):
    path = _small(tmp_path)
    module = torch.nn.Linear(8, 8)  # weight (8, 8), bias (8,)
    state = {"weight": torch.zeros(8, 4), "bias": torch.zeros(8), "extra": torch.zeros(1)}
    with pytest.raises(CheckpointError) as info:
        load_weights(module, state, path)
    message = str(info.value)
    assert message.startswith(f"{path}: the model weights do not fit")
    assert "weight: checkpoint shape (8, 4), network shape (8, 8)" in message
    assert "unexpected keys ['extra']" in message
    with pytest.raises(CheckpointError, match=r"missing keys \['bias'\]"):
        load_weights(module, {"weight": torch.zeros(8, 8)}, path)


def test_a_planner_checkpoint_whose_weights_do_not_fit_its_config_names_file_and_key(tmp_path):
    config = TrainConfig()
    model = ActorCritic(config.env.observation, config.network)
    wider = dataclasses.replace(config, network=dataclasses.replace(config.network, token_dim=32))
    path = save_checkpoint(tmp_path / "mismatch.pt", {"model": model.state_dict(), "config": wider.to_dict()})
    with pytest.raises(CheckpointError, match=r"mismatch.pt: the model weights do not fit .*checkpoint shape "
                                              r"\(16, .*network shape \(32"):
        NeuralParkerPlanner.from_checkpoint(path)


def test_a_site_checkpoint_is_refused_for_factorial_scenes_with_both_layouts_named(tmp_path):
    site = TrainConfig.from_dict(benchmark_defaults("site"))
    model = ActorCritic(site.env.observation, site.network)
    path = save_checkpoint(tmp_path / "site.pt", {"model": model.state_dict(), "config": site.to_dict()})
    planner = NeuralParkerPlanner.from_checkpoint(path, benchmark="site")
    assert planner.env_config.observation == site.env.observation
    with pytest.raises(CheckpointError) as info:
        NeuralParkerPlanner.from_checkpoint(path, benchmark="factorial")
    message = str(info.value)
    assert message.startswith(f"{path}: its observation layout (trained on 'site': 10 obstacles x 5 vertices")
    assert "no LiDAR" in message
    assert ("benchmark 'factorial' (20 obstacles x 8 vertices, 10 boundary segments, LiDAR 120 beams to 10.0 m)"
            in message)
    assert "observation.use_lidar: checkpoint has False, expected True" in message


def test_a_representation_ablation_plans_the_benchmark_it_was_trained_on(tmp_path):
    from np_sim.benchmarks import frozen_starts, load_benchmark

    none = TrainConfig.from_dict({"benchmark": "topology", "env": {"observation": {
        "use_obstacles": False, "use_boundary": False}}})
    model = ActorCritic(none.env.observation, none.network)
    path = save_checkpoint(tmp_path / "none.pt", {"model": model.state_dict(), "config": none.to_dict()})
    planner = NeuralParkerPlanner.from_checkpoint(path, benchmark="topology")
    assert planner.env_config.observation == none.env.observation  # no obstacle or boundary slots
    plan = planner.plan(load_benchmark("topology", "test")[0], frozen_starts("topology")[0, 0])
    assert plan.reason in ("", "collision", "timeout")  # an untrained policy plans; whether it parks is its own
    with pytest.raises(CheckpointError, match="its observation layout \\(trained on 'topology': no obstacle slots"):
        NeuralParkerPlanner.from_checkpoint(path, benchmark="factorial")  # another benchmark: the layout must match


def test_an_invalid_stored_config_is_a_checkpoint_error(tmp_path):
    config = TrainConfig().to_dict()
    config["ppo"]["epochs"] = 2.5
    path = save_checkpoint(tmp_path / "bad_config.pt", {"model": {}, "config": config})
    with pytest.raises(CheckpointError, match=r"bad_config.pt: its stored config .*ppo.epochs: expected an "
                                              r"integer, got 2.5"):
        NeuralParkerPlanner.from_checkpoint(path)


def test_write_atomic_replaces_whole_files_and_leaves_no_temporary(tmp_path):
    path = tmp_path / "f.bin"
    write_atomic(path, b"first")
    write_atomic(path, b"second")
    assert path.read_bytes() == b"second" and os.listdir(tmp_path) == ["f.bin"]
    umask = os.umask(0)
    os.umask(umask)
    assert path.stat().st_mode & 0o777 == 0o666 & ~umask


@pytest.mark.parametrize("data, message", [
    ({"epochs": 2.5}, r"PPOConfig.epochs: expected an integer, got 2.5"),
    ({"epochs": True}, r"PPOConfig.epochs: expected an integer, got True"),
    ({"learning_rate": "fast"}, r"PPOConfig.learning_rate: expected a number, got 'fast'"),
    ({"norm_rewards": 1}, r"PPOConfig.norm_rewards: expected true or false, got 1"),
])
def test_config_values_of_the_wrong_type_are_named(data, message):
    with pytest.raises(ConfigError, match=message):
        PPOConfig.from_dict(data)


def test_nested_config_types_are_checked_and_ints_count_as_floats():
    assert PPOConfig.from_dict({"learning_rate": 1}).learning_rate == 1
    with pytest.raises(ConfigError, match=r"TrainConfig.env.connector.mode: expected one of 'ensemble', 'fixed'"):
        TrainConfig.from_dict({"env": {"connector": {"mode": "both"}}})
    with pytest.raises(ConfigError, match=r"TrainConfig.network.head_hidden: expected a list of an integer"):
        TrainConfig.from_dict({"network": {"head_hidden": [64, 1.5]}})
    with pytest.raises(ConfigError, match=r"TrainConfig.ppo: expected a mapping \(a JSON object\), got list"):
        check_types(TrainConfig, {"ppo": [1, 2]})
