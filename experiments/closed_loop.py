"""The real-vehicle study in closed loop: the 47 held-out site clips driven in MuJoCo by each planner (paper §V-F,
Table ``tab:realworld``, App. C, Fig. ``fig:searchtime``; SPEC §8).

``python -m experiments.closed_loop --clips [--clips-limit N | --clip-names NAME ...] [--planners neuralparker
neuralparker_footprint np_guided_astar hybrid_astar] [--checkpoint PATH] [--footprint-checkpoint PATH] [--no-render]
[--render-clips K] [--out DIR] [--workers N] [--controller lqr] [--connector C] [--footprint-connector C]
[--footprint-samples N] [--footprint-rescue N:SCALE[:FIRST] ...] [--footprint-rescue-clearance M]
[--split eval|train-difficult] [--stitch] [--track-window K] [--search-margin M] [--footprint-margin M]``

For every evaluation clip and planner, `tracking.clip_run.run_clip` starts the MuJoCo vehicle at the clip's start
pose in the clip's ground truth (static objects, moving pedestrians and carts, the site boundary as walls), plans
from frame 0's detections, replans from the simulated pose and the current frame's detections when the followed
plan stops being valid (once per 0.1 s frame at most), tracks the newest plan with the LQR controller and
records both verdicts: **footprint success** (no chassis contact with a ground-truth object or wall, parked within
0.3 m / 10°) and **reference-point success** (parked, the executed reference point never inside a ground-truth
object nor outside the boundary). Planners: NeuralParker (the site checkpoint, paper-faithful reference-point
training), "NeuralParker (footprint)" (``checkpoints/site_np_footprint.pt``, trained under the footprint
convention, playing the best of its mean rollout and ``--footprint-samples`` seeded sampled rollouts,
`np_policy.sampling`, then wider rescue rounds when none succeeds or the best keeps less than 0.2 m of clearance,
the last with first arcs drawn over the whole action box, with the ``centred`` connector order; by default its row
is left out with a note when the file is missing), NP-Guided A* and Hybrid A* (both searching under the footprint
convention).

The table is the ``tab:realworld`` analogue — footprint success with reference-point success in parentheses, L
and reversals executed on each method's own footprint successes, median plan time over all calls — plus
closed-loop columns (failure reasons, final pose error and cross-track error). Writes into the run folder
(default ``results/closed_loop/<timestamp>/``): ``records.csv`` / ``records.json`` (one row per clip × planner),
``table.md``, ``config.json``, ``search_time.png`` and ``closed_loop.rrd`` (every run merged; the per-run files are
in ``rrd/``; off-screen camera frames for the first ``--render-clips`` clips).
"""

from __future__ import annotations

import argparse
import json
import math
import multiprocessing
import shutil
import subprocess
import sys
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from experiments.common import first, git_commit, run_folder, write_records
from np_sim.cli import cli_boundary, fresh_folder, non_negative_float, non_negative_int, positive_int
from np_sim.config import CONNECTOR_VARIANTS
from np_sim.errors import ConfigError

PLANNERS = ("neuralparker", "neuralparker_footprint", "np_guided_astar", "hybrid_astar")
"""Planners of the table, in the paper's row order (the footprint-aware NeuralParker after the paper-faithful one)."""
LABELS = {"neuralparker": "NeuralParker", "neuralparker_footprint": "NeuralParker (footprint)",
          "np_guided_astar": "NP-Guided A*", "hybrid_astar": "Hybrid A*"}
DEFAULT_CHECKPOINT = Path("checkpoints/site_np.pt")
"""The shipped paper-faithful site checkpoint."""
FOOTPRINT_CHECKPOINT = Path("checkpoints/site_np_footprint.pt")
"""The shipped footprint-aware site checkpoint."""
SEARCH_CONVENTION = "footprint"
"""Collision convention of Hybrid A* and of NP-Guided A*'s search (the paper validates with the footprint)."""
FOOTPRINT_SAMPLES = 32
"""Default sampled rollouts of NeuralParker (footprint), set on the first 94 difficult training clips, not on the
held-out ones: executed footprint success 0.59 with none, 0.73 with 16 and 0.81 with 32 (length cost), 0.83 with 32
and the drive-time cost, 0.78 with 64 (SE of 94 clips ≈ 0.04; README, "Best-of-N NeuralParker")."""
FOOTPRINT_CONNECTOR = "centred"
"""NeuralParker (footprint)'s terminal connector: the checkpoint's fixed nine tried target-aligned first
(`np_sim.config.ConnectorConfig.variant`). The paper's order ends plans 10° off the target whenever the 80°
candidate is feasible, on the edge of the 10° parking tolerance: on the held-out clips the tracker then lands a few
tenths of a degree beyond it and replans the same manoeuvre until the time is up (3 clips). Neutral on the 94
training clips (0.82 vs 0.83); README, "Best-of-N NeuralParker"."""
FOOTPRINT_RESCUE: tuple[tuple[int, float, str], ...] = ((128, 2.0, "policy"), (128, 3.0, "policy"),
                                                      (128, 1.0, "uniform"))
