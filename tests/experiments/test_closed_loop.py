"""experiments.closed_loop: two site clips end to end, headless, with Hybrid A* and an untrained site policy."""

import csv
import dataclasses
import json
import re

import numpy as np
import pytest
import torch

from experiments.closed_loop import SITE_PLANNERS, ClosedLoopConfig, main
from experiments.overrides import apply_overrides
from experiments.registry import build_planners
from np_policy.checkpoint import save_checkpoint
from np_policy.config import FOOTPRINT_ANYTIME, FOOTPRINT_SEARCH, PAPER
from np_policy.network import ActorCritic
from np_policy.train import TrainConfig, benchmark_defaults

KNOWN_FEASIBLE = "eval-1000016"
"""Hybrid A* (footprint convention) parks this clip without a touch in closed loop (averse start, one reversal)."""


TWO_CLIPS = ["--clips", "--clip-names", KNOWN_FEASIBLE, "eval-1000009", "--planners", "neuralparker", "hybrid_astar",
             "--no-render"]


@pytest.fixture(scope="module")
def site_checkpoint(tmp_path_factory):
    """A randomly initialised (seeded) policy of the paper's site configuration, as a checkpoint file."""
    torch.manual_seed(0)
    config = TrainConfig.from_dict(benchmark_defaults("site"))
    model = ActorCritic(config.env.observation, config.network)
    return save_checkpoint(tmp_path_factory.mktemp("site") / "site_random.pt",
                           {"model": model.state_dict(), "config": config.to_dict()})


@pytest.fixture(scope="module")
def two_clip_run(tmp_path_factory, site_checkpoint):
    """The two clips with the untrained policy and Hybrid A* on two workers: (its folder, what main returned)."""
    out = tmp_path_factory.mktemp("two_clips") / "run"
    return out, main(TWO_CLIPS + ["--checkpoint", str(site_checkpoint), "--workers", "2", "--out", str(out)])


def test_two_clips_run_end_to_end_and_the_known_feasible_clip_parks(two_clip_run, site_checkpoint):
    out, result = two_clip_run
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
    records = json.loads((out / "records.json").read_text())
    assert records[1]["planner"] == "hybrid_astar" and set(records[1]["plan_stages"]) == {""}
    calls = sum(r["plan_calls"] for r in records if r["planner"] == "neuralparker")
    assert all(len(r["plan_times_ms"]) == len(r["plan_stages"]) == r["plan_calls"] for r in records)
    assert {s for r in records if r["planner"] == "neuralparker" for s in r["plan_stages"]} == {"mean"}
    times = [t for r in records if r["planner"] == "neuralparker" for t in r["plan_times_ms"]]
    row = f"| NeuralParker | {calls} | {np.median(times):.1f} / {np.percentile(times, 90):.1f} | {calls} ("
    assert row in result["table"]
    assert "| Hybrid A* | " in result["table"] and result["table"].count(" | – |") >= 1
    assert (out / "table.md").exists() and (out / "closed_loop.rrd").stat().st_size > 0
    assert len(list((out / "rrd").glob("*.rrd"))) == 4
    config = json.loads((out / "config.json").read_text())
    assert config["clips"] == [KNOWN_FEASIBLE, "eval-1000009"]
    assert config["config"]["planner"]["checkpoint"] == str(site_checkpoint)
    assert ClosedLoopConfig.__dataclass_fields__.keys() == config["config"].keys()


