"""experiments.plan_time: the first frame of one clip timed with the shipped footprint planner and Hybrid A*."""

import csv

import numpy as np
import pytest

from experiments.plan_time import main
from tracking.clip_run import ClipRunConfig

CLIP = "eval-1000001"
"""The first held-out clip (timed only: nothing is tuned here)."""


def test_first_frames_are_the_closed_loops_first_scene_and_the_table_has_the_ratio_and_stages(tmp_path):
    out = tmp_path / "run"
    result = main(["--clips-limit", "1", "--planners", "neuralparker_footprint", "hybrid_astar",
                   "--set", "planner.neuralparker_footprint=footprint_anytime",
                   "planner.neuralparker_footprint.samples=4", "planner.neuralparker_footprint.rescue=[]",
                   "--out", str(out)])
    rows = list(csv.DictReader((out / "records.csv").open()))
    assert [r["planner"] for r in rows] == ["neuralparker_footprint", "hybrid_astar"]
    assert {r["clip"] for r in rows} == {CLIP} and all(float(r["plan_time_ms"]) > 0 for r in rows)
    assert rows[0]["stage"] in ("mean", "sampled") and rows[1]["stage"] == ""
    table = (out / "table.md").read_text()
    assert "| Hybrid A* |" in table and "| 1.00 | — |" in table
    ratio = float(rows[0]["plan_time_ms"]) / float(rows[1]["plan_time_ms"])
    assert f"| {ratio:.2f} | {rows[0]['stage']} 1 (" in table
    assert result["table"] in (out / "table.md").read_text()


def test_the_scene_timed_is_the_one_the_closed_loop_plans_first():
    from experiments.closed_loop import split_clips
    from experiments.plan_time import first_frames
    from np_sim.planners import HybridAStar
    from tracking.clip_run import ReplanningLoop

    clip = split_clips("eval")[0]
    name, scene, start = first_frames([clip], ClipRunConfig().track_window)[0]
    frame, expected = ReplanningLoop(clip, HybridAStar(), ClipRunConfig()).frame_scene(0.0, start)
    assert (name, frame) == (CLIP, 0) and np.array_equal(start, clip.start)
    assert scene.to_dict() == expected.to_dict()


@pytest.mark.parametrize("argv, message", [
    (["--set", "planner.neuralparker_footprint=fast"], "expected a preset name"),
    (["--clips-limit", "0"], "must be a positive integer, got 0"),
])
def test_a_users_mistake_is_one_error_line(argv, message, capsys):
    with pytest.raises(SystemExit) as stop:
        main(argv)
    assert stop.value.code == 2 and message in capsys.readouterr().err
