"""Closed-loop robustness: the main job's clip runs repeated under one disturbance at a time (beyond the paper;
docs/robustness.md).

``python -m experiments.robustness --clips [--split eval|train-difficult] [--clips-limit N | --clip-names NAME ...]
[--planners ...] [--factors ...] [--levels mild moderate severe] [--seed S] [--workers N] [--ray-address ADDR]
[--out DIR | --resume DIR] [--dry-run] [--no-rrd] [--set KEY=VALUE ...]``

Every clip × planner of the closed-loop study (`experiments.closed_loop`: same planners, clips, tracker and
``--set`` settings) is driven once undisturbed (level 'none') and once per factor of ``--factors`` (default all
eight of `tracking.disturbance.FACTORS`: detection noise and drops, localisation noise with drift, actuation
latency, a slower steering actuator, tyre friction, a payload shifting the centre of mass, a longer body) at each
of ``--levels``. Every planner meets the same draws: a run's random draws are seeded by ``--seed`` and the clip.

Runs are scheduled on Ray as one task per (factor, level, clip) on a pool of actors that each build the planners
once: a local Ray with ``--workers`` actors (default one per core) or the cluster at ``--ray-address`` (one actor
per CPU of it; the project must be installed on every node). ``--workers 1`` without an address runs in this
process, without Ray. Each finished row is appended to ``records.csv`` at once; after a kill, ``--resume DIR``
runs what is missing with the settings stored in ``DIR/config.json``. ``--dry-run`` prints the run count and the
CPU time estimated from the main job's recorded wall times, and runs nothing.

Writes into the run folder (default ``results/robustness/<timestamp>/``): ``records.csv`` (one row per factor ×
level × clip × planner: the closed-loop record columns plus factor, level, level_value, setting, seed),
``table.md``, ``plots/<factor>.png`` (footprint success and contact rate against the level, one line per planner,
95 % Wilson bands), ``config.json`` and ``rrd/`` (the first failing clip of every factor × level × planner, driven
again with a Rerun recording).
"""

from __future__ import annotations

import argparse
import csv
import dataclasses
import gzip
import json
import os
import sys
import time
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from experiments.closed_loop import (CLIP_SPLITS, PLANNERS, SITE_PLANNERS, ClosedLoopConfig, clip_indices, clip_rows,
                                     default_workers, planner_names, split_clips)
from experiments.common import git_commit, run_folder
from experiments.overrides import apply_overrides
from experiments.registry import build_planners
from experiments.robustness_report import factor_figure, format_table
from np_sim.cli import cli_boundary, fresh_folder, non_negative_int, positive_int
from np_sim.errors import ConfigError
from tracking.disturbance import FACTORS, LEVELS, Disturbance

KEY = ("factor", "level", "planner", "clip")
"""The columns that name a run; ``--resume`` skips the keys already in ``records.csv``."""
MAIN_JOB = Path("docs/results/2026-12-02-anytime-main-job/records.csv.gz")
"""The main job's records, whose wall times give ``--dry-run``'s estimate."""
FALLBACK_RUN_S = 2.5
"""CPU seconds per run assumed for a planner the main job's records lack."""


def study_rows(clip, planners: dict[str, Any], factor: str, level: str, seed: int,
               loop: ClosedLoopConfig) -> list[dict]:
    """The record rows of ``clip`` driven by every planner of ``planners`` under ``factor`` at ``level`` ('none':
    undisturbed), each led by the disturbance's columns."""
    disturbance = None if factor == "none" else Disturbance.at(factor, level, seed)
    head = {"factor": factor, "level": level, "level_value": 0.0 if disturbance is None else disturbance.value,
            "setting": "none" if disturbance is None else disturbance.setting, "seed": seed}
    rows = clip_rows(clip, planners, loop.controller, None, False, loop.clip_run, disturbance)
    return [{**head, **row} for row in rows]


def study_jobs(factors, levels, clips: list, indices: list[int], names: list[str],
               done: set[tuple]) -> list[tuple[str, str, int, tuple[str, ...]]]:
    """(factor, level, clip index, planners still to run) of every (factor, level, clip) with a run missing from
    ``done``; the undisturbed level first."""
    cells = [("none", "none")] + [(f, lv) for f in factors for lv in levels]
    jobs = []
    for factor, level in cells:
        for k in indices:
            todo = tuple(n for n in names if (factor, level, n, clips[k].name) not in done)
            if todo:
                jobs.append((factor, level, k, todo))
    return jobs