"""Default rescue rounds of NeuralParker (footprint) (`PlannerSettings.footprint_rescue`), set on the first 94
difficult training clips: executed footprint success 0.82 without, 0.86 with the two policy rounds (plan_failed
4 → 0) and 0.86 with 256 rollouts per round; with the clearance rescue 0.89, and 0.90 with the third round (first
arc uniform over the action box, then the policy at 1 σ; 0.89 with 64 such rollouts or at 2 σ) (README,
"Best-of-N NeuralParker")."""
FOOTPRINT_RESCUE_CLEARANCE_M = 0.2
"""NeuralParker (footprint)'s rescue rounds also run while its best plan keeps less than this clearance (m; the
ladder's levels are 0.2 / 0.1 / 0 m), set on the first 94 difficult training clips: executed footprint success
0.86 → 0.89 with the default closed loop, 0.90 → 0.93 with --stitch --track-window 5, 0.91 with 0.1 m (README,
"Best-of-N NeuralParker")."""
PAPER = {"neuralparker": "0.60 (0.93) | 7.0 | 1.20 | 0.37", "np_guided_astar": "0.72 | 7.7 | 1.17 | 4.24",
         "hybrid_astar": "0.67 | 7.2 | 1.13 | 5.26"}
"""Table tab:realworld (real vehicle, C++ plan times): succ. | L | Rev. | plan time (ms)."""


@dataclass(frozen=True)
class PlannerSettings:
    """Which checkpoints the planners load and how they plan (the command line's planner options)."""

    checkpoint: Path = DEFAULT_CHECKPOINT
    """Paper-faithful site checkpoint (NeuralParker and NP-Guided A*'s policy stage)."""
    footprint_checkpoint: Path = FOOTPRINT_CHECKPOINT
    """Footprint-aware site checkpoint (NeuralParker (footprint))."""
    search_margin_m: float = 0.0
    """Hybrid A* and NP-Guided A*'s search plan for the footprint grown by this on every side (m)."""
    connector: str | None = None
    """Terminal connector of the paper-faithful NeuralParker (and NP-Guided A*'s policy stage): 'fixed',
    'ensemble' or 'centred' overrides the checkpoint's (`np_sim.config.ConnectorConfig.variant`); None keeps it."""
    footprint_connector: str | None = FOOTPRINT_CONNECTOR
    """The same for NeuralParker (footprint); default 'centred'."""
    footprint_samples: int = FOOTPRINT_SAMPLES
    """NeuralParker (footprint) plays the best of its mean rollout and this many sampled rollouts
    (`np_policy.sampling`); 0 = the paper's mean-action planner."""
    footprint_rescue: tuple[tuple[int, float, str], ...] = FOOTPRINT_RESCUE
    """NeuralParker (footprint)'s wider rounds when no rollout succeeds: (rollouts, standard-deviation scale, first
    arc 'policy' or 'uniform') each, in order (`np_policy.planner.NeuralParkerPlanner`); () = none."""
    footprint_margin_m: float = 0.0
    """NeuralParker (footprint)'s rollouts are checked with the footprint grown by this on every side (m)."""
    footprint_rescue_clearance_m: float = FOOTPRINT_RESCUE_CLEARANCE_M
    """NeuralParker (footprint)'s rescue rounds also run while its chosen plan keeps less clearance than this (m;
    0 = only after a failure)."""


