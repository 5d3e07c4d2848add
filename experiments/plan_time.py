"""Plan time on the site clips' first frames: every closed-loop planner on the scenes its first call sees.

``python -m experiments.plan_time [--split eval|train-difficult] [--clips-limit N] [--planners NAME ...]
[--set KEY=VALUE ...] [--out DIR]``

For each clip, the scene of the closed loop's first planner call (`tracking.perception.perceived_scene` of frame 0
from the clip start, with the run's tracking window) is planned once by every planner, after one untimed warm-up
call per planner (numba compilation). Prints, per planner, the success rate of those plans and the median and 90th
percentile of ``Plan.plan_time_s``, with the ratio of each median to Hybrid A*'s; a staged-effort planner (the
footprint NeuralParker presets) also shows how many calls each stage answered ('mean': the mean rollout was
accepted; 'sampled'; 'rescue') and the median time of each. Planners and checkpoints are the main job's
(`experiments.closed_loop`); ``--set`` takes the same planner settings, e.g.
``--set planner.neuralparker_footprint=footprint_best_of_n``. Results: ``records.csv`` (one row per clip and
planner), ``records.json`` and ``table.md`` in a fresh ``results/plan_time/<time>/``.

This is a benchmark: run it with nothing else running on the machine, or its times are not figures.
"""

from __future__ import annotations

import argparse
import dataclasses
from collections import Counter
from pathlib import Path
from typing import Any

import numpy as np

from experiments.closed_loop import CLIP_SPLITS, PLANNERS, SITE_PLANNERS, split_clips
from experiments.common import first, run_folder, write_records
from experiments.overrides import apply_overrides
from experiments.registry import PlannerOptions, build_planners, label
from np_sim.cli import cli_boundary, fresh_folder, positive_int
from np_sim.errors import StartInCollisionError
from np_sim.plan import PLAN_STAGES
from tracking.clip_run import ClipRunConfig
from tracking.perception import perceived_scene


@dataclasses.dataclass(frozen=True)
class PlanTimeConfig:
    """What ``experiments.plan_time`` measures (``--set`` reaches every field by its dotted path)."""

    planners: tuple[str, ...] = PLANNERS
    """Planners to time, in table order (the main job's)."""
    split: str = "eval"
    """Clip set (`experiments.closed_loop.CLIP_SPLITS`)."""
    clips_limit: int | None = None
    """Only the first this many clips (None = all)."""
    planner: PlannerOptions = SITE_PLANNERS
    """Checkpoints and presets, the main job's by default."""
    track_window: int = ClipRunConfig().track_window
    """Detections tracked over this many frames, as in the closed loop's first call."""


def first_frames(clips: list, window: int) -> list[tuple[str, Any, np.ndarray]]:
    """(clip name, scene of the first planner call with detections tracked over ``window`` frames, start pose)
    per clip (module docstring)."""
    frames = []
    for clip in clips:
        start = np.asarray(clip.start, float)
        frames.append((clip.name, perceived_scene(clip, 0, pose=start, track_window=window), start))
    return frames


def time_planner(name: str, planner, frames) -> list[dict[str, Any]]:
    """One record per first frame: success, plan time (ms) and stage of ``planner``'s plan."""
    planner.plan(*frames[0][1:])  # warm-up: compilation is not plan time
    rows = []
    for clip, scene, start in frames:
        try:
            plan = planner.plan(scene, start)
            success, reason, ms, stage = plan.success, plan.reason, plan.plan_time_s * 1e3, plan.stage
        except StartInCollisionError as error:
            success, reason, ms, stage = False, f"refused: {error}", float("nan"), ""
        rows.append({"clip": clip, "planner": name, "success": int(success), "reason": reason,
                     "plan_time_ms": ms, "stage": stage})
    return rows


def summary(records: list[dict[str, Any]], names: list[str]) -> str:
    """The markdown table of the module docstring."""
    def times(name, stage=None):
        return np.array([r["plan_time_ms"] for r in records
                         if r["planner"] == name and (stage is None or r["stage"] == stage)])

    base = np.nanmedian(times("hybrid_astar")) if "hybrid_astar" in names else float("nan")
    lines = ["| planner | success | median (ms) | p90 (ms) | median / Hybrid A*'s | stages: calls, median (ms) |",
             "|---|---|---|---|---|---|"]
    for name in names:
        t = times(name)
        success = np.mean([r["success"] for r in records if r["planner"] == name])
        stages = Counter(r["stage"] for r in records if r["planner"] == name)
        split = ", ".join(f"{s} {stages[s]} ({np.nanmedian(times(name, s)):.1f})"
                          for s in PLAN_STAGES if stages[s])
        lines.append(f"| {label(name)} | {success:.2f} | {np.nanmedian(t):.1f} | {np.nanpercentile(t, 90):.1f} | "
                     f"{np.nanmedian(t) / base:.2f} | {split or '—'} |")
    return "\n".join(lines)


def run(config: PlanTimeConfig, out: Path | None = None) -> dict[str, Any]:
    """Time every planner of ``config`` on the first frames; write records and table; return them."""
    frames = first_frames(first(split_clips(config.split), config.clips_limit, "--clips-limit"), config.track_window)
    planners = build_planners(list(config.planners), config.planner)
    records = [row for name, planner in planners.items() for row in time_planner(name, planner, frames)]
    folder = run_folder("plan_time", out)
    write_records(folder, records)
    table = summary(records, list(planners))
    heading = f"Plan time on the first frames of {len(frames)} {config.split} clips (warm, one call each)\n\n"
    (folder / "table.md").write_text(heading + table + "\n")
    return {"folder": folder, "records": records, "table": heading + table}


@cli_boundary
def main(argv=None) -> dict[str, Any]:
    """Command-line entry point (usage in the module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m experiments.plan_time", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--split", choices=CLIP_SPLITS, default="eval", help="clip set (default the held-out 47)")
    parser.add_argument("--clips-limit", type=positive_int, default=None, help="only the first N clips")
    parser.add_argument("--planners", nargs="+", choices=PLANNERS, default=list(PLANNERS),
                        help="planners to time (default the main job's five)")
    parser.add_argument("--out", type=fresh_folder, default=None,
                        help="new or empty run folder (default: a fresh results/plan_time/<time>)")
    parser.add_argument("--set", nargs="+", action="extend", default=[], metavar="KEY=VALUE", dest="overrides",
                        help="planner settings by dotted path, e.g. planner.neuralparker_footprint=footprint_best_of_n")
    args = parser.parse_args(argv)
    config = PlanTimeConfig(planners=tuple(args.planners), split=args.split, clips_limit=args.clips_limit)
    result = run(apply_overrides(config, args.overrides), args.out)
    print(result["table"])
    print(f"\nresults in {result['folder']}/: records.csv, records.json, table.md")
    return result


if __name__ == "__main__":
    main()