def test_a_missing_checkpoint_is_a_clear_error(tmp_path, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--clips", "--clips-limit", "1", "--checkpoint", str(tmp_path / "none.pt"), "--out", str(tmp_path)])
    assert exit_info.value.code == 2
    assert re.search("planner neuralparker: its checkpoint .*none.pt does not exist; pass --checkpoint PATH",
                     capsys.readouterr().err)


def test_a_named_footprint_planner_needs_its_checkpoint(tmp_path, site_checkpoint, capsys):
    with pytest.raises(SystemExit) as exit_info:
        main(["--clips", "--clips-limit", "1", "--planners", "neuralparker_footprint", "--checkpoint",
              str(site_checkpoint), "--set", f"planner.footprint_checkpoint={tmp_path / 'none_fp.pt'}", "--out",
              str(tmp_path / "run")])
    assert exit_info.value.code == 2
    assert re.search("planner neuralparker_footprint: its checkpoint .*none_fp.pt does not exist; pass --set "
                     "planner.footprint_checkpoint=PATH", capsys.readouterr().err)


def test_perception_filter_and_search_margin_reach_the_run(tmp_path):
    out = tmp_path / "run"
    main(["--clips", "--clip-names", KNOWN_FEASIBLE, "--planners", "hybrid_astar", "--no-render",
          "--set", "clip_run.track_window=5", "planner.search_margin_m=0.15", "--out", str(out)])
    config = json.loads((out / "config.json").read_text())["config"]
    assert config["planner"]["search_margin_m"] == 0.15 and config["clip_run"]["track_window"] == 5
    assert config["workers"] == 1  # one per core by default, but never more than the clips
    row = next(csv.DictReader((out / "records.csv").open()))
    assert row["footprint_success"] == "1", row["detail"]


def test_two_workers_give_the_records_of_one(tmp_path, site_checkpoint, two_clip_run):
    two_out, two = two_clip_run  # two workers hung with fork before
    one = main(TWO_CLIPS + ["--checkpoint", str(site_checkpoint), "--out", str(tmp_path / "one"), "--workers", "1"])
    assert [(r["clip"], r["planner"]) for r in two["records"]] == [(r["clip"], r["planner"]) for r in one["records"]]
    assert [_untimed(r) for r in two["records"]] == [_untimed(r) for r in one["records"]]  # all but the wall clock
    workers = [json.loads((out / "config.json").read_text())["config"]["workers"] for out in (tmp_path / "one",
                                                                                              two_out)]
    assert workers == [1, 2]


def _untimed(row: dict) -> str:
    """``row`` without its wall-clock columns (plan times, the run's wall time and real-time factor), as JSON text
    (a NaN equals a NaN there)."""
    return json.dumps({k: v for k, v in row.items() if k not in TIMING_COLUMNS}, sort_keys=True)


TIMING_COLUMNS = ("plan_time_median_ms", "plan_time_first_ms", "plan_time_max_ms", "plan_times_ms", "wall_time_s",
                  "realtime_factor")
"""The record columns measured on the wall clock; every other column is a function of the seeds and settings."""


def test_footprint_preset_fields_reach_the_planner_and_the_config(tmp_path):
    out = tmp_path / "run"
    rescue = 'planner.neuralparker_footprint.rescue=[[8, 2], [6, 1, "uniform"]]'
    main(["--clips", "--clip-names", KNOWN_FEASIBLE, "--planners", "neuralparker_footprint", "--no-render", "--set",
          "planner.neuralparker_footprint.samples=4", rescue, "planner.neuralparker_footprint.guard_sigmas=[1, 2, 3]",
          "--out", str(out)])
    config = json.loads((out / "config.json").read_text())["config"]["planner"]["neuralparker_footprint"]
    assert config["samples"] == 4 and config["connector"] == "centred" and config["rescue_clearance_m"] == 0.2
    assert config["rescue"] == [[8, 2.0, "policy"], [6, 1.0, "uniform"]] and config["accept_mean_m"] == 0.2
    assert config["rollout_max_arcs"] == 50 and config["rescue_stop_m"] is None and config["mean_margin_m"] == 0.2
    table = (out / "table.md").read_text()
    assert ("returns its mean rollout, played first with the body grown by 0.2 m, then as is "
            "(planner.neuralparker_footprint.mean_margin_m) (before the plain one, the guarded mean rollout: each arc "
            "the first of the mean action and offsets at 1, 2, 3 σ that parks aligned, else does not collide; "
            "planner.neuralparker_footprint.guard_sigmas), at once when that succeeds, is steerable and keeps "
            "0.2 m of clearance") in table
    assert "best of its mean rollout and 4 sampled rollouts" in table and "terminal connector: centred" in table
    assert ("When none of them succeeds or the best keeps less than 0.2 m clearance it samples 8 at 2 σ, then 6 "
            "at 1 σ after a uniform first arc (planner.neuralparker_footprint.rescue)." in table)
    assert ("sampled, grown-body mean, guarded and rescue rollouts end as timeouts after 50 arcs, its plain mean "
            "rollout at the policy env's budget (planner.neuralparker_footprint.rollout_max_arcs)." in table
            and "rescue_stop_m" not in table)


def test_the_default_site_planners_are_the_presets():
    """The footprint row plays the 'footprint_anytime' preset (rescue rounds at 2, 3 and 1 σ of the policy's
    own standard deviation), the paper-faithful row and NP-Guided A*'s guide the 'paper' preset with the site
    checkpoint's connector (the paper's order); both searches plan under the footprint convention."""
    assert SITE_PLANNERS.neuralparker == PAPER and SITE_PLANNERS.neuralparker_footprint == FOOTPRINT_ANYTIME
    assert SITE_PLANNERS.neuralparker_search == FOOTPRINT_SEARCH
    planners = build_planners(["neuralparker", "neuralparker_footprint", "np_guided_astar", "hybrid_astar"],
                              SITE_PLANNERS)
    default = planners["neuralparker_footprint"]
    assert [(r.n, r.first_arc) for r in default.rescue] == [(128, "policy"), (128, "policy"), (128, "uniform")]
    assert [r.config.episode.max_arcs for r in (default.mean, default.sampled, *default.rescue)] == [200] + [50] * 4
    for rounds, scale in zip(default.rescue, (2.0, 3.0, 1.0), strict=True):
        assert rounds.std == pytest.approx(scale * default.sampled.std)
    assert default.env_config.connector.headings_deg == (90.0, 80.0, 100.0)
    assert default.env_config.connector.mode == "fixed"
    assert planners["neuralparker"].env_config.connector.headings_deg == (80.0, 90.0, 100.0)
    assert planners["np_guided_astar"].learned.policy is planners["neuralparker"].policy  # loaded once
    assert {name: p.convention for name, p in planners.items()} == {
        "neuralparker": "reference_point", "neuralparker_footprint": "footprint", "np_guided_astar": "footprint",
        "hybrid_astar": "footprint"}
    assert all(p.name == name for name, p in planners.items() if name != "neuralparker_footprint")


def test_set_overrides_any_field_by_its_path_and_names_a_bad_one():
    config = apply_overrides(ClosedLoopConfig(), ["planner.neuralparker_footprint=paper", "controller=stanley",
                                                  "planner.neuralparker.connector=ensemble", "clip_names=[\"a\"]",
                                                  "planner.footprint_checkpoint=x.pt", "clips_limit=null"])
    assert config.planner.neuralparker_footprint == PAPER and config.controller == "stanley"
    assert config.planner.neuralparker.connector == "ensemble" and config.clip_names == ("a",)
    assert str(config.planner.footprint_checkpoint) == "x.pt" and config.clips_limit is None
    bad = {"planner.neuralparker_footprint.sample=3": r"NeuralParkerConfig: unknown key 'sample'; expected one of "
                                                      r"\['connector', 'action', 'samples'",
           "planner.neuralparker_footprint.samples=-1": r"NeuralParkerConfig.samples: expected an integer >= 0",
           "planner.neuralparker_footprint.samples=2.5": r"NeuralParkerConfig.samples: expected an integer, got 2.5",
           "planner.neuralparker_footprint=best": r"expected a preset name, one of \['footprint_anytime', "
                                                  r"'footprint_best_of_n', 'footprint_search', 'paper'\]",
           "clip_run=1": r"ClosedLoopConfig.clip_run: a group of settings; set one of its fields",
           "controller=pid": r"ClosedLoopConfig.controller: expected one of \['lqr', ",
           "clip_run.replan=never": r"ClipRunConfig.replan: expected one of",
           "workers.n=2": r"ClosedLoopConfig.workers: a single setting, it has no field 'n'",
           "samples": r"expected KEY=VALUE"}
    for item, message in bad.items():
        with pytest.raises(ValueError, match=re.escape(f"--set {item}: ")):
            apply_overrides(ClosedLoopConfig(), [item])
        with pytest.raises(ValueError, match=message):
            apply_overrides(ClosedLoopConfig(), [item])


def test_the_difficult_training_clips_run_by_split(tmp_path, monkeypatch, capsys):
    import np_sim.clips as clips_module

    clips, _ = clips_module.generate_split("train", 12)  # the first twelve training clips: two are difficult
    monkeypatch.setattr(clips_module, "difficult_clips",
                        lambda split: [c for c in clips if c.difficulty.difficult] if split == "train" else None)
    out = tmp_path / "run"
    result = main(["--clips", "--split", "train-difficult", "--clips-limit", "1", "--planners", "hybrid_astar",
                   "--no-render", "--out", str(out)])
    config = json.loads((out / "config.json").read_text())
    assert config["config"]["split"] == "train-difficult" and config["clips"] == ["train-0000009"]
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
    result = main(["--clips", "--clip-names", "eval-1000009", "--planners", "hybrid_astar", "--no-render", "--set",
                   "clip_run.stitch=true", "--out", str(out)])
    config = json.loads((out / "config.json").read_text())["config"]
    assert config["clip_run"]["stitch"] is True and config["clip_run"]["stitch_margin_m"] == 0.2
    assert "Stitched replanning (clip_run.stitch)" in result["table"]
    assert result["records"][0]["footprint_success"]


def test_the_notes_name_the_search_stage_and_the_endpoint_limited_clearance():
    from experiments.closed_loop import footprint_notes, planner_notes

    notes = " ".join(footprint_notes(FOOTPRINT_SEARCH))
    assert ("it searches with Hybrid A* for the body grown by 0.2 m (footprint convention, at most 2000 expansions, "
            "steering priced at its drive time; planner.neuralparker_footprint.search_margin_m) and returns that plan "
            "when it passes the same test; otherwise its sampled and rescue rounds run.") in notes
    assert "(The clearance asked of a call's plans is at most its start pose's" in notes
    start_only = dataclasses.replace(FOOTPRINT_SEARCH, start_limited_clearance=True, target_limited_clearance=False)
    both_ends = dataclasses.replace(start_only, target_limited_clearance=True)
    target_only = dataclasses.replace(start_only, start_limited_clearance=False, target_limited_clearance=True)
    assert ("(The clearance asked of a call's plans is at most its start pose's: "
            "planner.neuralparker_footprint.start_limited_clearance.)") in footprint_notes(start_only)
    assert ("(The clearance asked of a call's plans is at most its start pose's and its target pose's: "
            "planner.neuralparker_footprint.start_limited_clearance, "
            "planner.neuralparker_footprint.target_limited_clearance.)") in footprint_notes(both_ends)
    assert ("(The clearance asked of a call's plans is at most its target pose's: "
            "planner.neuralparker_footprint.target_limited_clearance.)") in footprint_notes(target_only)
    assert ("(Its plain mean rollout also ends as a timeout after 50 arcs: planner.neuralparker_footprint.mean_capped.)"
            in notes and "its plain mean rollout at the policy env's budget" not in notes)
    assert "mean_capped" not in " ".join(footprint_notes(FOOTPRINT_ANYTIME))
    assert "steering at 0.1 m;" in " ".join(footprint_notes(dataclasses.replace(FOOTPRINT_SEARCH,
                                                                                search_steer_cost_m=0.1)))
    assert "Hybrid A*" not in " ".join(footprint_notes(FOOTPRINT_ANYTIME))
    both = planner_notes(["neuralparker_footprint", "neuralparker_search"], ClosedLoopConfig())
    assert ("NeuralParker (footprint) + search plays the same policy and stages as NeuralParker (footprint), and "
            "where its mean rollouts are refused") in both
    assert sum("planner.neuralparker_search.search_margin_m" in n for n in both) == 1
    alone = " ".join(planner_notes(["neuralparker_search"], ClosedLoopConfig()))
    assert "NeuralParker (footprint) + search returns its mean rollout" in alone
    assert "neuralparker_footprint" not in alone
