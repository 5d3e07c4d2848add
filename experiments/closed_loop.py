"""The real-vehicle study in closed loop: the 47 held-out site clips driven in MuJoCo by each planner (paper §V-F,
Table ``tab:realworld``, App. C, Fig. ``fig:searchtime``; spec §8).

``python -m experiments.closed_loop --clips [--split eval|train-difficult] [--clips-limit N | --clip-names NAME ...]
[--planners neuralparker neuralparker_footprint neuralparker_search np_guided_astar hybrid_astar] [--checkpoint PATH]
[--no-render]
[--vehicle sedan|van|FILE] [--workers N] [--out DIR] [--set KEY=VALUE ...]``

For every evaluation clip and planner, `tracking.clip_run.run_clip` starts the MuJoCo vehicle at the clip's start
pose in the clip's ground truth (static objects, moving pedestrians and carts, the site boundary as walls), plans
from frame 0's detections, replans from the simulated pose and the current frame's detections when the followed
plan stops being valid (once per 0.1 s frame at most), tracks the newest plan with the LQR controller and
records both verdicts: **footprint success** (no chassis contact with a ground-truth object or wall, parked within
0.3 m / 10°) and **reference-point success** (parked, the executed reference point never inside a ground-truth
object nor outside the boundary). Planners (`experiments.registry`): NeuralParker (the site checkpoint,
paper-faithful reference-point training, the 'paper' preset), "NeuralParker (footprint)"
(``checkpoints/site_np_footprint.pt``, trained under the footprint convention, the 'footprint_anytime' preset: its
mean rollout when that keeps 0.2 m of clearance, else the best of it and 32 seeded sampled rollouts, then wider
rescue rounds, centred connector order), "NeuralParker (footprint) + search" (the same checkpoint, the
'footprint_search' preset: a learned-first hybrid with a Hybrid A* search for the body grown by 0.2 m between the
mean rollouts and the sampled round; both footprint rows are left out with a note when the file is missing),
NP-Guided A* and Hybrid A* (both searching under the footprint convention). ``--vehicle`` (`np_sim.vehicle`) is
the vehicle planned for and driven (``planner.vehicle`` and ``clip_run.tracker.vehicle``, which must agree): the
searches' footprint and κ_max, the validators, the MuJoCo vehicle; the shipped site checkpoints were trained for the
default car and are refused for another vehicle, so with ``--vehicle van`` run ``--planners hybrid_astar`` or pass
checkpoints trained for it.

Every setting is a field of `ClosedLoopConfig`; the flags set the common ones and ``--set KEY=VALUE`` any other
(`experiments.overrides`), e.g. ``--set clip_run.stitch=true clip_run.track_window=5``, ``--set
planner.search_margin_m=0.15``, ``--set planner.neuralparker.connector=ensemble``, ``--set
planner.neuralparker_footprint.samples=16``, ``--set planner.neuralparker_footprint=paper`` (a whole preset),
``--set planner.footprint_checkpoint=PATH``, ``--set controller=stanley render_clips=5``.

The table is the ``tab:realworld`` analogue — footprint success with reference-point success in parentheses, L
and reversals executed on each method's own footprint successes, median plan time over all calls — plus
every call's plan time (median, 90th percentile) with the stage that answered it, and closed-loop columns (failure
reasons, final pose error and cross-track error). Writes into the run folder
(default ``results/closed_loop/<timestamp>/``): ``records.csv`` / ``records.json`` (one row per clip × planner),
``table.md``, ``config.json`` (the resolved `ClosedLoopConfig`, the clips, the git commit), ``search_time.png`` and
``closed_loop.rrd`` (every run merged; the per-run files are in ``rrd/``; off-screen camera frames for the first
``render_clips`` clips).
"""

from __future__ import annotations

import argparse
import dataclasses
import json
import math
import multiprocessing
import os
import time
from collections import Counter
from concurrent.futures import ProcessPoolExecutor
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from experiments.common import first, run_folder, write_records
from experiments.overrides import apply_overrides
from experiments.registry import PlannerOptions, build_planners, check_names, label
from np_policy.config import NeuralParkerConfig
from np_sim.cli import cli_boundary, fresh_folder, positive_int, vehicle_spec
from np_sim.errors import ConfigError
from np_sim.plan import PLAN_STAGES
from np_sim.provenance import provenance
from tracking.clip_run import ClipRunConfig
from tracking.rerun_log import merge_recordings

