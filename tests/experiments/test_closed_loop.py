"""experiments.closed_loop: two site clips end to end, headless, with Hybrid A* and an untrained site policy."""

import argparse
import csv
import json
import re

import pytest
import torch

from experiments.closed_loop import PlannerSettings, _rescue_round, _rescue_text, build_planners, main
from np_policy.checkpoint import save_checkpoint
from np_policy.network import ActorCritic
from np_policy.train import TrainConfig, benchmark_defaults

KNOWN_FEASIBLE = "eval-1000016"
"""Hybrid A* (footprint convention) parks this clip without a touch in closed loop (averse start, one reversal)."""


@pytest.fixture
def site_checkpoint(tmp_path):
    """A randomly initialised (seeded) policy of the paper's site configuration, as a checkpoint file."""
    torch.manual_seed(0)
    config = TrainConfig.from_dict(benchmark_defaults("site"))
    model = ActorCritic(config.env.observation, config.network)
    return save_checkpoint(tmp_path / "site_random.pt", {"model": model.state_dict(), "config": config.to_dict()})


def test_two_clips_run_end_to_end_and_the_known_feasible_clip_parks(tmp_path, site_checkpoint):
    out = tmp_path / "run"
    result = main(["--clips", "--clip-names", KNOWN_FEASIBLE, "eval-1000009", "--planners", "neuralparker",
                   "hybrid_astar", "--checkpoint", str(site_checkpoint), "--no-render", "--out", str(out)])
    rows = list(csv.DictReader((out / "records.csv").open()))
    assert [(r["clip"], r["planner"]) for r in rows] == [(KNOWN_FEASIBLE, "neuralparker"),
                                                          (KNOWN_FEASIBLE, "hybrid_astar"),
                                                          ("eval-1000009", "neuralparker"),
                                                          ("eval-1000009", "hybrid_astar")]
    for key in ("footprint_success", "reference_point_success", "reason", "plan_time_median_ms", "plan_time_first_ms",
                "plan_calls", "plan_failures", "plan_rejected", "path_length_m", "reversals", "final_position_error_m",
                "cross_track_rms_m", "sim_time_s", "wall_time_s", "first_contact_object", "first_plan_footprint_valid",
                "first_plan_exact_footprint_valid"):
        assert key in rows[0]
    hybrid = rows[1]
    assert hybrid["footprint_success"] == "1" and hybrid["reference_point_success"] == "1", hybrid["detail"]
    assert float(hybrid["final_position_error_m"]) < 0.3 and int(hybrid["reversals"]) >= 1
    for r in rows:  # a footprint success is a reference-point success; a failure names its reason
        assert r["reference_point_success"] >= r["footprint_success"]
        assert (r["footprint_success"] == "1") == (r["reason"] == "")
    assert "| Hybrid A* |" in result["table"] and "| NeuralParker |" in result["table"]
    assert "0.60 (0.93) / 7.0 / 1.20 / 0.37" in result["table"]  # the paper's column on the held-out clips
    assert json.loads((out / "records.json").read_text())[1]["planner"] == "hybrid_astar"
    assert (out / "table.md").exists() and (out / "closed_loop.rrd").stat().st_size > 0
    assert len(list((out / "rrd").glob("*.rrd"))) == 4
    assert json.loads((out / "config.json").read_text())["clips"] == [KNOWN_FEASIBLE, "eval-1000009"]


def test_a_missing_checkpoint_is_a_clear_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--clips", "--clips-limit", "1", "--checkpoint", str(tmp_path / "none.pt"), "--out", str(tmp_path)])
    assert exit_info.value.code == 2
    assert "site NeuralParker checkpoint" in capsys.readouterr().err


def test_a_named_footprint_planner_needs_its_checkpoint(tmp_path, site_checkpoint, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--clips", "--clips-limit", "1", "--planners", "neuralparker_footprint", "--checkpoint",
              str(site_checkpoint), "--footprint-checkpoint", str(tmp_path / "none_fp.pt"), "--out",
              str(tmp_path / "run")])
    assert exit_info.value.code == 2
    assert re.search("footprint-aware site checkpoint .*none_fp.pt does not exist", capsys.readouterr().err)


def test_perception_filter_and_search_margin_reach_the_run(tmp_path):
    out = tmp_path / "run"
    main(["--clips", "--clip-names", KNOWN_FEASIBLE, "--planners", "hybrid_astar", "--no-render",
          "--track-window", "5", "--search-margin", "0.15", "--out", str(out)])
    config = json.loads((out / "config.json").read_text())
    assert config["search_margin_m"] == 0.15 and config["clip_run"]["track_window"] == 5
    row = next(csv.DictReader((out / "records.csv").open()))
    assert row["footprint_success"] == "1", row["detail"]


def test_two_workers_give_the_records_of_one(tmp_path, site_checkpoint):
    args = ["--clips", "--clip-names", KNOWN_FEASIBLE, "eval-1000009", "--planners", "neuralparker", "hybrid_astar",
            "--checkpoint", str(site_checkpoint), "--no-render"]
    one = main(args + ["--out", str(tmp_path / "one")])["records"]
    two = main(args + ["--out", str(tmp_path / "two"), "--workers", "2"])["records"]  # hung with fork before
    keys = ("clip", "planner", "footprint_success", "reason", "plan_calls", "path_length_m", "final_position_error_m")
    assert [[r[k] for k in keys] for r in two] == [[r[k] for k in keys] for r in one]