def build_planners(names: list[str], settings: PlannerSettings) -> dict[str, Any]:
    """One planner per name (see `PlannerSettings`); NeuralParker and NP-Guided A* share the paper-faithful site
    policy."""
    unknown = [n for n in names if n not in PLANNERS]
    if unknown:
        raise ConfigError(f"experiments.closed_loop: unknown planner(s) {unknown}; expected some of {list(PLANNERS)}")
    if settings.footprint_samples < 0:
        raise ConfigError(f"--footprint-samples: expected >= 0, got {settings.footprint_samples}")
    from np_sim.planners import HybridAStar, HybridAStarConfig
    from np_sim.vehicle import VehicleSpec

    search = HybridAStarConfig(vehicle=VehicleSpec().inflated(settings.search_margin_m))

    planners: dict[str, Any] = {}
    learned = None
    if {"neuralparker", "np_guided_astar"} & set(names):
        if not Path(settings.checkpoint).exists():
            raise FileNotFoundError(
                f"experiments.closed_loop: the site NeuralParker checkpoint {settings.checkpoint} does not exist; "
                f"pass --checkpoint PATH (a site-configuration checkpoint, e.g. "
                f"checkpoints/runs/site_np_seed0/best.pt) or leave neuralparker and np_guided_astar out of --planners")
        from np_policy.planner import NeuralParkerPlanner

        learned = NeuralParkerPlanner.from_checkpoint(settings.checkpoint, settings.connector, benchmark="site")
    if "neuralparker_footprint" in names and not Path(settings.footprint_checkpoint).exists():
        raise FileNotFoundError(
            f"experiments.closed_loop: the footprint-aware site checkpoint {settings.footprint_checkpoint} does not "
            f"exist; pass --footprint-checkpoint PATH or leave neuralparker_footprint out of --planners")
    for name in names:
        if name == "hybrid_astar":
            planners[name] = HybridAStar(search, convention=SEARCH_CONVENTION)
        elif name == "np_guided_astar":
            from np_policy.staged import NPGuidedAStar

            planners[name] = NPGuidedAStar(learned, HybridAStar(search, convention=SEARCH_CONVENTION))
        elif name == "neuralparker":
            planners[name] = learned
        else:  # neuralparker_footprint
            from np_policy.planner import NeuralParkerPlanner

            planners[name] = NeuralParkerPlanner.from_checkpoint(
                settings.footprint_checkpoint, settings.footprint_connector, samples=settings.footprint_samples,
                rescue=settings.footprint_rescue, margin_m=settings.footprint_margin_m,
                rescue_clearance_m=settings.footprint_rescue_clearance_m, benchmark="site")
    return planners


def clip_rows(clip, planners: dict[str, Any], controller: str, rrd_dir: Path | None, render: bool,
              config=None) -> list[dict]:
    """Run one clip with every planner (``config``: a `tracking.clip_run.ClipRunConfig`, default its defaults);
    one record row per planner."""
    from tracking.clip_run import clip_world, object_of_geom, run_clip

    ground = clip_world(clip)
    rows = []
    for name, planner in planners.items():
        rrd = None if rrd_dir is None else rrd_path(rrd_dir, clip.name, name)
        run = run_clip(clip, planner, controller, config=config, rerun_path=rrd,
                       render=render)
        rec, first = run.record, run.first_plan
        times = np.array([c.plan_time_s for c in run.calls]) * 1e3
        L, rev, _ = first.metrics() if first.success else (math.nan, -1, math.nan)
        row = {"clip": clip.name, "difficulty": "+".join(clip.difficulty.reasons), "planner": name,
               "footprint_success": int(run.footprint_success),
               "reference_point_success": int(run.reference_point_success), "parked": int(run.parked),
               "reference_point_detail": run.reference_point_detail,
               "first_contact_object": object_of_geom(clip, ground, rec.contacts[0].geom) if rec.contacts else "",
               "plan_calls": len(run.calls), "plan_failures": sum(not c.success for c in run.calls),
               "plan_rejected": sum(bool(c.rejected) for c in run.calls),
               "plan_time_median_ms": float(np.median(times)), "plan_time_first_ms": float(times[0]),
               "plan_time_max_ms": float(times.max()), "first_plan_success": int(first.success),
               "first_plan_reason": first.reason, "first_plan_L_m": L, "first_plan_reversals": rev,
               "first_plan_expanded_nodes": first.expanded_nodes,
               "first_plan_footprint_valid": int(run.first_plan_valid["footprint"]),
               "first_plan_reference_point_valid": int(run.first_plan_valid["reference_point"]),
               "first_plan_exact_footprint_valid": int(run.first_plan_valid["exact_footprint"])}
        row.update(rec.to_row())
        rows.append(row)
    return rows


_WORKER: dict[str, Any] = {}
"""Per-process state of the worker pool: clips and planners, built once per process."""