PLANNERS = ("neuralparker", "neuralparker_footprint", "neuralparker_search", "np_guided_astar", "hybrid_astar")
"""Planners of the table, in the paper's row order (the footprint-aware NeuralParker and its learned-first hybrid with
a search after the paper-faithful one)."""
FOOTPRINT_ROWS = ("neuralparker_footprint", "neuralparker_search")
"""The rows that play the footprint-aware checkpoint (``PlannerOptions.footprint_checkpoint``)."""
PAPER = {"neuralparker": "0.60 (0.93) | 7.0 | 1.20 | 0.37", "np_guided_astar": "0.72 | 7.7 | 1.17 | 4.24",
         "hybrid_astar": "0.67 | 7.2 | 1.13 | 5.26"}
"""Table tab:realworld (real vehicle, C++ plan times): succ. | L | Rev. | plan time (ms)."""
CLIP_SPLITS = ("eval", "train-difficult")
"""Clip sets ``run`` drives: the 47 held-out clips, or the difficult training clips in clip order (where the
footprint-aware planner's settings were tuned; the first 94 are left out of its recorded training resets)."""
SITE_PLANNERS = PlannerOptions(checkpoint=Path("checkpoints/site_np.pt"),
                               footprint_checkpoint=Path("checkpoints/site_np_footprint.pt"), convention="footprint",
                               benchmark="site")
"""The shipped site checkpoints (paper-faithful, footprint-aware), the presets 'paper', 'footprint_anytime' and
'footprint_search', both searches under the footprint convention (the paper validates with the footprint)."""


@dataclass(frozen=True)
class ClosedLoopConfig:
    """Everything a closed-loop run depends on (written to its ``config.json``)."""

    planners: tuple[str, ...] | None = None
    """Planners to run, in table order; None = all of ``PLANNERS``, leaving out the two footprint rows (with a note)
    when their checkpoint is missing (a planner named explicitly must have its checkpoint)."""
    split: str = "eval"
    """Clip set, ``CLIP_SPLITS``: the held-out clips or the difficult training clips."""
    clips_limit: int | None = None
    """Only the first this many clips of the split (None = all)."""
    clip_names: tuple[str, ...] = ()
    """Only these clips of the split, in this order (empty = ``clips_limit``)."""
    controller: str = "lqr"
    """Lateral controller (`tracking.controllers.CONTROLLERS`)."""
    render_clips: int = 3
    """Clips (the first ones) whose recordings get off-screen camera frames."""
    workers: int | None = None
    """Parallel processes, None = one per core this process may use (`default_workers`), never more than the
    clips. The records do not depend on it."""
    planner: PlannerOptions = SITE_PLANNERS
    """Checkpoints, NeuralParker presets and the searches' convention and margin (`experiments.registry`)."""
    clip_run: ClipRunConfig = field(default_factory=ClipRunConfig)
    """Replanning, perception filter, stitching and tracker settings (`tracking.clip_run.ClipRunConfig`)."""

    def __post_init__(self) -> None:
        if self.planners is not None:
            object.__setattr__(self, "planners", tuple(check_names(self.planners, PLANNERS)))
        if self.split not in CLIP_SPLITS:
            raise ConfigError(f"ClosedLoopConfig.split: expected one of {CLIP_SPLITS}, got {self.split!r}")
        for name, least in (("clips_limit", 1), ("render_clips", 0), ("workers", 1)):
            value = getattr(self, name)
            if value is not None and value < least:
                raise ConfigError(f"ClosedLoopConfig.{name}: expected >= {least}, got {value!r}")
        from tracking.controllers import CONTROLLERS

        if self.controller not in CONTROLLERS:
            raise ConfigError(f"ClosedLoopConfig.controller: expected one of {sorted(CONTROLLERS)}, got "
                              f"{self.controller!r}")
        if self.planner.vehicle != self.clip_run.tracker.vehicle:
            raise ConfigError(f"ClosedLoopConfig: planner.vehicle {self.planner.vehicle.describe()} is not "
                              f"clip_run.tracker.vehicle {self.clip_run.tracker.vehicle.describe()}; the vehicle "
                              "planned for must be the one driven (--vehicle sets both)")


