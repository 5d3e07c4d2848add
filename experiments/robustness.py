"""Closed-loop robustness: the main job's clip runs repeated under one disturbance at a time (beyond the paper;
docs/robustness.md).

``python -m experiments.robustness --clips [--split eval|train-difficult] [--clips-limit N | --clip-names NAME ...]
[--planners ...] [--factors ...] [--levels mild moderate severe] [--seed S] [--workers N] [--ray-address ADDR]
[--out DIR | --resume DIR] [--dry-run] [--no-rrd] [--set KEY=VALUE ...]``

``python -m experiments.robustness --benchmark factorial|topology [--per-scene K] [--limit N] [--convention ...]
[--checkpoint PATH] [--vehicle sedan|van|FILE] ...`` or ``--scenes FILE... [--starts N]``: frozen-start episodes
instead of the clips, each planned once and tracked as `experiments.track` does (`tracking.episode_run`: where
each factor acts on an episode).

With ``--clips``, every clip × planner of the closed-loop study (`experiments.closed_loop`: same planners, clips,
tracker and ``--set`` settings) is driven once undisturbed (level 'none') and once per factor of ``--factors``
(default all eight of `tracking.disturbance.FACTORS`: detection noise and drops, localisation noise with drift,
actuation latency, a slower steering actuator, tyre friction, a payload shifting the centre of mass, a longer body)
at each of ``--levels``. With ``--benchmark`` or ``--scenes``, every episode × planner likewise (planners default to the
searches and, with a checkpoint (the shipped Factorial one by default), the learned planners). Every planner meets
the same draws: a run's random draws are seeded by ``--seed`` and the clip or episode (``--seed`` also draws the
starts of scene files with ``--starts``).

Runs are scheduled on Ray as one task per (factor, level, clip or episode) on a pool of actors that each build the
planners once: a local Ray with ``--workers`` actors (default one per core) or the cluster at ``--ray-address``
(one actor per CPU of it; the project must be installed on every node). ``--workers 1`` without an address runs in this
process, without Ray. Each finished row is appended to ``records.csv`` at once; after a kill, ``--resume DIR``
runs what is missing with the settings stored in ``DIR/config.json``. ``--dry-run`` prints the run count and the
CPU time estimated from the main job's recorded wall times, and runs nothing.

Writes into the run folder (default ``results/robustness/<timestamp>/``): ``records.csv`` (one row per factor ×
level × clip (episode) × planner: the closed-loop record columns plus factor, level, level_value, setting, seed),
``table.md``, ``plots/<factor>.png`` (footprint success and contact rate against the level, one line per planner,
95 % Wilson bands), ``config.json`` and ``rrd/`` (per factor × level × planner the first clip that fails there but
passes undisturbed, else the level's first failure, driven again with a Rerun recording; ``python -m
experiments.failure_review DIR`` reads them).
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

from experiments.closed_loop import (CLIP_SPLITS, PLANNERS, SITE_PLANNERS, ClosedLoopConfig, default_workers,
                                     planner_names)
from experiments.common import run_folder
from experiments.overrides import apply_overrides
from experiments.registry import PlannerOptions, build_planners, check_names
from experiments.robustness_report import FailureCase, factor_figure, failure_cases, format_table
from experiments.robustness_sources import StartSpec, build_source, disturbance_at
from experiments.scene_files import scene_file
from experiments.track import PLANNERS as TRACK_PLANNERS
from np_sim.cli import cli_boundary, existing_file, fresh_folder, non_negative_int, positive_int, vehicle_spec
from np_sim.errors import ConfigError
from np_sim.provenance import provenance
from np_sim.vehicle import VehicleSpec
from tracking.controllers import CONTROLLERS
from tracking.disturbance import FACTORS, LEVELS

FACTORIAL_CHECKPOINT = Path("checkpoints/factorial_np_seed0.pt")
"""The learned planners' default checkpoint on the Factorial starts (the shipped one)."""
MAIN_JOB = Path("docs/results/2026-12-02-anytime-main-job/records.csv.gz")
"""The main job's records, whose wall times give ``--dry-run``'s estimate."""
EPISODE_PLANNERS = ("hybrid_astar", "neuralparker", "np_guided_astar", "staged_astar_np")
"""Planners of an episode study by default (the learned ones only with a checkpoint)."""
FALLBACK_RUN_S = 2.5
"""CPU seconds per run assumed for a planner the main job's records lack."""