CLIP_SPLITS = ("eval", "train-difficult")
"""Clip sets ``run`` drives: the 47 held-out clips, or the difficult training clips in clip order (where the
footprint-aware planner's settings were tuned; the first 94 are left out of its recorded training resets)."""


def split_clips(split: str) -> list:
    """The clips of ``split`` (``CLIP_SPLITS``)."""
    from np_sim.clips import difficult_clips, load_clips

    if split == "eval":
        return load_clips("eval")
    if split == "train-difficult":
        return difficult_clips("train")
    raise ConfigError(f"--split: expected one of {CLIP_SPLITS}, got {split!r}")


def _init_worker(names: list[str], settings: PlannerSettings, split: str) -> None:
    _WORKER["clips"] = split_clips(split)
    _WORKER["planners"] = build_planners(names, settings)


def _work(args) -> list[dict]:
    index, controller, rrd_dir, render, clip_config = args
    return clip_rows(_WORKER["clips"][index], _WORKER["planners"], controller, rrd_dir, render, clip_config)


def run(planners: list[str] | None = None, settings: PlannerSettings | None = None, clips_limit: int | None = None,
        render_clips: int = 3, render: bool = True, out: Path | None = None, workers: int = 1,
        controller: str = "lqr", rrd: bool = True, progress: bool = True,
        clip_names: list[str] | None = None, replan: str = "on_invalid", track_window: int = 1,
        split: str = "eval", stitch: bool = False) -> dict[str, Any]:
    """Run the clips × planners; returns records, table text, folder and notes (see the module docstring).
    ``split`` picks the clip set (``CLIP_SPLITS``; the held-out clips by default).
    ``planners=None`` runs all of them, leaving out the footprint-aware NeuralParker (with a note) when
    ``settings.footprint_checkpoint`` is missing; a planner named explicitly must have its checkpoint.
    ``track_window`` is the perception filter (off by default, as on the paper's vehicle); ``stitch`` starts the
    replans of a moving vehicle from the pose ahead on its plan where it can still stop (`tracking.stitching`)."""
    from tracking.clip_run import ClipRunConfig

    from tracking.controllers import CONTROLLERS

    if controller not in CONTROLLERS:
        raise ConfigError(f"--controller: expected one of {sorted(CONTROLLERS)}, got {controller!r}")
    if workers < 1:
        raise ConfigError(f"--workers: expected >= 1, got {workers}")
    names = list(PLANNERS if planners is None else planners)
    notes = []
    settings = PlannerSettings() if settings is None else settings
    footprint = Path(settings.footprint_checkpoint)
    if planners is None and not footprint.exists():
        names.remove("neuralparker_footprint")
        notes.append(f"NeuralParker (footprint): {footprint} is missing, row left out.")
    clip_config = ClipRunConfig(replan=replan, track_window=track_window, stitch=stitch)
    if stitch:
        notes.append("Stitched replanning (--stitch): a moving vehicle's replan starts from the pose ahead on its "
                     "followed plan where it can still stop, and it drives that plan up to there.")
    if "neuralparker_footprint" in names and settings.footprint_samples:
        notes.append(f"NeuralParker (footprint) plays the best of its mean rollout and {settings.footprint_samples} "
                     f"sampled rollouts (np_policy.sampling; --footprint-samples 0 = the paper's planner).")
    if "neuralparker_footprint" in names and settings.footprint_rescue:
        from np_policy.planner import rescue_round

        rounds = ", then ".join(f"{n} at {scale:g} σ" + (" after a uniform first arc" if first == "uniform" else "")
                                for n, scale, first in map(rescue_round, settings.footprint_rescue))
        when = (f"none of them succeeds or the best keeps less than {settings.footprint_rescue_clearance_m:g} m "
                f"clearance" if settings.footprint_rescue_clearance_m > 0 else "none of them succeeds")
        notes.append(f"When {when} it samples {rounds} (--footprint-rescue).")
    if "neuralparker_footprint" in names and settings.footprint_connector:
        notes.append(f"NeuralParker (footprint)'s terminal connector: {settings.footprint_connector} "
                     f"(--footprint-connector; centred = the fixed nine candidates, target-aligned first).")
    build_planners(names, settings)  # fail fast on a bad setting, before any work
    clips = split_clips(split)
    if clip_names:
        known = {c.name: k for k, c in enumerate(clips)}
        missing = [n for n in clip_names if n not in known]
        if missing:
            raise ConfigError(f"--clip-names: {missing} are not {split} clips ({clips[0].name} … {clips[-1].name})")
        indices = [known[n] for n in clip_names]
    else:
        indices = first(list(range(len(clips))), clips_limit, "--clips-limit")
    folder = run_folder("closed_loop", out)
    rrd_dir = folder / "rrd" if rrd else None
    jobs = [(k, controller, rrd_dir, render and n < render_clips, clip_config) for n, k in enumerate(indices)]
    wall0 = time.perf_counter()
    bar = tqdm(total=len(jobs) * len(names), desc="clips × planners in MuJoCo", unit="run", disable=not progress)
    results: list[list[dict]] = []
    if workers == 1:
        _init_worker(names, settings, split)
        for job in jobs:
            results.append(_work(job))
            bar.update(len(names))
    else:
        # spawn, not fork: the parent has torch's thread pool up (build_planners above), and a forked child can
        # deadlock on its locks (it did: --workers 2 hung with idle workers)
        with ProcessPoolExecutor(workers, mp_context=multiprocessing.get_context("spawn"), initializer=_init_worker,
                                 initargs=(names, settings, split)) as pool:
            for rows in pool.map(_work, jobs):  # in clip order, so the records do not depend on the workers
                results.append(rows)
                bar.update(len(names))
    bar.close()
    wall = time.perf_counter() - wall0
    records = [row for rows in results for row in rows]
    table = format_table(records, names, split) + "\n\n" + "\n".join(notes)
    write_records(folder, records)
    (folder / "table.md").write_text(table.strip() + "\n")
    figure = search_time_figure(records, folder / "search_time.png")
    written = [] if rrd_dir is None else [rrd_path(rrd_dir, clips[k].name, name) for k in indices for name in names]
    merged = merge_rrd([p for p in written if p.exists()], folder / "closed_loop.rrd")
    (folder / "config.json").write_text(json.dumps({
        "planners": names, "checkpoint": str(settings.checkpoint),
        "footprint_checkpoint": str(footprint) if "neuralparker_footprint" in names else None,
        "footprint_samples": settings.footprint_samples if "neuralparker_footprint" in names else None,
        "footprint_rescue": settings.footprint_rescue if "neuralparker_footprint" in names else None,
        "search_convention": SEARCH_CONVENTION, "split": split, "clips": [clips[k].name for k in indices],
        "controller": controller,
        "render_clips": render_clips if render else 0, "workers": workers, "wall_time_s": wall,
        "search_margin_m": settings.search_margin_m, "connector": settings.connector,
        "footprint_margin_m": settings.footprint_margin_m if "neuralparker_footprint" in names else None,
        "footprint_rescue_clearance_m": (settings.footprint_rescue_clearance_m if "neuralparker_footprint" in names
                                         else None),
        "footprint_connector": settings.footprint_connector if "neuralparker_footprint" in names else None,
        "clip_run": _clip_run_config(clip_config),
        "git_commit": git_commit()},
        indent=2, default=str))
    return {"records": records, "table": table, "folder": folder, "figure": figure, "rrd": merged,
            "wall_time_s": wall}