def for_vehicle(config: ClosedLoopConfig, vehicle) -> ClosedLoopConfig:
    """``config`` planning for and driving ``vehicle`` (a `np_sim.vehicle.VehicleSpec`)."""
    tracker = dataclasses.replace(config.clip_run.tracker, vehicle=vehicle)
    return dataclasses.replace(config, planner=dataclasses.replace(config.planner, vehicle=vehicle),
                               clip_run=dataclasses.replace(config.clip_run, tracker=tracker))


def planner_names(config: ClosedLoopConfig) -> tuple[list[str], list[str]]:
    """The planners ``config`` runs and the notes on the ones left out (see ``ClosedLoopConfig.planners``)."""
    if config.planners is not None:
        return list(config.planners), []
    footprint = config.planner.footprint_checkpoint
    if footprint is None or not Path(footprint).exists():
        return [n for n in PLANNERS if n not in FOOTPRINT_ROWS], [
            f"{label(n)}: {footprint} is missing, row left out." for n in FOOTPRINT_ROWS]
    return list(PLANNERS), []


def disturbed(config, disturbance=None):
    """The `tracking.clip_run.ClipRunConfig` ``config`` with the physical factors of ``disturbance`` (None: none)
    applied to its tracker (`tracking.disturbance.Disturbance.tracker`)."""
    return config if disturbance is None else dataclasses.replace(config, tracker=disturbance.tracker(config.tracker))


def clip_rows(clip, planners: dict[str, Any], controller: str, rrd_dir: Path | None, render: bool,
              config=None, disturbance=None) -> list[dict]:
    """Run one clip with every planner (``config``: a `tracking.clip_run.ClipRunConfig`, default its defaults;
    ``disturbance``: None or a `tracking.disturbance.Disturbance`, its physical factors applied to
    ``config.tracker``); one record row per planner."""
    from tracking.clip_run import clip_mujoco_world, clip_world, object_of_geom, run_clip

    config = disturbed(ClipRunConfig() if config is None else config, disturbance)
    ground = clip_world(clip)
    world = clip_mujoco_world(clip, config.tracker, ground)  # compiled once, reset by each run
    rows = []
    for name, planner in planners.items():
        rrd = None if rrd_dir is None else rrd_path(rrd_dir, clip.name, name)
        run = run_clip(clip, planner, controller, config=config, rerun_path=rrd, render=render, world=world,
                       disturbance=disturbance)
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
               "plan_time_max_ms": float(times.max()), "plan_times_ms": [round(float(t), 3) for t in times],
               "plan_stages": [c.stage for c in run.calls], "first_plan_success": int(first.success),
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


def split_clips(split: str) -> list:
    """The clips of ``split`` (``CLIP_SPLITS``)."""
    from np_sim.clips import difficult_clips, load_clips

    if split == "eval":
        return load_clips("eval")
    if split == "train-difficult":
        return difficult_clips("train")
    raise ConfigError(f"--split: expected one of {CLIP_SPLITS}, got {split!r}")


def default_workers() -> int:
    """One worker per CPU core this process may run on."""
    return len(os.sched_getaffinity(0))


def _init_worker(names: list[str], options: PlannerOptions, split: str) -> None:
    # one thread each for torch, numba's parallel loops and Mesa's software renderer: the pool already has a
    # process per core, and more threads than cores only wait on each other
    from np_policy.threads import use_threads

    os.environ["LP_NUM_THREADS"] = "1"  # read when the first off-screen GL context is made, after this
    use_threads(1)
    _WORKER["clips"] = split_clips(split)
    _WORKER["planners"] = build_planners(names, options)


def _work(args) -> list[dict]:
    index, controller, rrd_dir, render, clip_config = args
    return clip_rows(_WORKER["clips"][index], _WORKER["planners"], controller, rrd_dir, render, clip_config)