def study_jobs(factors, levels, units: list[str], names: list[str], key: set[tuple] | None = None,
               ) -> list[tuple[str, str, int, tuple[str, ...]]]:
    """(factor, level, unit index, planners still to run) of every (factor, level, unit) with a run missing from
    ``key`` (the (factor, level, planner, unit name) of the runs done); the undisturbed level first."""
    done = key or set()
    cells = [("none", "none")] + [(f, lv) for f in factors for lv in levels]
    jobs = []
    for factor, level in cells:
        for k, unit in enumerate(units):
            todo = tuple(n for n in names if (factor, level, n, unit) not in done)
            if todo:
                jobs.append((factor, level, k, todo))
    return jobs


class RecordLog:
    """``records.csv`` of a study, appended one row at a time (flushed), read back on ``--resume``."""

    def __init__(self, path: Path, key: str = "clip"):
        self.path, self.key = path, key
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
        """(factor, level, planner, clip or episode) of every row written so far."""
        return {(r["factor"], r["level"], r["planner"], r[self.key]) for r in self.rows()}

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
    from np_policy.threads import use_threads

    use_threads(1)


class StudyWorker:
    """A worker of the study: its source (`experiments.robustness_sources`) and planners, built once, and the runs
    of one job at a time."""

    def __init__(self, names: list[str], spec, seed: int, quiet: bool = True):
        if quiet:
            _quiet_threads()
        self.seed = seed
        self.source = build_source(spec)
        self.planners = build_planners(names, self.source.options)

    def run(self, job: tuple) -> list[dict]:
        """The rows of one (factor, level, unit index, planners) job, each led by the disturbance's columns."""
        factor, level, k, names = job
        head = disturbance_columns(factor, level, self.seed)
        rows = self.source.rows(k, {n: self.planners[n] for n in names}, factor, level, self.seed)
        return [{**head, **row} for row in rows]


def disturbance_columns(factor: str, level: str, seed: int) -> dict:
    """factor, level, level_value, setting and seed of a run."""
    disturbance = disturbance_at(factor, level, seed)
    return {"factor": factor, "level": level, "level_value": 0.0 if disturbance is None else disturbance.value,
            "setting": "none" if disturbance is None else disturbance.setting, "seed": seed}


def run_jobs(jobs: list[tuple], names: list[str], spec, seed: int, log: RecordLog,
             workers: int, address: str | None) -> None:
    """Run ``jobs``, appending each one's rows to ``log`` as it finishes: in this process for one worker without
    an address, else on Ray actors (module docstring)."""
    bar = tqdm(total=sum(len(j[3]) for j in jobs), desc="robustness runs", unit="run")
    if workers == 1 and address is None:
        from np_policy.threads import threads

        worker = StudyWorker(names, spec, seed, quiet=False)
        with threads(1):  # torch and numba on one thread as on a pool worker, the caller's counts restored after
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
        pool = ActorPool([actor.remote(names, spec, seed) for _ in range(min(workers, len(jobs)))])
        for rows in pool.map_unordered(lambda a, job: a.run.remote(job), jobs):
            log.append(rows)
            bar.update(len(rows))
    finally:
        bar.close()
        ray.shutdown()


def recording_path(folder: Path, case: FailureCase) -> Path:
    """Where the study in ``folder`` keeps the recording of ``case``: ``rrd/<factor>_<level>_<planner>_<unit>.rrd``."""
    return folder / "rrd" / f"{case.factor}_{case.level}_{case.planner}_{case.unit.replace('#', '_')}.rrd"


def record_failures(rows: list[dict], source, seed: int, folder: Path) -> list[Path]:
    """Drive the failure each disturbance caused (`experiments.robustness_report.failure_cases`: per factor × level
    × planner the first clip or episode, in ``source.units`` order, that fails there but passes undisturbed, else
    the level's first failure) again with a Rerun recording, ``rrd/<factor>_<level>_<planner>_<unit>.rrd`` (kept
    when it exists: a resumed study)."""
    cases = failure_cases(rows, source.units, source.key)
    if not cases:
        return []
    order = {name: k for k, name in enumerate(source.units)}
    planners = build_planners(sorted({c.planner for c in cases}), source.options)
    written = []
    for case in tqdm(cases, desc="recording failures"):
        path = recording_path(folder, case)
        if not path.exists():
            path.parent.mkdir(exist_ok=True)
            source.record(order[case.unit], planners[case.planner], case.factor, case.level, seed, path)
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


