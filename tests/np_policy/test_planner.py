"""NeuralParkerPlanner: rebuilt from a checkpoint, plays the env's rules, returns a consistent Plan."""

import dataclasses
import json

import numpy as np
import pytest

from np_policy.checkpoint import CheckpointError
from np_policy.config import (FOOTPRINT_ANYTIME, FOOTPRINT_BEST_OF_N, FOOTPRINT_SEARCH, PAPER, PRESETS,
                              NeuralParkerConfig)
from np_policy.planner import NeuralParkerPlanner, Policy
from np_policy.train import TrainConfig, train
from np_sim.errors import ConfigError
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
            env = ParkingEnv(scenes[k], planner.env_config)
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

    save_checkpoint(ckpt, {"model": planner.model.state_dict(), "config": planner.policy.train.to_dict()})
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
    assert json.loads((tmp_path / "best" / "config.json").read_text())["neuralparker"]["samples"] == 3
    # the mean rollout is among the candidates, so best-of-N solves every start the mean action solves
    solved = {(r["scene"], int(r["start_id"])) for r in rows[:6] if r["success"] == "1"}
    assert solved <= {(r["scene"], r["start_id"]) for r in best["records"] if r["success"]}
    sampled = main(["--benchmark", "factorial", "--checkpoints", str(ckpt), "--connector", "fixed", "--action",
                    "sample", "--action-seed", "4", "--out", str(tmp_path / "sampled"), "--limit", "6"])
    assert "| NeuralParker, sampled actions (seed 4) (" in sampled["table"]
    config = json.loads((tmp_path / "sampled" / "config.json").read_text())["neuralparker"]
    assert (config["action"], config["seed"]) == ("sample", 4)
    with pytest.raises(SystemExit):
        main(["--benchmark", "factorial", "--checkpoints", str(ckpt), "--action", "greedy"])
    with pytest.raises(SystemExit):
        main(["--benchmark", "factorial", "--checkpoints", str(ckpt), "--action", "sample", "--samples", "2"])


def test_the_connector_can_be_swapped_at_load_and_a_bad_mode_is_named(planner, tmp_path):
    from np_policy.checkpoint import save_checkpoint

    ckpt = tmp_path / "ckpt.pt"
    save_checkpoint(ckpt, {"model": planner.model.state_dict(), "config": planner.policy.train.to_dict()})
    assert planner.env_config.connector.mode == "ensemble"
    fixed = NeuralParkerPlanner.from_checkpoint(ckpt, NeuralParkerConfig(connector="fixed"))
    assert fixed.env_config.connector.mode == "fixed"
    assert fixed.env_config.connector.n_candidates < planner.env_config.connector.n_candidates
    centred = NeuralParkerPlanner.from_checkpoint(ckpt, NeuralParkerConfig(connector="centred")).env_config.connector
    assert centred.mode == "fixed" and centred.headings_deg == (90.0, 80.0, 100.0)
    expected = r"connector: expected one of \('fixed', 'ensemble', 'centred'\) or None, got 'spline'"
    with pytest.raises(ConfigError, match=expected):
        NeuralParkerConfig(connector="spline")


def test_a_success_that_breaks_its_rule_is_claimed_as_a_validation_failure(planner, monkeypatch):
    # a rollout "succeeding" along the arc (κ 0.5, l 3 m) whose front-left corner sweeps 1 mm into the apex of a
    # thin triangle between its 11th and 12th of 30 samples: the sampled footprint passes, the exact rule does not
    import dataclasses

    from np_sim.plan import Plan
    from np_sim.scene import Scene

    triangle = [[4.7417, -1.3138], [5.7286, -1.1508], [5.7343, -1.1904]]
    scene = Scene.from_dict({"boundary": [[-30, -30], [30, -30], [30, 30], [-30, 30]],
                             "obstacles": [{"polygon": triangle}], "target": [20.0, 20.0, 0.0]})
    env = dataclasses.replace(planner.env_config, collision="footprint")
    footprint = NeuralParkerPlanner(Policy(planner.model, dataclasses.replace(planner.policy.train, env=env)))
    assert footprint.convention == "footprint" and planner.convention == "reference_point"
    clipped = Plan(start=np.zeros(3), arcs=np.array([[0.5, 3.0]]), success=True)
    monkeypatch.setattr(footprint, "_mean_rollout", lambda scene, start: clipped)
    plan = footprint.plan(scene, np.zeros(3))
    assert not plan.success and plan.reason.startswith("validation: exact rule, segment 0")
    shorter = dataclasses.replace(clipped, arcs=np.array([[0.5, 0.9]]))
    monkeypatch.setattr(footprint, "_mean_rollout", lambda scene, start: shorter)
    assert footprint.plan(scene, np.zeros(3)).success