def planner_notes(names: list[str], config: ClosedLoopConfig) -> list[str]:
    """The table's notes on the run's settings beyond the paper's (stitching, the footprint rows' presets)."""
    notes = []
    if config.clip_run.stitch:
        notes.append("Stitched replanning (clip_run.stitch): a moving vehicle's replan starts from the pose ahead on "
                     "its followed plan where it can still stop, and it drives that plan up to there.")
    if "neuralparker_footprint" in names:
        notes += footprint_notes(config.planner.neuralparker_footprint)
    if "neuralparker_search" in names:
        search, footprint = config.planner.neuralparker_search, config.planner.neuralparker_footprint
        if "neuralparker_footprint" in names and dataclasses.replace(search, **{
                f: getattr(footprint, f) for f in SEARCH_FIELDS}) == footprint:
            notes += [f"{label('neuralparker_search')} plays the same policy and stages as NeuralParker "
                      f"(footprint), and where its mean rollouts are refused", *search_notes(search)]
        else:
            notes += footprint_notes(search, "neuralparker_search")
    return notes


SEARCH_FIELDS = ("search_margin_m", "search_max_expanded", "search_steer_cost_m", "start_limited_clearance",
                 "target_limited_clearance", "mean_capped")
"""The `NeuralParkerConfig` fields in which the search row's preset differs from the learned row's: the search
stage, the clearance caps and the capped plain mean rollout."""


def search_notes(config: NeuralParkerConfig, row: str = "neuralparker_search") -> list[str]:
    """The notes on the search stage of the footprint row ``row`` playing ``config`` (none without one)."""
    notes = []
    if config.search_margin_m is not None:
        steer = ("priced at its drive time" if config.search_steer_cost_m is None
                 else f"at {config.search_steer_cost_m:g} m")
        notes.append(f"it searches with Hybrid A* for the body grown by {config.search_margin_m:g} m (footprint "
                     f"convention, at most {config.search_max_expanded} expansions, steering {steer}; "
                     f"planner.{row}.search_margin_m) and returns that plan when it passes the same test; otherwise "
                     f"its sampled and rescue rounds run.")
    ends = [end for end, on in (("start", config.start_limited_clearance),
                                ("target", config.target_limited_clearance)) if on]
    if ends:
        poses = " and its ".join(f"{end} pose's" for end in ends)
        keys = ", ".join(f"planner.{row}.{end}_limited_clearance" for end in ends)
        notes.append(f"(The clearance asked of a call's plans is at most its {poses}: {keys}.)")
    if config.mean_capped:
        notes.append(f"(Its plain mean rollout also ends as a timeout after {config.rollout_max_arcs} arcs: "
                     f"planner.{row}.mean_capped.)")
    return notes