def dry_run_text(jobs: list[tuple], names: list[str], clips: bool) -> str:
    """The run count and the estimated CPU time of ``jobs`` (for episodes: ``FALLBACK_RUN_S`` a run)."""
    seconds = run_seconds(names) if clips else dict.fromkeys(names, FALLBACK_RUN_S)
    runs = sum(len(j[3]) for j in jobs)
    cpu = sum(seconds[n] for j in jobs for n in j[3])
    per = ", ".join(f"{n} {seconds[n]:.1f} s" for n in names)
    unit = "clip" if clips else "episode"
    source = f"from {MAIN_JOB}" if clips else "assumed"
    return (f"{runs} runs ({len(jobs)} factor × level × {unit} jobs) ≈ {cpu / 3600:.1f} CPU-hours "
            f"(per run: {per}; {source}); ≈ {cpu / 3600 / default_workers():.1f} h on the "
            f"{default_workers()} cores here")


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(prog="python -m experiments.robustness", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    mode = parser.add_mutually_exclusive_group()
    mode.add_argument("--clips", action="store_true", help="run the site clips (the main job's closed loop)")
    mode.add_argument("--benchmark", choices=["factorial", "topology"],
                      help="run the benchmark's frozen test starts instead (planned once, tracked)")
    mode.add_argument("--scenes", nargs="+", type=scene_file, metavar="FILE",
                      help="run your own scene files instead (np_sim/data/scene.schema.json; or a shipped example "
                           "name): their starts, or --starts N drawn from each start region with --seed")
    parser.add_argument("--split", choices=CLIP_SPLITS, default="eval", help="clip set (default: the 47 held-out)")
    parser.add_argument("--clips-limit", type=positive_int, default=None, help="only the first N clips")
    parser.add_argument("--clip-names", nargs="+", default=(), help="only these clips (e.g. eval-1000016)")
    parser.add_argument("--planners", nargs="+", choices=sorted({*PLANNERS, *TRACK_PLANNERS}), default=None,
                        help="planners (default: the main job's; on starts the searches and, with a checkpoint, "
                             f"the learned planners: {', '.join(EPISODE_PLANNERS)})")
    episodes = parser.add_argument_group("frozen-start episodes (--benchmark, --scenes)")
    episodes.add_argument("--starts", type=positive_int, metavar="N",
                          help="with --scenes: starts drawn from the start region of each file that lists none")
    episodes.add_argument("--per-scene", type=positive_int, default=None, help="only the first K starts per scene")
    episodes.add_argument("--limit", type=positive_int, default=None, help="only the first N episodes")
    episodes.add_argument("--convention", choices=["reference_point", "footprint"], default="footprint",
                          help="convention of the searches (default footprint: the body is driven)")
    episodes.add_argument("--checkpoint", type=existing_file, default=None,
                          help=f"the learned planners' policy (default on Factorial: {FACTORIAL_CHECKPOINT})")
    episodes.add_argument("--vehicle", type=vehicle_spec, default=None,
                          help="vehicle planned for and driven: sedan (default), van or a vehicle JSON file")
    episodes.add_argument("--controller", choices=list(CONTROLLERS), default="lqr", help="tracking controller")
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
    parser.add_argument("--no-rrd", action="store_true", help="no Rerun recordings of the failures")
    parser.add_argument("--set", nargs="+", action="extend", default=[], metavar="KEY=VALUE", dest="overrides",
                        help="any setting of experiments.closed_loop.ClosedLoopConfig by its dotted path")
    return parser


def _settings(args, argv: list[str]) -> tuple[argparse.Namespace, list[str]]:
    """The study's arguments: ``args`` itself, or those stored in ``--resume``'s folder (its argv)."""
    if args.resume is None:
        if not (args.clips or args.benchmark or args.scenes):
            raise ConfigError("give --clips (the site clips), --benchmark NAME, --scenes FILE... or --resume DIR")
        if args.starts is not None and not args.scenes:
            raise ConfigError("--starts: only with --scenes (the benchmarks have frozen starts)")
        return args, argv
    stored = args.resume / "config.json"
    if not stored.is_file():
        raise ConfigError(f"--resume: {stored} not found; expected the folder of an earlier robustness study")
    saved = json.loads(stored.read_text())["argv"]
    again = _parser().parse_args(saved)
    again.workers, again.ray_address, again.no_rrd = args.workers, args.ray_address, args.no_rrd
    again.resume, again.dry_run = args.resume, args.dry_run
    return again, saved


def stored_study(folder: Path) -> argparse.Namespace:
    """The arguments the study in ``folder`` ran with (its ``config.json``), as `main` resumes it; a ConfigError
    when ``folder`` holds no study."""
    return _settings(_parser().parse_args(["--resume", str(folder)]), [])[0]


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


def study_spec(args) -> tuple[ClosedLoopConfig | StartSpec, list[str], list[str]]:
    """The study's source spec (`experiments.robustness_sources`), its planners and notes on planners left out."""
    if args.clips:
        loop = study_config(args)
        names, notes = planner_names(loop)
        return loop, names, notes
    if args.overrides:
        raise ConfigError("--set: only with --clips (it sets experiments.closed_loop.ClosedLoopConfig)")
    benchmark = args.benchmark or "factorial"
    checkpoint = args.checkpoint or (FACTORIAL_CHECKPOINT if args.benchmark == "factorial" else None)
    options = PlannerOptions(checkpoint=None if checkpoint is None else Path(checkpoint).resolve(),
                             convention=args.convention, benchmark=None if args.scenes else benchmark,
                             vehicle=args.vehicle or VehicleSpec())
    names, notes = args.planners, []
    if names is None:
        names = list(EPISODE_PLANNERS) if checkpoint else ["hybrid_astar"]
        notes = [] if checkpoint else ["The learned planners need --checkpoint PATH: only Hybrid A* ran."]
    check_names(names, TRACK_PLANNERS)
    scenes = tuple(Path(f).resolve() for f in args.scenes or ())
    spec = StartSpec(options=options, benchmark=benchmark, scenes=scenes, n_starts=args.starts,
                     starts_seed=args.seed, per_scene=args.per_scene, limit=args.limit, controller=args.controller)
    return spec, list(names), notes


def study_config(args) -> ClosedLoopConfig:
    """The closed-loop settings of a clip study's runs."""
    if args.planners:
        check_names(args.planners, PLANNERS)
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
    spec, names, notes = study_spec(args)
    source = build_source(spec)
    folder = args.resume
    log = RecordLog(folder / "records.csv", source.key) if folder is not None else None
    jobs = study_jobs(args.factors, args.levels, source.units, names, None if log is None else log.done())
    if args.dry_run:
        print(dry_run_text(jobs, names, clips=args.clips))
        return {"jobs": jobs}
    build_planners(names, source.options)  # fails fast on a missing checkpoint, before any folder or work
    if folder is None:
        folder = run_folder("robustness", args.out)
        log = RecordLog(folder / "records.csv", source.key)
        (folder / "config.json").write_text(json.dumps(
            {"argv": _study_argv(argv), "config": dataclasses.asdict(spec), "planners": names,
             "factors": args.factors, "levels": args.levels, "seed": args.seed, f"{source.noun}s": source.units,
             **provenance()}, indent=2, default=str))
    start = time.perf_counter()
    run_jobs(jobs, names, spec, args.seed, log, args.workers or default_workers(), args.ray_address)
    rows = log.rows()
    table = "\n".join([format_table(rows, args.factors, names, source.key), *notes]).strip()
    (folder / "table.md").write_text(table + "\n")
    (folder / "plots").mkdir(exist_ok=True)
    plots = [factor_figure(rows, f, names, folder / "plots" / f"{f}.png") for f in args.factors]
    recordings = [] if args.no_rrd else record_failures(rows, source, args.seed, folder)
    print(table)
    print(f"\n{len(rows)} runs ({sum(len(j[3]) for j in jobs)} now, {time.perf_counter() - start:.0f} s); results "
          f"in {folder}/: records.csv, table.md, config.json, plots/ ({len(plots)})"
          + (f", rrd/ ({len(recordings)} failures)" if recordings else ""))
    return {"folder": folder, "rows": rows, "table": table, "plots": plots, "recordings": recordings}


if __name__ == "__main__":
    main()