def _clip_run_config(clip_config) -> dict:
    """The clip-run settings as written into config.json."""
    from dataclasses import asdict

    config = asdict(clip_config)
    return {k: v for k, v in config.items() if k != "tracker"} | {
        "world": config["tracker"]["world"], "executor": config["tracker"]["executor"]}


def _fmt(value: float, digits: int = 2) -> str:
    return "–" if value is None or not math.isfinite(value) else f"{value:.{digits}f}"


def _mean(values) -> float:
    v = np.asarray(list(values), float)
    return float(np.mean(v)) if len(v) else math.nan


def format_table(records: list[dict], names: list[str], split: str = "eval") -> str:
    """Markdown: the tab:realworld analogue, the closed-loop columns and, on the held-out clips the paper's figures
    are for, the paper's real-vehicle figures."""
    n = len({r["clip"] for r in records})
    held_out = split == "eval"
    which = "held-out" if held_out else "difficult training"
    lines = [f"Closed loop on {n} {which} site clips (MuJoCo, LQR tracker, replanning from the simulated pose).", "",
             "| Method | Succ. footprint (ref. point) | First plan valid: footprint / exact | L (m) | Rev. | "
             "Plan time median (ms) | first-frame plan time median (ms) |"
             + (" Paper: Succ. / L / Rev. / ms |" if held_out else ""),
             "|---|---|---|---|---|---|---|" + ("---|" if held_out else "")]
    for name in names:
        rows = [r for r in records if r["planner"] == name]
        ok = [r for r in rows if r["footprint_success"]]
        lines.append(
            f"| {LABELS[name]} | {_mean(r['footprint_success'] for r in rows):.2f} "
            f"({_mean(r['reference_point_success'] for r in rows):.2f}) | "
            f"{_mean(r['first_plan_footprint_valid'] for r in rows):.2f} / "
            f"{_mean(r['first_plan_exact_footprint_valid'] for r in rows):.2f} | "
            f"{_fmt(_mean(r['path_length_m'] for r in ok), 1)} | {_fmt(_mean(r['reversals'] for r in ok))} | "
            f"{_fmt(float(np.median([r['plan_time_median_ms'] for r in rows])))} | "
            f"{_fmt(float(np.median([r['plan_time_first_ms'] for r in rows])))} |"
            + (f" {PAPER.get(name, '–').replace(' | ', ' / ')} |" if held_out else ""))
    lines += ["", "| Method | Failure reasons | Parked | Final error, footprint successes (m / °) | Cross-track RMS / "
              "max (m) | Planner calls / failed / refused per run | Sim / wall time per run (s) |",
              "|---|---|---|---|---|---|---|"]
    for name in names:
        rows = [r for r in records if r["planner"] == name]
        ok = [r for r in rows if r["footprint_success"]]
        ran = [r for r in rows if r["sim_time_s"] > 0]
        reasons = Counter(r["reason"] for r in rows if r["reason"])
        lines.append(
            f"| {LABELS[name]} | {', '.join(f'{k} {v}' for k, v in reasons.most_common()) or '–'} | "
            f"{_mean(r['parked'] for r in rows):.2f} | {_fmt(_mean(r['final_position_error_m'] for r in ok), 3)} / "
            f"{_fmt(_mean(r['final_heading_error_deg'] for r in ok), 1)} | "
            f"{_fmt(_mean(r['cross_track_rms_m'] for r in ran), 3)} / "
            f"{_fmt(_mean(r['cross_track_max_m'] for r in ran), 3)} | "
            f"{_mean(r['plan_calls'] for r in rows):.1f} / {_mean(r['plan_failures'] for r in rows):.1f} / "
            f"{_mean(r['plan_rejected'] for r in rows):.1f} | "
            f"{_mean(r['sim_time_s'] for r in rows):.1f} / {_mean(r['wall_time_s'] for r in rows):.2f} |")
    lines += ["", "Succ.: executed footprint success (no chassis contact with a ground-truth object or wall, parked "
              "within 0.3 m / 10°) on all clips; in parentheses the reference-point success (parked, the executed "
              "reference point never inside a ground-truth object or outside the boundary). First plan valid: the "
              "frame-0 plan against the frame-0 ground truth, footprint at the benchmark's samples / swept exactly. "
              "L and Rev. are executed, "
              "on each method's own footprint successes. Plan times are Python on this machine (paper: C++ on the "
              "vehicle)." + (" Paper column: Table tab:realworld (real-vehicle perception, paths validated in "
                             "simulation)." if held_out else "")]
    return "\n".join(lines)