def footprint_notes(footprint: NeuralParkerConfig, row: str = "neuralparker_footprint") -> list[str]:
    """The table's notes on how the footprint row ``row`` plays its policy (its `NeuralParkerConfig`)."""
    notes, name, key = [], label(row), f"planner.{row}"
    if footprint.accept_mean_m is not None:
        grown = (f", played first with the body grown by {footprint.mean_margin_m:g} m, then as is "
                 f"({key}.mean_margin_m)" if footprint.mean_margin_m else "")
        guarded = (f" (before the plain one, the guarded mean rollout: each arc the first of the mean action and "
                   f"offsets at {', '.join(f'{s:g}' for s in footprint.guard_sigmas)} σ that parks aligned, else does "
                   f"not collide; {key}.guard_sigmas)" if footprint.guard_sigmas else "")
        aligned = (f" and ends within {footprint.weights.heading_slack_deg:g}° of the target's heading "
                   f"({key}.accept_aligned)" if footprint.accept_aligned else "")
        notes.append(f"{name} returns its mean rollout{grown}{guarded}{',' if grown else ''} at once "
                     f"when that succeeds, is steerable and keeps {footprint.accept_mean_m:g} m of clearance "
                     f"({key}.accept_mean_m){aligned}; otherwise:")
        notes += search_notes(footprint, row)
    if footprint.samples:
        notes.append(f"{name} plays the best of its mean rollout and {footprint.samples} sampled "
                     f"rollouts (np_policy.sampling; {key}.samples=0 = the paper's planner).")
    if footprint.rescue:
        rounds = ", then ".join(f"{n} at {scale:g} σ" + (" after a uniform first arc" if first == "uniform" else "")
                                for n, scale, first in footprint.rescue)
        when = (f"none of them succeeds or the best keeps less than {footprint.rescue_clearance_m:g} m clearance"
                if footprint.rescue_clearance_m > 0 else "none of them succeeds")
        notes.append(f"When {when} it samples {rounds} ({key}.rescue).")
        if footprint.rescue_stop_m is not None and len(footprint.rescue) > 1:
            keeps = f" and keeps {footprint.rescue_stop_m:g} m clearance" if footprint.rescue_stop_m > 0 else ""
            notes.append(f"After a rescue round the later ones are skipped once the chosen plan succeeds{keeps} "
                         f"({key}.rescue_stop_m).")
    if footprint.rollout_max_arcs is not None and (footprint.samples or footprint.rescue):
        grown = ", grown-body mean" if footprint.mean_margin_m else ""
        guarded = ", guarded" if footprint.guard_sigmas else ""
        plain = "" if footprint.mean_capped else ", its plain mean rollout at the policy env's budget"
        notes.append(f"{name}'s sampled{grown}{guarded} and rescue rollouts end as timeouts after "
                     f"{footprint.rollout_max_arcs} arcs{plain} ({key}.rollout_max_arcs).")
    if footprint.connector:
        notes.append(f"{name}'s terminal connector: {footprint.connector} "
                     f"(centred = the fixed nine candidates, target-aligned first).")
    return notes


def clip_indices(clips: list, config: ClosedLoopConfig) -> list[int]:
    """Indices of the clips ``config`` names (``clip_names``, else the first ``clips_limit``)."""
    if not config.clip_names:
        return first(list(range(len(clips))), config.clips_limit, "--clips-limit")
    known = {c.name: k for k, c in enumerate(clips)}
    missing = [n for n in config.clip_names if n not in known]
    if missing:
        raise ConfigError(f"--clip-names: {missing} are not {config.split} clips ({clips[0].name} … "
                          f"{clips[-1].name})")
    return [known[n] for n in config.clip_names]


def drive(planners: dict[str, Any], config: ClosedLoopConfig, clips: list, indices: list[int], rrd_dir: Path | None,
          progress: bool) -> list[dict]:
    """The record rows of every clip of ``indices`` × planner, in clip order: with one worker on ``planners`` in
    this process, else on ``config.workers`` processes, each building its own planners."""
    names = list(planners)
    jobs = [(k, config.controller, rrd_dir, n < config.render_clips, config.clip_run) for n, k in enumerate(indices)]
    bar = tqdm(total=len(jobs) * len(names), desc="clips × planners in MuJoCo", unit="run", disable=not progress)
    results: list[list[dict]] = []
    if config.workers == 1:
        from np_policy.threads import threads

        with threads(1):  # torch and numba on one thread as in a pool worker: plan times do not depend on the count
            for k, *settings in jobs:
                results.append(clip_rows(clips[k], planners, *settings))
                bar.update(len(names))
    else:
        # spawn, not fork: the parent has torch's thread pool up (build_planners), and a forked child can deadlock
        # on its locks (it did: two workers hung idle)
        with ProcessPoolExecutor(config.workers, mp_context=multiprocessing.get_context("spawn"),
                                 initializer=_init_worker, initargs=(names, config.planner, config.split)) as pool:
            for rows in pool.map(_work, jobs):  # in clip order, so the records do not depend on the workers
                results.append(rows)
                bar.update(len(names))
    bar.close()
    return [row for rows in results for row in rows]