class RecordLog:
    """``records.csv`` of a study, appended one row at a time (flushed), read back on ``--resume``."""

    def __init__(self, path: Path):
        self.path = path
        self.fields: list[str] | None = None
        if path.exists():
            self._drop_torn_rows()

    def _drop_torn_rows(self) -> None:
        """Rewrite the file without a last row a kill cut short (fewer fields than the header)."""
        with self.path.open(newline="") as fh:
            table = list(csv.reader(fh))
        if not table:
            return
        self.fields = table[0]
        whole = [r for r in table[1:] if len(r) == len(self.fields)]
        if len(whole) < len(table) - 1:
            tmp = self.path.with_suffix(".tmp")
            with tmp.open("w", newline="") as fh:
                csv.writer(fh).writerows([self.fields, *whole])
            os.replace(tmp, self.path)

    def rows(self) -> list[dict]:
        """Every row written so far (strings, as read)."""
        if not self.path.exists():
            return []
        with self.path.open(newline="") as fh:
            return list(csv.DictReader(fh))

    def done(self) -> set[tuple]:
        """The ``KEY`` of every row written so far."""
        return {tuple(r[k] for k in KEY) for r in self.rows()}

    def append(self, rows: list[dict]) -> None:
        """Append ``rows`` (the header first when the file is new) and flush them to disk."""
        new = self.fields is None
        self.fields = list(rows[0]) if new else self.fields
        with self.path.open("a", newline="") as fh:
            writer = csv.DictWriter(fh, fieldnames=self.fields)
            if new:
                writer.writeheader()
            writer.writerows(rows)
            fh.flush()
            os.fsync(fh.fileno())


def _quiet_threads() -> None:
    """One thread each for torch and numba in a worker: the pool already has a worker per core."""
    import numba
    import torch

    torch.set_num_threads(1)
    numba.set_num_threads(1)


class StudyWorker:
    """A worker of the study: the clips and the planners, built once, and the runs of one job at a time."""

    def __init__(self, names: list[str], loop: ClosedLoopConfig, seed: int, quiet: bool = True):
        if quiet:
            _quiet_threads()
        self.loop, self.seed = loop, seed
        self.clips = split_clips(loop.split)
        self.planners = build_planners(names, loop.planner)

    def run(self, job: tuple) -> list[dict]:
        """The rows of one (factor, level, clip index, planners) job."""
        factor, level, k, names = job
        return study_rows(self.clips[k], {n: self.planners[n] for n in names}, factor, level, self.seed, self.loop)


def run_jobs(jobs: list[tuple], names: list[str], loop: ClosedLoopConfig, seed: int, log: RecordLog,
             workers: int, address: str | None) -> None:
    """Run ``jobs``, appending each one's rows to ``log`` as it finishes: in this process for one worker without
    an address, else on Ray actors (module docstring)."""
    bar = tqdm(total=sum(len(j[3]) for j in jobs), desc="robustness runs", unit="run")
    if workers == 1 and address is None:
        worker = StudyWorker(names, loop, seed, quiet=False)
        for job in jobs:
            log.append(worker.run(job))
            bar.update(len(job[3]))
        bar.close()
        return
    import ray
    from ray.util import ActorPool

    if address:
        ray.init(address=address, log_to_driver=False)
        workers = int(ray.cluster_resources().get("CPU", 1))
    else:
        ray.init(num_cpus=workers, include_dashboard=False, log_to_driver=False)
    try:
        actor = ray.remote(num_cpus=1)(StudyWorker)
        pool = ActorPool([actor.remote(names, loop, seed) for _ in range(min(workers, len(jobs)))])
        for rows in pool.map_unordered(lambda a, job: a.run.remote(job), jobs):
            log.append(rows)
            bar.update(len(rows))
    finally:
        bar.close()
        ray.shutdown()


