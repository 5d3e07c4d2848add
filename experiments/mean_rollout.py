"""How the footprint planner's mean rollout ends on the site clips' first frames, and why it is not accepted.

``python -m experiments.mean_rollout [--split train-difficult|eval] [--clips-limit N | --clip-names NAME ...]
[--checkpoint PATH] [--out DIR]``

The footprint NeuralParker answers a call at the cost of one rollout only when the policy's mean rollout succeeds,
passes the plan validation, is steerable and keeps the anytime test's clearance (`np_policy.planner`,
``accept_mean_m``; with ``mean_margin_m``, the mean rollout of the grown body first, then the plain one); every
other call pays the sampled and rescue rounds. This script plays only those mean rollouts
on the scene of each clip's first planner call (`experiments.plan_time.first_frames`, the main job's tracking
window) and sorts the outcomes: 'accepted' (success with at least ``accept_mean_m`` of clearance on the choice's
ladder, steerable), 'success, clearance <level> m' (below it; −1: not even the plain footprint at the finer
samples), 'success, unsteerable', or the failure reason ('collision', 'timeout', 'validation: …'). The accepted
count is the count of calls the anytime planner answers with its mean rollout on the same frames. It is the
measure to move for the planner's plan-time goal; tune with ``--split train-difficult`` (the default) only.
``--clip-names`` plays the named clips instead (``train-<seed>`` or an eval clip's name, `np_sim.clips.find_clip`),
without generating the whole training split first (a few minutes).
Results: ``records.csv`` / ``records.json`` (one row per clip) and ``table.md`` in a fresh
``results/mean_rollout/<time>/``.
"""

from __future__ import annotations

import argparse
import dataclasses
from collections import Counter
from pathlib import Path
from typing import Any

from experiments.closed_loop import CLIP_SPLITS, SITE_PLANNERS, split_clips
from experiments.common import first, run_folder, write_records
from experiments.plan_time import first_frames
from experiments.registry import build_planners
from np_policy.sampling import clearance_level, steerable
from np_sim.clips import find_clip
from np_sim.cli import cli_boundary, fresh_folder, positive_int
from np_sim.errors import StartInCollisionError
from tracking.clip_run import ClipRunConfig


def outcome(planner, scene, start) -> tuple[str, float]:
    """(category of the module docstring, clearance level in m or nan) of ``planner``'s mean rollout, validated
    and tested for acceptance by the planner's own ``claimed`` and ``accepted``."""
    grown, answered = planner.grown_answer(scene, start)  # with mean_margin_m, tried before the plain one
    plan = grown if answered else planner.claimed(scene, planner.mean(scene, start)[0])
    if not plan.success:
        return plan.reason, float("nan")
    weights = planner.config.weights
    rows = plan.sample(weights.sample_ds_m)
    level = clearance_level(scene, rows[:, :3], planner.body, weights.margins_m)
    if planner.accepted(scene, plan):
        return "accepted", level
    if not steerable(rows, planner.body, weights):
        return "success, unsteerable", level
    return f"success, clearance {level:g} m", level


def run(clips: list, label: str, checkpoint: Path | None, out: Path | None) -> dict[str, Any]:
    """Sort the mean rollouts of the first frames of ``clips`` (module docstring; ``label`` names them in the
    table); write records and table; return them."""
    options = SITE_PLANNERS if checkpoint is None else dataclasses.replace(SITE_PLANNERS,
                                                                           footprint_checkpoint=checkpoint)
    planner = build_planners(["neuralparker_footprint"], options)["neuralparker_footprint"]
    if planner.config.accept_mean_m is None:
        raise ValueError("experiments.mean_rollout: the footprint planner's preset has no anytime test "
                         "(accept_mean_m is None)")
    frames = first_frames(clips, ClipRunConfig().track_window)
    records = []
    for clip, scene, start in frames:
        try:
            category, level = outcome(planner, scene, start)
        except StartInCollisionError as error:
            category, level = f"refused: {error}", float("nan")
        records.append({"clip": clip, "outcome": category, "clearance_level_m": level})
    folder = run_folder("mean_rollout", out)
    write_records(folder, records)
    counts = Counter(r["outcome"] for r in records)
    lines = [f"Mean rollout of the footprint planner on the first frames of {len(records)} {label} clips "
             f"(anytime test: success, steerable, {planner.config.accept_mean_m:g} m of clearance)", "",
             "| outcome | clips |", "|---|---|"]
    lines += [f"| {name} | {n} |" for name, n in sorted(counts.items(), key=lambda kv: (-kv[1], kv[0]))]
    table = "\n".join(lines)
    (folder / "table.md").write_text(table + "\n")
    return {"folder": folder, "records": records, "counts": counts, "table": table}


@cli_boundary
def main(argv=None) -> dict[str, Any]:
    """Command-line entry point (usage in the module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m experiments.mean_rollout", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--split", choices=CLIP_SPLITS, default="train-difficult",
                        help="clip set (default the difficult training clips)")
    which = parser.add_mutually_exclusive_group()
    which.add_argument("--clips-limit", type=positive_int, default=None, help="only the first N clips")
    which.add_argument("--clip-names", nargs="+", default=None, metavar="NAME",
                       help="these clips instead of a split's (train-<seed> or an eval clip's name)")
    parser.add_argument("--checkpoint", type=Path, default=None,
                        help="footprint checkpoint to play (default the main job's, checkpoints/site_np_footprint.pt)")
    parser.add_argument("--out", type=fresh_folder, default=None,
                        help="new or empty run folder (default: a fresh results/mean_rollout/<time>)")
    args = parser.parse_args(argv)
    if args.clip_names:
        clips, label = [find_clip(name) for name in args.clip_names], "named"
    else:
        clips, label = first(split_clips(args.split), args.clips_limit, "--clips-limit"), args.split
    result = run(clips, label, args.checkpoint, args.out)
    print(result["table"])
    print(f"\nresults in {result['folder']}/: records.csv, records.json, table.md")
    return result


if __name__ == "__main__":
    main()