def run(config: ClosedLoopConfig | None = None, out: Path | None = None, rrd: bool = True,
        progress: bool = True) -> dict[str, Any]:
    """Run the clips × planners of ``config``; returns records, table text, folder, figure, merged recording, the
    config it ran with (``workers`` resolved), the clips' wall time and the wall time of each phase (set-up: the
    planners and clips; drive: the clips; outputs: the files and the merged recording)."""
    start = time.perf_counter()
    config = ClosedLoopConfig() if config is None else config
    names, notes = planner_names(config)
    notes += planner_notes(names, config)
    planners = build_planners(names, config.planner)  # fails fast on a bad setting, before any work
    clips = split_clips(config.split)
    indices = clip_indices(clips, config)
    # the count it ran with, in config.json too
    config = dataclasses.replace(config, workers=min(config.workers or default_workers(), len(indices)))
    folder = run_folder("closed_loop", out)
    rrd_dir = folder / "rrd" if rrd else None
    wall0 = time.perf_counter()
    records = drive(planners, config, clips, indices, rrd_dir, progress)
    wall = time.perf_counter() - wall0
    table = format_table(records, names, config.split) + "\n\n" + "\n".join(notes)
    write_records(folder, records)
    (folder / "table.md").write_text(table.strip() + "\n")
    figure = search_time_figure(records, folder / "search_time.png")
    written = [] if rrd_dir is None else [rrd_path(rrd_dir, clips[k].name, name) for k in indices for name in names]
    merged = merge_rrd([p for p in written if p.exists()], folder / "closed_loop.rrd")
    phases = {"setup": wall0 - start, "drive": wall, "outputs": time.perf_counter() - wall0 - wall}
    (folder / "config.json").write_text(json.dumps(
        {"config": dataclasses.asdict(config), "planners": names, "clips": [clips[k].name for k in indices],
         "wall_time_s": wall, "phase_times_s": phases, **provenance()}, indent=2, default=str))
    return {"records": records, "table": table, "folder": folder, "figure": figure, "rrd": merged,
            "wall_time_s": wall, "phase_times_s": phases, "config": config}


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
            f"| {label(name)} | {_mean(r['footprint_success'] for r in rows):.2f} "
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
            f"| {label(name)} | {', '.join(f'{k} {v}' for k, v in reasons.most_common()) or '–'} | "
            f"{_mean(r['parked'] for r in rows):.2f} | {_fmt(_mean(r['final_position_error_m'] for r in ok), 3)} / "
            f"{_fmt(_mean(r['final_heading_error_deg'] for r in ok), 1)} | "
            f"{_fmt(_mean(r['cross_track_rms_m'] for r in ran), 3)} / "
            f"{_fmt(_mean(r['cross_track_max_m'] for r in ran), 3)} | "
            f"{_mean(r['plan_calls'] for r in rows):.1f} / {_mean(r['plan_failures'] for r in rows):.1f} / "
            f"{_mean(r['plan_rejected'] for r in rows):.1f} | "
            f"{_mean(r['sim_time_s'] for r in rows):.1f} / {_mean(r['wall_time_s'] for r in rows):.2f} |")
    lines += ["", *call_table(records, names)]
    lines += ["", "Succ.: executed footprint success (no chassis contact with a ground-truth object or wall, parked "
              "within 0.3 m / 10°) on all clips; in parentheses the reference-point success (parked, the executed "
              "reference point never inside a ground-truth object or outside the boundary). First plan valid: the "
              "frame-0 plan against the frame-0 ground truth, footprint at the benchmark's samples / swept exactly. "
              "L and Rev. are executed, "
              "on each method's own footprint successes. Plan times are Python on this machine (paper: C++ on the "
              "vehicle)." + (" Paper column: Table tab:realworld (real-vehicle perception, paths validated in "
                             "simulation)." if held_out else "")]
    return "\n".join(lines)


def call_table(records: list[dict], names: list[str]) -> list[str]:
    """Markdown lines: per method, every planner call's plan time (median, 90th percentile) and, for a
    staged-effort planner, how many calls each stage answered and their median time."""
    lines = ["| Method | Planner calls | Plan time, all calls: median / p90 (ms) | Calls answered by the mean "
             "rollout / the guarded rollout / the search / the sampled round / the rescue rounds (median ms) |",
             "|---|---|---|---|"]
    for name in names:
        rows = [r for r in records if r["planner"] == name]
        times = np.array([t for r in rows for t in r["plan_times_ms"]])
        stages = np.array([s for r in rows for s in r["plan_stages"]])
        split = " / ".join(f"{np.sum(stages == s)} ({_fmt(float(np.median(times[stages == s])), 1)})"
                           if np.any(stages == s) else "0" for s in PLAN_STAGES)
        lines.append(f"| {label(name)} | {len(times)} | {_fmt(float(np.median(times)), 1)} / "
                     f"{_fmt(float(np.percentile(times, 90)), 1)} | {split if np.any(stages != '') else '–'} |")
    return lines


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
    """Merge the given per-run ``.rrd`` files (this run's only) into one optimised file with the viewer layout
    (`tracking.rerun_log.merge_recordings`); None when there are none."""
    return merge_recordings(files, out) if files else None


