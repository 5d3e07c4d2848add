"""NeuralParkerPlanner: rebuilt from a checkpoint, plays the env's rules, returns a consistent Plan."""

import json

import numpy as np
import pytest

from np_policy.checkpoint import CheckpointError
from np_policy.planner import NeuralParkerPlanner
from np_policy.train import TrainConfig, train
from np_sim.env import ParkingEnv
from np_sim.examples import example_scenes
from np_sim.starts import UniformStartSampler

TINY = {"benchmark": "examples", "seed": 1, "curriculum_pool": 32,
        "ppo": {"num_train_envs": 16, "num_test_envs": 4, "selection_episodes": 8, "steps_per_collect": 256,
                "steps_per_epoch": 256,
                "batch_size": 128, "repeats": 1, "epochs": 1}}


@pytest.fixture(scope="module")
def planner(tmp_path_factory):
    out = tmp_path_factory.mktemp("run")
    train(TrainConfig.from_dict(TINY), out, progress=False)
    return NeuralParkerPlanner.from_checkpoint(out / "best.pt")


def test_plans_replay_exactly_in_the_env(planner):
    scenes = [s for s in example_scenes() if s.tags.get("expect") != "no_path"]
    sampler = UniformStartSampler(scenes)
    rng = np.random.default_rng(0)
    outcomes = set()
    for k in range(len(scenes)):
        for start in sampler(rng, np.full(4, k)):
            plan = planner.plan(scenes[k], start)
            assert plan.arcs.shape[1] == 2 and len(plan.arcs) >= 1 and plan.plan_time_s > 0
            env = ParkingEnv(scenes[k], planner.config.env)
            env.reset(options={"start": start})
            for kappa, length in plan.arcs:
                _, _, term, trunc, info = env.step(np.array([kappa / 0.68, length / 10.0], np.float32))
            assert term or trunc
            assert info["success"] == plan.success
            assert plan.reason == ("" if plan.success else ("collision" if info["collision"] else "timeout"))
            if plan.success:
                L, rev, dk = plan.metrics()
                assert L == pytest.approx(info["path_length"]) and rev == info["reversals"]
                assert dk == pytest.approx(info["delta_kappa"])
            outcomes.add(plan.success)
    assert outcomes == {True, False}


def test_missing_checkpoint_is_a_clear_error(tmp_path):
    with pytest.raises(CheckpointError, match="checkpoint file not found"):
        NeuralParkerPlanner.from_checkpoint(tmp_path / "missing.pt")


def test_evaluate_cli_writes_records_and_table(planner, tmp_path):
    import csv

    from experiments.evaluate import main

    ckpt = tmp_path / "ckpt.pt"
    from np_policy.checkpoint import save_checkpoint

    save_checkpoint(ckpt, {"model": planner.model.state_dict(), "config": planner.config.to_dict()})
    result = main(["--benchmark", "factorial", "--checkpoints", str(ckpt), str(ckpt), "--connector", "fixed",
                   "--out", str(tmp_path / "eval"), "--limit", "12"])
    rows = list(csv.DictReader((tmp_path / "eval" / "records.csv").open()))
    assert len(rows) == 24 and {r["connector"] for r in rows} == {"fixed"}
    # exact validity is recorded per episode; a failed plan is never exact-valid
    assert all(r["exact_footprint_valid"] <= r["exact_ref_point_valid"] <= r["success"] for r in rows)
    assert "| NeuralParker (fixed) |" in result["table"]
    # two identical seeds: the sample SD over seeds is zero
    assert "± 0.000" in result["table"].splitlines()[-1]
    best = main(["--benchmark", "factorial", "--checkpoints", str(ckpt), "--connector", "fixed", "--samples", "3",
                 "--out", str(tmp_path / "best"), "--limit", "6"])
    assert "| NeuralParker, best of 1 + 3 (" in best["table"]
    assert json.loads((tmp_path / "best" / "config.json").read_text())["samples"] == 3
    # the mean rollout is among the candidates, so best-of-N solves every start the mean action solves
    solved = {(r["scene"], int(r["start_id"])) for r in rows[:6] if r["success"] == "1"}
    assert solved <= {(r["scene"], r["start_id"]) for r in best["records"] if r["success"]}
    sampled = main(["--benchmark", "factorial", "--checkpoints", str(ckpt), "--connector", "fixed", "--action",
                    "sample", "--action-seed", "4", "--out", str(tmp_path / "sampled"), "--limit", "6"])
    assert "| NeuralParker, sampled actions (seed 4) (" in sampled["table"]
    config = json.loads((tmp_path / "sampled" / "config.json").read_text())
    assert (config["action"], config["action_seed"]) == ("sample", 4)
    with pytest.raises(SystemExit):
        main(["--benchmark", "factorial", "--checkpoints", str(ckpt), "--action", "greedy"])
    with pytest.raises(SystemExit):
        main(["--benchmark", "factorial", "--checkpoints", str(ckpt), "--action", "sample", "--samples", "2"])


def test_the_connector_can_be_swapped_at_load_and_a_bad_mode_is_named(planner, tmp_path):
    from np_policy.checkpoint import save_checkpoint
    from np_sim.errors import ConfigError

    ckpt = tmp_path / "ckpt.pt"
    save_checkpoint(ckpt, {"model": planner.model.state_dict(), "config": planner.config.to_dict()})
    assert planner.config.env.connector.mode == "ensemble"
    fixed = NeuralParkerPlanner.from_checkpoint(ckpt, "fixed")
    assert fixed.config.env.connector.mode == "fixed"
    assert fixed.config.env.connector.n_candidates < planner.config.env.connector.n_candidates
    centred = NeuralParkerPlanner.from_checkpoint(ckpt, "centred").config.env.connector
    assert centred.mode == "fixed" and centred.headings_deg == (90.0, 80.0, 100.0)
    expected = r"connector: expected one of \('fixed', 'ensemble', 'centred'\), got 'spline'"
    with pytest.raises(ConfigError, match=expected):
        NeuralParkerPlanner.from_checkpoint(ckpt, "spline")


def test_a_success_that_breaks_its_rule_is_claimed_as_a_validation_failure(planner, monkeypatch):
    # a rollout "succeeding" along the arc (κ 0.5, l 3 m) whose front-left corner sweeps 1 mm into the apex of a
    # thin triangle between its 11th and 12th of 30 samples: the sampled footprint passes, the exact rule does not
    import dataclasses

    from np_sim.plan import Plan
    from np_sim.scene import Scene

    triangle = [[4.7417, -1.3138], [5.7286, -1.1508], [5.7343, -1.1904]]
    scene = Scene.from_dict({"boundary": [[-30, -30], [30, -30], [30, 30], [-30, 30]],
                             "obstacles": [{"polygon": triangle}], "target": [20.0, 20.0, 0.0]})
    env = dataclasses.replace(planner.config.env, collision="footprint")
    footprint = NeuralParkerPlanner(planner.model, dataclasses.replace(planner.config, env=env))
    clipped = Plan(start=np.zeros(3), arcs=np.array([[0.5, 3.0]]), success=True)
    monkeypatch.setattr(footprint, "_mean_rollout", lambda scene, start: clipped)
    plan = footprint.plan(scene, np.zeros(3))
    assert not plan.success and plan.reason.startswith("validation: exact rule, segment 0")
    shorter = dataclasses.replace(clipped, arcs=np.array([[0.5, 0.9]]))
    monkeypatch.setattr(footprint, "_mean_rollout", lambda scene, start: shorter)
    assert footprint.plan(scene, np.zeros(3)).success