def test_presets_are_the_documented_recipes_and_round_trip_through_json():
    """'paper' is the mean rollout with the checkpoint's connector; 'footprint_best_of_n' is the recipe of
    docs/planners.md (32 samples, rescue rounds 128 at 2 σ, 128 at 3 σ, 128 with uniform first arcs at 1 σ, the
    rescue for clearance below 0.2 m, the centred connector); 'footprint_search' is 'footprint_anytime' with the
    0.2 m search, the clearance capped at the start's and the target's and the plain mean rollout capped at 50 arcs;
    every preset survives to_dict → JSON → from_dict."""
    assert PRESETS == {"paper": PAPER, "footprint_best_of_n": FOOTPRINT_BEST_OF_N,
                       "footprint_anytime": FOOTPRINT_ANYTIME, "footprint_search": FOOTPRINT_SEARCH}
    assert FOOTPRINT_SEARCH == dataclasses.replace(FOOTPRINT_ANYTIME, search_margin_m=0.2,
                                                   start_limited_clearance=True, target_limited_clearance=True,
                                                   mean_capped=True)
    assert (PAPER.action, PAPER.samples, PAPER.rescue, PAPER.connector, PAPER.margin_m) == ("mean", 0, (), None, 0.0)
    best = FOOTPRINT_BEST_OF_N
    assert (best.samples, best.connector, best.rescue_clearance_m) == (32, "centred", 0.2)
    assert best.rescue == ((128, 2.0, "policy"), (128, 3.0, "policy"), (128, 1.0, "uniform"))
    for name, preset in PRESETS.items():
        assert NeuralParkerConfig.preset(name) is preset
        assert NeuralParkerConfig.from_dict(json.loads(json.dumps(preset.to_dict()))) == preset
    assert NeuralParkerConfig(rescue=((8, 2),)).rescue == ((8, 2.0, "policy"),)
    with pytest.raises(ConfigError,
                       match=r"expected a preset name, one of \['footprint_anytime', 'footprint_best_of_n', "
                             r"'footprint_search', 'paper'\]"):
        NeuralParkerConfig.preset("best")
    with pytest.raises(ConfigError, match=r"NeuralParkerConfig: unknown key\(s\) \['sample'\]"):
        NeuralParkerConfig.from_dict({"sample": 3})
    with pytest.raises(ConfigError, match=r"NeuralParkerConfig.samples: expected an integer, got 2.5"):
        NeuralParkerConfig.from_dict({"samples": 2.5})


def test_a_preset_by_name_builds_the_same_planner_as_its_config(planner, tmp_path):
    from np_policy.checkpoint import save_checkpoint
    from np_sim.planners import Planner

    ckpt = tmp_path / "ckpt.pt"
    save_checkpoint(ckpt, {"model": planner.model.state_dict(), "config": planner.policy.train.to_dict()})
    by_name = NeuralParkerPlanner.from_checkpoint(ckpt, "footprint_best_of_n")
    assert by_name.config is FOOTPRINT_BEST_OF_N and isinstance(by_name, Planner)
    assert by_name.sampled.n == 32 and [r.n for r in by_name.rescue] == [128, 128, 128]
    assert (by_name.name, by_name.convention) == ("neuralparker", planner.policy.train.env.collision)