@cli_boundary
def main(argv=None) -> dict[str, Any]:
    """Command-line entry point (usage in the module docstring; ``--help`` lists the options; a user's mistake
    exits 2 with one error line)."""
    parser = argparse.ArgumentParser(prog="python -m experiments.closed_loop", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--clips", action="store_true", required=True, help="run the site clips")
    parser.add_argument("--split", choices=CLIP_SPLITS, default="eval",
                        help="clip set: the 47 held-out clips (default), or the 304 difficult training clips in "
                             "clip order (the tuning set of the footprint-aware planner: add --clips-limit 94)")
    parser.add_argument("--clips-limit", type=positive_int, default=None, help="only the first N clips")
    parser.add_argument("--clip-names", nargs="+", default=(), help="only these clips (e.g. eval-1000016)")
    parser.add_argument("--planners", nargs="+", choices=PLANNERS, default=None,
                        help="planners to run (default all; neuralparker_footprint and neuralparker_search are left "
                             "out with a note when their checkpoint is missing)")
    parser.add_argument("--checkpoint", type=Path, default=SITE_PLANNERS.checkpoint,
                        help=f"paper-faithful site NeuralParker checkpoint of neuralparker and np_guided_astar "
                             f"(default {SITE_PLANNERS.checkpoint})")
    parser.add_argument("--no-render", action="store_true", help="no off-screen camera frames in the .rrd")
    parser.add_argument("--vehicle", type=vehicle_spec, default=None,
                        help="vehicle planned for and driven: a preset (sedan, the default; van) or a vehicle JSON "
                             "file (docs/vehicles.md); the site checkpoints are the sedan's")
    parser.add_argument("--workers", type=positive_int, default=None,
                        help=f"parallel processes (default one per core: {default_workers()} here)")
    parser.add_argument("--out", type=fresh_folder, default=None,
                        help="new or empty run folder (default: a fresh results/closed_loop/<time>)")
    parser.add_argument("--set", nargs="+", action="extend", default=[], metavar="KEY=VALUE", dest="overrides",
                        help="any other setting of ClosedLoopConfig by its dotted field path (module docstring), "
                             "e.g. clip_run.track_window=5 clip_run.stitch=true planner.search_margin_m=0.15 "
                             "planner.neuralparker_footprint.samples=16 planner.neuralparker_footprint=paper")
    args = parser.parse_args(argv)
    config = ClosedLoopConfig(planners=args.planners, split=args.split, clips_limit=args.clips_limit,
                              clip_names=tuple(args.clip_names), workers=args.workers,
                              render_clips=0 if args.no_render else ClosedLoopConfig.render_clips,
                              planner=dataclasses.replace(SITE_PLANNERS, checkpoint=args.checkpoint))
    if args.vehicle is not None:
        config = for_vehicle(config, args.vehicle)
    result = run(apply_overrides(config, args.overrides), args.out)
    folder = result["folder"]
    print(result["table"])
    phases = result["phase_times_s"]
    print(f"\nwall time {sum(phases.values()):.0f} s (set-up {phases['setup']:.0f} s, clips {phases['drive']:.0f} s "
          f"on {result['config'].workers} worker(s), files and recording {phases['outputs']:.0f} s); results in "
          f"{folder}/: records.csv, records.json, table.md, config.json"
          + (", search_time.png" if result["figure"] else ""))
    if result["rrd"] is not None:
        print(f"Rerun recording of every run: {result['rrd']}  (open it with: rerun {result['rrd']})")
    return result


if __name__ == "__main__":
    main()