def search_time_figure(records: list[dict], path: Path) -> Path | None:
    """Fig. fig:searchtime analogue: clips ranked by Hybrid A*'s first-frame plan time, both searches' times."""
    planners = {r["planner"] for r in records}
    if not {"hybrid_astar", "np_guided_astar"} <= planners:
        return None
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    hybrid = {r["clip"]: r["plan_time_first_ms"] for r in records if r["planner"] == "hybrid_astar"}
    guided = {r["clip"]: r["plan_time_first_ms"] for r in records if r["planner"] == "np_guided_astar"}
    order = sorted(hybrid, key=lambda c: (hybrid[c], c))
    fig, ax = plt.subplots(figsize=(7.0, 3.2))
    rank = np.arange(1, len(order) + 1)
    ax.plot(rank, [hybrid[c] for c in order], "o-", ms=3, label="Hybrid A*")
    ax.plot(rank, [guided[c] for c in order], "s-", ms=3, label="NP-Guided A* (rollout + search)")
    ax.set_yscale("log")
    ax.set_xlabel("clip rank by Hybrid A* search time")
    ax.set_ylabel("first-frame plan time (ms)")
    ax.set_title("Search time per clip, from the clip start at frame 0", fontsize=9)
    ax.legend(fontsize=8)
    ax.grid(True, which="both", alpha=0.3)
    fig.tight_layout()
    fig.savefig(path, dpi=150)
    plt.close(fig)
    return path