def record_failures(rows: list[dict], loop: ClosedLoopConfig, seed: int, folder: Path) -> list[Path]:
    """Drive the first failing clip (in clip order) of every factor × level × planner again with a Rerun
    recording, ``rrd/<factor>_<level>_<planner>_<clip>.rrd`` (kept when it exists: a resumed study)."""
    order = {c.name: k for k, c in enumerate(split_clips(loop.split))}
    firsts: dict[tuple, str] = {}
    for r in sorted(rows, key=lambda r: order[r["clip"]]):
        if not int(r["footprint_success"]):
            firsts.setdefault((r["factor"], r["level"], r["planner"]), r["clip"])
    if not firsts:
        return []
    from tracking.clip_run import run_clip

    clips = split_clips(loop.split)
    planners = build_planners(sorted({p for _, _, p in firsts}), loop.planner)
    written = []
    for (factor, level, planner), clip_name in tqdm(sorted(firsts.items()), desc="recording first failures"):
        path = folder / "rrd" / f"{factor}_{level}_{planner}_{clip_name}.rrd"
        if not path.exists():
            disturbance = None if factor == "none" else Disturbance.at(factor, level, seed)
            config = loop.clip_run if disturbance is None else dataclasses.replace(
                loop.clip_run, tracker=disturbance.tracker(loop.clip_run.tracker))
            path.parent.mkdir(exist_ok=True)
            run_clip(clips[order[clip_name]], planners[planner], loop.controller, config=config, rerun_path=path,
                     disturbance=disturbance)
        written.append(path)
    return written


def run_seconds(names: list[str], records: Path = MAIN_JOB) -> dict[str, float]:
    """Mean CPU seconds of one clip run per planner, from the main job's records (wall time of the drive plus the
    first plan), ``FALLBACK_RUN_S`` for a planner they lack."""
    rows = list(csv.DictReader(gzip.open(records, "rt"))) if records.exists() else []
    out = {}
    for name in names:
        times = [float(r["wall_time_s"]) + float(r["plan_time_first_ms"]) / 1e3 for r in rows if r["planner"] == name]
        out[name] = float(np.mean(times)) if times else FALLBACK_RUN_S
    return out


def dry_run_text(jobs: list[tuple], names: list[str]) -> str:
    """The run count and the estimated CPU time of ``jobs``."""
    seconds = run_seconds(names)
    runs = sum(len(j[3]) for j in jobs)
    cpu = sum(seconds[n] for j in jobs for n in j[3])
    per = ", ".join(f"{n} {seconds[n]:.1f} s" for n in names)
    return (f"{runs} runs ({len(jobs)} factor × level × clip jobs) ≈ {cpu / 3600:.1f} CPU-hours "
            f"(per run: {per}; from {MAIN_JOB}); ≈ {cpu / 3600 / default_workers():.1f} h on the "
            f"{default_workers()} cores here")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m experiments.robustness", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--clips", action="store_true", help="run the site clips (the main job's closed loop)")
    parser.add_argument("--split", choices=CLIP_SPLITS, default="eval", help="clip set (default: the 47 held-out)")
    parser.add_argument("--clips-limit", type=positive_int, default=None, help="only the first N clips")
    parser.add_argument("--clip-names", nargs="+", default=(), help="only these clips (e.g. eval-1000016)")
    parser.add_argument("--planners", nargs="+", choices=PLANNERS, default=None,
                        help="planners (default: the main job's)")
    parser.add_argument("--factors", nargs="+", choices=list(FACTORS), default=list(FACTORS),
                        help="disturbance factors (default all eight)")
    parser.add_argument("--levels", nargs="+", choices=LEVELS, default=list(LEVELS),
                        help="levels beside the undisturbed run (default mild moderate severe)")
    parser.add_argument("--seed", type=non_negative_int, default=0, help="seed of the disturbances' draws")
    parser.add_argument("--workers", type=positive_int, default=None,
                        help=f"local Ray actors (default one per core: {default_workers()} here); 1 = no Ray")
    parser.add_argument("--ray-address", help="join this Ray cluster (default: a local Ray)")
    parser.add_argument("--out", type=fresh_folder, default=None,
                        help="new or empty run folder (default: a fresh results/robustness/<time>)")
    parser.add_argument("--resume", type=Path, default=None, metavar="DIR",
                        help="continue the study in DIR with its stored settings (the other options but "
                             "--workers and --ray-address are ignored)")
    parser.add_argument("--dry-run", action="store_true", help="print the run count and CPU time; run nothing")
    parser.add_argument("--no-rrd", action="store_true", help="no Rerun recordings of the first failures")
    parser.add_argument("--set", nargs="+", action="extend", default=[], metavar="KEY=VALUE", dest="overrides",
                        help="any setting of experiments.closed_loop.ClosedLoopConfig by its dotted path")
    return parser