def test_footprint_samples_and_connector_reach_the_planner_and_the_config(tmp_path):
    out = tmp_path / "run"
    main(["--clips", "--clip-names", KNOWN_FEASIBLE, "--planners", "neuralparker_footprint", "--no-render",
          "--footprint-samples", "4", "--footprint-rescue", "8:2", "6:1:uniform", "--out", str(out)])
    config = json.loads((out / "config.json").read_text())
    assert config["footprint_samples"] == 4 and config["footprint_connector"] == "centred"
    assert config["footprint_rescue"] == [[8, 2.0, "policy"], [6, 1.0, "uniform"]]
    table = (out / "table.md").read_text()
    assert "best of its mean rollout and 4 sampled rollouts" in table and "terminal connector: centred" in table
    assert ("When none of them succeeds or the best keeps less than 0.2 m clearance it samples 8 at 2 σ, then 6 "
            "at 1 σ after a uniform first arc (--footprint-rescue)." in table)
    assert config["footprint_rescue_clearance_m"] == 0.2
    default = build_planners(["neuralparker_footprint"], PlannerSettings())["neuralparker_footprint"]
    assert [(r.n, r.first_arc) for r in default.rescue] == [(128, "policy"), (128, "policy"), (128, "uniform")]
    assert default.rescue_clearance_m == 0.2
    off = build_planners(["neuralparker_footprint"], PlannerSettings(footprint_rescue_clearance_m=0.0))
    assert off["neuralparker_footprint"].rescue_clearance_m == 0.0
    for rounds, scale in zip(default.rescue, (2.0, 3.0, 1.0), strict=True):
        assert rounds.std == pytest.approx(scale * default.sampled.std)
    with pytest.raises(SystemExit):
        main(["--clips", "--footprint-rescue", "8", "--out", str(tmp_path / "bad")])
    for bad in ("8:2:grid", "8:2:uniform:1", "0:1"):
        with pytest.raises(argparse.ArgumentTypeError, match=f"expected N:SCALE\\[:FIRST\\] .*got '{bad}'"):
            _rescue_round(bad)
    assert _rescue_round("8:2") == (8, 2.0, "policy") and _rescue_text((8, 2.0, "policy")) == "8:2"
    settings = PlannerSettings(footprint_connector="fixed", footprint_samples=0)
    planner = build_planners(["neuralparker_footprint"], settings)["neuralparker_footprint"]
    assert planner.config.env.connector.headings_deg == (80.0, 90.0, 100.0)  # the checkpoint's, the paper's order
    planner = build_planners(["neuralparker_footprint"], PlannerSettings())["neuralparker_footprint"]
    assert planner.config.env.connector.headings_deg == (90.0, 80.0, 100.0)
    assert planner.config.env.connector.mode == "fixed"
    with pytest.raises(ValueError, match="--footprint-samples: expected >= 0"):
        build_planners(["neuralparker_footprint"], PlannerSettings(footprint_samples=-1))


def test_the_difficult_training_clips_run_by_split(tmp_path, monkeypatch, capsys):
    import np_sim.clips as clips_module

    clips, _ = clips_module.generate_split("train", 12)  # the first twelve training clips: two are difficult
    monkeypatch.setattr(clips_module, "difficult_clips",
                        lambda split: [c for c in clips if c.difficulty.difficult] if split == "train" else None)
    out = tmp_path / "run"
    result = main(["--clips", "--split", "train-difficult", "--clips-limit", "1", "--planners", "hybrid_astar",
                   "--no-render", "--out", str(out)])
    config = json.loads((out / "config.json").read_text())
    assert config["split"] == "train-difficult" and config["clips"] == ["train-0000009"]
    assert [r["clip"] for r in result["records"]] == ["train-0000009"]
    assert "Closed loop on 1 difficult training site clips" in result["table"]
    assert "Paper" not in result["table"]  # the paper's figures are for its held-out clips
    with pytest.raises(SystemExit) as exit_info:
        main(["--clips", "--split", "train-difficult", "--clip-names", KNOWN_FEASIBLE, "--planners", "hybrid_astar",
              "--no-render", "--out", str(tmp_path / "bad")])
    assert exit_info.value.code == 2
    assert re.search(r"\['eval-1000016'\] are not train-difficult clips \(train-0000009 …", capsys.readouterr().err)


def test_stitch_flag_reaches_the_clip_runs_config_and_table(tmp_path):
    out = tmp_path / "run"
    result = main(["--clips", "--clip-names", "eval-1000009", "--planners", "hybrid_astar", "--no-render", "--stitch",
                   "--out", str(out)])
    config = json.loads((out / "config.json").read_text())
    assert config["clip_run"]["stitch"] is True and config["clip_run"]["stitch_margin_m"] == 0.2
    assert "Stitched replanning (--stitch)" in result["table"]
    assert result["records"][0]["footprint_success"]
