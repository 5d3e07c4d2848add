"""experiments.mean_rollout: its sorting of the mean rollouts agrees with the anytime planner's own decisions."""

import csv
import dataclasses

import pytest

from experiments.closed_loop import SITE_PLANNERS
from experiments.mean_rollout import main
from experiments.plan_time import first_frames
from experiments.registry import build_planners
from np_policy.config import FOOTPRINT_ANYTIME
from np_sim.clips import find_clip
from tracking.clip_run import ClipRunConfig

CLIPS = ["train-0000009", "train-0000010", "train-0000018", "train-0000021", "train-0000024", "train-0000029",
         "train-0000035", "train-0000037", "train-0000039"]
"""The first nine difficult training clips: accepted, close and failed mean rollouts among them."""


def test_accepted_is_exactly_where_the_anytime_planner_answers_with_its_mean_rollout(tmp_path):
    result = main(["--clip-names", *CLIPS, "--out", str(tmp_path / "run")])
    rows = list(csv.DictReader((tmp_path / "run" / "records.csv").open()))
    assert [r["clip"] for r in rows] == CLIPS and sum(result["counts"].values()) == len(CLIPS)
    outcomes = {r["outcome"] for r in rows}
    assert "accepted" in outcomes and outcomes & {"collision", "timeout"} and any("clearance" in o for o in outcomes)
    # the planner itself, with cheap later rounds: whether the mean rollout answers does not depend on them
    options = dataclasses.replace(SITE_PLANNERS, neuralparker_footprint=dataclasses.replace(
        FOOTPRINT_ANYTIME, samples=4, rescue=()))
    planner = build_planners(["neuralparker_footprint"], options)["neuralparker_footprint"]
    frames = first_frames([find_clip(name) for name in CLIPS], ClipRunConfig().track_window)
    for row, (clip, scene, start) in zip(rows, frames):
        assert row["clip"] == clip
        assert (planner.plan(scene, start).stage == "mean") == (row["outcome"] == "accepted"), clip
        level = float(row["clearance_level_m"])
        assert (level >= 0.2) if row["outcome"] == "accepted" else not level >= 0.2
    assert f"| accepted | {result['counts']['accepted']} |" in (tmp_path / "run" / "table.md").read_text()


@pytest.mark.parametrize("argv, message", [
    (["--clips-limit", "0"], "must be a positive integer, got 0"),
    (["--clip-names", "train-x"], "no clip named 'train-x'"),
    (["--clips-limit", "2", "--clip-names", "train-0000009"], "not allowed with argument"),
])
def test_a_users_mistake_is_one_error_line(argv, message, capsys):
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2 and message in capsys.readouterr().err