def rrd_path(rrd_dir: Path, clip_name: str, planner: str) -> Path:
    """The per-run recording of ``planner`` on clip ``clip_name`` in ``rrd_dir``."""
    return rrd_dir / f"{clip_name}_{planner}.rrd"


def merge_rrd(files: list[Path], out: Path) -> Path | None:
    """Merge the given per-run ``.rrd`` files (this run's only) into one file with ``rerun rrd merge``; None when
    there are none."""
    if not files:
        return None
    exe = Path(sys.executable).parent / "rerun"
    exe = str(exe) if exe.exists() else shutil.which("rerun")
    if exe is None:
        raise FileNotFoundError("merge_rrd: the 'rerun' command is missing; install rerun-sdk into the venv")
    subprocess.run([exe, "rrd", "merge", "-o", str(out), *map(str, files)], check=True, capture_output=True)
    return out


def _rescue_text(spec: tuple[int, float, str]) -> str:
    """(N, SCALE, FIRST) → ``N:SCALE[:FIRST]``, the inverse of `_rescue_round`."""
    n, scale, first = spec
    return f"{n}:{scale:g}" + ("" if first == "policy" else f":{first}")


def _rescue_round(text: str) -> tuple[int, float, str]:
    """``N:SCALE[:FIRST]`` → (N, SCALE, FIRST) for --footprint-rescue (FIRST 'policy' when left out)."""
    from np_policy.planner import rescue_round
    from np_policy.sampling import FIRST_ARCS

    parts = text.split(":")
    try:
        return rescue_round((int(parts[0]), float(parts[1]), *parts[2:]))
    except (ValueError, IndexError) as error:
        raise argparse.ArgumentTypeError(f"expected N:SCALE[:FIRST] with N >= 1 rollouts, SCALE > 0 and FIRST one "
                                         f"of {', '.join(FIRST_ARCS)}, got {text!r}") from error