def _settings(args, argv: list[str]) -> tuple[argparse.Namespace, list[str]]:
    """The study's arguments: ``args`` itself, or those stored in ``--resume``'s folder (its argv)."""
    if args.resume is None:
        if not args.clips:
            raise ConfigError("give --clips (the site clips) or --resume DIR")
        return args, argv
    stored = args.resume / "config.json"
    if not stored.is_file():
        raise ConfigError(f"--resume: {stored} not found; expected the folder of an earlier robustness study")
    saved = json.loads(stored.read_text())["argv"]
    again = _parser().parse_args(saved)
    again.workers, again.ray_address, again.no_rrd = args.workers, args.ray_address, args.no_rrd
    again.resume, again.dry_run = args.resume, args.dry_run
    return again, saved


def _study_argv(argv: list[str]) -> list[str]:
    """``argv`` without the options that do not define the study (its folder, workers, cluster, recordings)."""
    out, skip = [], False
    for a in argv:
        if skip:
            skip = False
        elif a in ("--out", "--workers", "--ray-address"):
            skip = True
        elif a != "--no-rrd" and not a.startswith(("--out=", "--workers=", "--ray-address=")):
            out.append(a)
    return out


def study_config(args) -> ClosedLoopConfig:
    """The closed-loop settings of the study's runs."""
    config = apply_overrides(ClosedLoopConfig(planners=args.planners, split=args.split, clips_limit=args.clips_limit,
                                              clip_names=tuple(args.clip_names), render_clips=0,
                                              planner=SITE_PLANNERS), args.overrides)
    options = config.planner  # absolute: a Ray worker need not start in this folder
    absolute = {f: Path(getattr(options, f)).resolve() for f in ("checkpoint", "footprint_checkpoint")
                if getattr(options, f) is not None}
    return dataclasses.replace(config, planner=dataclasses.replace(options, **absolute))


@cli_boundary
def main(argv=None) -> dict[str, Any]:
    """Command-line entry point (usage in the module docstring; a user's mistake exits 2 with one error line)."""
    argv = list(sys.argv[1:] if argv is None else argv)
    args, argv = _settings(_parser().parse_args(argv), argv)
    loop = study_config(args)
    names, notes = planner_names(loop)
    clips = split_clips(loop.split)
    indices = clip_indices(clips, loop)
    folder = args.resume
    log = RecordLog(folder / "records.csv") if folder is not None else None
    jobs = study_jobs(args.factors, args.levels, clips, indices, names, set() if log is None else log.done())
    if args.dry_run:
        print(dry_run_text(jobs, names))
        return {"jobs": jobs}
    build_planners(names, loop.planner)  # fails fast on a missing checkpoint, before any folder or work
    if folder is None:
        folder = run_folder("robustness", args.out)
        log = RecordLog(folder / "records.csv")
        stored = _study_argv(argv)
        (folder / "config.json").write_text(json.dumps(
            {"argv": stored, "config": dataclasses.asdict(loop), "planners": names, "factors": args.factors,
             "levels": args.levels, "seed": args.seed, "clips": [clips[k].name for k in indices],
             "git_commit": git_commit()}, indent=2, default=str))
    start = time.perf_counter()
    run_jobs(jobs, names, loop, args.seed, log, args.workers or default_workers(), args.ray_address)
    rows = log.rows()
    table = "\n".join([format_table(rows, args.factors, names), *notes]).strip()
    (folder / "table.md").write_text(table + "\n")
    (folder / "plots").mkdir(exist_ok=True)
    plots = [factor_figure(rows, f, names, folder / "plots" / f"{f}.png") for f in args.factors]
    recordings = [] if args.no_rrd else record_failures(rows, loop, args.seed, folder)
    print(table)
    print(f"\n{len(rows)} runs ({sum(len(j[3]) for j in jobs)} now, {time.perf_counter() - start:.0f} s); results "
          f"in {folder}/: records.csv, table.md, config.json, plots/ ({len(plots)})"
          + (f", rrd/ ({len(recordings)} first failures)" if recordings else ""))
    return {"folder": folder, "rows": rows, "table": table, "plots": plots, "recordings": recordings}


if __name__ == "__main__":
    main()