@cli_boundary
def main(argv=None) -> dict[str, Any]:
    """Command-line entry point (usage in the module docstring; ``--help`` lists the options; a user's mistake
    exits 2 with one error line)."""
    from tracking.controllers import CONTROLLERS

    parser = argparse.ArgumentParser(prog="python -m experiments.closed_loop", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--clips", action="store_true", required=True, help="run the 47 held-out site clips")
    parser.add_argument("--split", choices=CLIP_SPLITS, default="eval",
                        help="clip set: the 47 held-out clips (default), or the 304 difficult training clips in "
                             "clip order (the tuning set of the footprint-aware planner: add --clips-limit 94)")
    parser.add_argument("--clips-limit", type=positive_int, default=None, help="only the first N clips")
    parser.add_argument("--clip-names", nargs="+", default=None, help="only these clips (e.g. eval-1000016)")
    parser.add_argument("--planners", nargs="+", choices=PLANNERS, default=None,
                        help="planners to run (default all; neuralparker_footprint is left out with a note when "
                             "its checkpoint is missing)")
    parser.add_argument("--checkpoint", type=Path, default=DEFAULT_CHECKPOINT,
                        help=f"site NeuralParker checkpoint, paper-faithful (default {DEFAULT_CHECKPOINT})")
    parser.add_argument("--footprint-checkpoint", type=Path, default=FOOTPRINT_CHECKPOINT,
                        help=f"footprint-aware site NeuralParker checkpoint (default {FOOTPRINT_CHECKPOINT})")
    parser.add_argument("--no-render", action="store_true", help="no off-screen camera frames in the .rrd")
    parser.add_argument("--render-clips", type=non_negative_int, default=3, help="clips with camera frames (default 3)")
    parser.add_argument("--out", type=fresh_folder, default=None,
                        help="new or empty run folder (default: a fresh results/closed_loop/<time>)")
    parser.add_argument("--workers", type=positive_int, default=1, help="parallel processes (default 1)")
    parser.add_argument("--controller", choices=sorted(CONTROLLERS), default="lqr", help="lateral controller")
    parser.add_argument("--replan", choices=("on_invalid", "every_frame"), default="on_invalid",
                        help="on_invalid (default): every frame, replan only when the followed plan collides with "
                             "that frame's detections or the vehicle is off it; every_frame: replan every frame and "
                             "always follow the newest plan")
    parser.add_argument("--track-window", type=positive_int, default=1,
                        help="filter each object's detections over this many frames before planning (mean shape "
                             "at the latest centroid, dropouts held; default 1 = raw frames, as on the paper's "
                             "vehicle)")
    parser.add_argument("--stitch", action="store_true",
                        help="a replan of a moving vehicle starts from the pose ahead on its followed plan where it "
                             "can still stop (braking distance + one frame + 0.2 m), and the vehicle drives the "
                             "followed plan up to there (trajectory stitching; default: from the simulated pose)")
    parser.add_argument("--footprint-margin", type=non_negative_float, default=0.0, metavar="M",
                        help="NeuralParker (footprint)'s rollouts are checked with the footprint grown by M metres "
                             "on every side (default 0)")
    parser.add_argument("--footprint-rescue-clearance", type=non_negative_float, default=FOOTPRINT_RESCUE_CLEARANCE_M,
                        metavar="M",
                        help="NeuralParker (footprint): run the rescue rounds also when the best plan keeps less "
                             "than M metres of clearance (levels 0.2 / 0.1 / 0 m; default "
                             f"{FOOTPRINT_RESCUE_CLEARANCE_M:g}; 0: only when no rollout succeeds)")
    parser.add_argument("--search-margin", type=non_negative_float, default=0.0, metavar="M",
                        help="Hybrid A* and NP-Guided A*'s search plan for the footprint grown by M metres on every "
                             "side (default 0)")
    parser.add_argument("--connector", choices=CONNECTOR_VARIANTS, default=None,
                        help="NeuralParker's terminal connector (default: the checkpoint's, the site's fixed nine "
                             "candidates; ensemble = the paper's 81-candidate ensemble, an evaluation-only swap; "
                             "centred = the fixed nine tried target-aligned first)")
    parser.add_argument("--footprint-connector", choices=CONNECTOR_VARIANTS, default=FOOTPRINT_CONNECTOR,
                        help=f"the same for NeuralParker (footprint) (default {FOOTPRINT_CONNECTOR}: its plans end on "
                             f"the target heading whenever that candidate is feasible, not 10° off it at the edge of "
                             f"the parking tolerance)")
    parser.add_argument("--footprint-samples", type=non_negative_int, default=FOOTPRINT_SAMPLES, metavar="N",
                        help=f"NeuralParker (footprint) plays the best of its mean rollout and N seeded sampled "
                             f"rollouts, chosen by steerability, then drive time + clearance + reversal + "
                             f"terminal-heading cost (default {FOOTPRINT_SAMPLES}; 0 = the paper's mean-action "
                             f"planner)")
    parser.add_argument("--footprint-rescue", type=_rescue_round, nargs="*", default=list(FOOTPRINT_RESCUE),
                        metavar="N:SCALE[:FIRST]",
                        help="NeuralParker (footprint): when none of its rollouts succeeds (or the best keeps too "
                             "little clearance), sample N more with the policy's standard deviation times SCALE, "
                             "round after round until one succeeds; FIRST = uniform draws each rollout's first arc "
                             "uniformly over the action box (default policy) (default "
                             f"{' '.join(_rescue_text(spec) for spec in FOOTPRINT_RESCUE) or 'none'}; "
                             "give no value for none)")
    args = parser.parse_args(argv)
    settings = PlannerSettings(checkpoint=args.checkpoint, footprint_checkpoint=args.footprint_checkpoint,
                               search_margin_m=args.search_margin, connector=args.connector,
                               footprint_connector=args.footprint_connector, footprint_samples=args.footprint_samples,
                               footprint_rescue=tuple(args.footprint_rescue),
                               footprint_margin_m=args.footprint_margin,
                               footprint_rescue_clearance_m=args.footprint_rescue_clearance)
    result = run(args.planners, settings, args.clips_limit, args.render_clips, not args.no_render, args.out,
                 args.workers, args.controller, clip_names=args.clip_names, replan=args.replan,
                 track_window=args.track_window, split=args.split, stitch=args.stitch)
    folder = result["folder"]
    print(result["table"])
    print(f"\nwall time {result['wall_time_s']:.0f} s; results in {folder}/: records.csv, records.json, table.md, "
          f"config.json" + (", search_time.png" if result["figure"] else ""))
    if result["rrd"] is not None:
        print(f"Rerun recording of every run: {result['rrd']}  (open it with: rerun {result['rrd']})")
    return result


if __name__ == "__main__":
    main()
