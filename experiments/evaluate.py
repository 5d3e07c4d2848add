"""Evaluate NeuralParker checkpoints on a benchmark's frozen test starts (paper §III-A protocol, Table I style).

``python -m experiments.evaluate --benchmark factorial --checkpoints a.pt [b.pt c.pt] [--preset paper]
[--connector fixed|ensemble|centred] [--samples N | --action sample [--action-seed S]] [--vehicle sedan|van|FILE]
[--split test|validation|holdout [--starts-per-scene N]] [--out DIR [--resume]]``

Each checkpoint is one training seed. Every frozen start (1,080 Factorial, 720 Topology-Stress) is planned with
the checkpoint's environment rules and the NeuralParker preset ``--preset`` (`np_policy.config.PRESETS`; default
'paper', the deterministic policy); the other flags replace one field of it: ``--connector``
(``NeuralParkerConfig.connector``) swaps the terminal connector at evaluation time only (the paper's "ensemble,
evaluation only" row; ``centred`` is the fixed nine tried target-aligned first,
`np_sim.config.ConnectorConfig.variant`); ``--samples N`` plans with the best of the mean rollout and N seeded
sampled rollouts (`np_policy.sampling`, beyond the paper); ``--action sample`` plays one rollout of sampled actions
instead of the mean, as a Tianshou policy acts at test time by default; ``--action-seed`` seeds both. Success is on
the full set, beside it the exact validity of the planned paths (`np_sim.validate`: the footprint, and the
reference point, swept continuously; a failure counts as invalid); path length L, reversals and Δκ (eq:metrics)
on the common-success cohort — here the episodes every
evaluated seed solved — reported as the mean ± sample SD over seeds; plan time as median and 90th percentile.
``--vehicle`` (`np_sim.vehicle`, default the sedan) is the vehicle planned for: a checkpoint trained for another
one is refused with both named, and the exact footprint validity uses its footprint. Writes ``records.csv`` and
``records.json`` (one row per episode), ``table.md`` and ``config.json`` into the run folder; each finished
episode is kept as the run goes, and ``--resume`` continues a killed run (`experiments.progress`).

``--split validation`` plans the validation starts on the **training** scenes instead
(`np_sim.benchmarks.validation_starts`: the same protocol, seed 1, ``--starts-per-scene`` per scene, default 10):
the set on which a choice may be made, and the way to tell a policy that has not learned the benchmark from one
that has not generalised to its held-out scenes. ``--split holdout`` plans the same starts on only the training
scenes the checkpoints left out (``TrainConfig.holdout_every``, the same in every checkpoint): scenes the policy
never saw, for choosing how a recipe generalises without the test scenes.
"""

from __future__ import annotations

import argparse
import dataclasses
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from experiments.common import first, mean_sd
from experiments.progress import EpisodeProgress, check_out, progress_folder
from experiments.scene_files import add_split_arguments, common_holdout
from np_policy.config import ACTIONS, PAPER, PRESETS, NeuralParkerConfig
from np_policy.planner import NeuralParkerPlanner, Policy
from np_sim.benchmarks.frozen import VALIDATION_STARTS_PER_SCENE, split_episodes
from np_sim.cli import cli_boundary, existing_file, non_negative_int, positive_int, vehicle_spec
from np_sim.config import CONNECTOR_VARIANTS
from np_sim.validate import plan_valid
from np_sim.vehicle import VehicleSpec


def method_name(config: NeuralParkerConfig) -> str:
    """The table's name of a NeuralParker planner playing ``config``."""
    if config.action == "sample":
        return f"NeuralParker, sampled actions (seed {config.seed})"
    if not config.samples and not config.rescue:
        return "NeuralParker"
    return f"NeuralParker, best of 1 + {config.samples}" + (" + rescue rounds" if config.rescue else "")


def evaluate(benchmark: str, checkpoints: list[Path], config: NeuralParkerConfig = PAPER, out: Path | None = None,
             limit: int | None = None, progress: bool = True, vehicle: VehicleSpec | None = None,
             resume: bool = False, split: str = "test",
             starts_per_scene: int = VALIDATION_STARTS_PER_SCENE) -> dict[str, Any]:
    """Plan every frozen start (``split`` 'validation': the validation starts on the training scenes,
    ``starts_per_scene`` each; 'holdout': those of the training scenes the checkpoints left out) with every
    checkpoint for ``vehicle`` (default the sedan; a checkpoint trained for another is refused), playing each as
    ``config`` says (the 'paper' preset: the mean action); returns the records and the table text. Each finished
    episode is kept as it goes (`experiments.progress`); ``resume`` continues the interrupted run in ``out``."""
    vehicle = VehicleSpec() if vehicle is None else vehicle
    holdout_every = shared_holdout(checkpoints, benchmark) if split == "holdout" else 0
    scenes, starts = split_episodes(benchmark, split, starts_per_scene, vehicle, holdout_every)
    episodes = first([(k, j) for k in range(len(scenes)) for j in range(starts.shape[1])], limit)
    settings = {"benchmark": benchmark, "split": split, "checkpoints": [str(p) for p in checkpoints],
                "neuralparker": config.to_dict(), "vehicle": vehicle.to_dict(), "episodes": len(episodes)}
    if split != "test":
        settings["starts_per_scene"] = starts_per_scene
    if holdout_every:
        settings["holdout_every"] = holdout_every
    folder = progress_folder("evaluate", out, resume)
    kept = EpisodeProgress(folder, settings, resume)
    records: list[dict[str, Any]] = []
    for seed_index, path in enumerate(checkpoints):
        planner = NeuralParkerPlanner.from_checkpoint(path, config, benchmark=benchmark, vehicle=vehicle)
        for k, j in tqdm(episodes, desc=f"{Path(path).name}", unit="ep", disable=not progress):
            records += kept.rows((seed_index, k, j), lambda: [episode_row(
                planner, config, scenes[k], starts[k, j], vehicle,
                {"scene": scenes[k].name, "start_id": j, "checkpoint": str(path), "seed_index": seed_index})])
    table = format_table(records, len(checkpoints))
    kept.write_results(records, table, settings)
    return {"records": records, "table": table, "folder": folder}


def shared_holdout(checkpoints: list[Path], benchmark: str) -> int:
    """The ``TrainConfig.holdout_every`` every checkpoint was trained with (ConfigError naming them when they differ
    or when none left scenes out)."""
    return common_holdout({str(path): Policy.load(path, benchmark).train.holdout_every for path in checkpoints})


def episode_row(planner: NeuralParkerPlanner, config: NeuralParkerConfig, scene, start, vehicle: VehicleSpec,
                episode: dict[str, Any]) -> dict[str, Any]:
    """The record of one frozen start planned by ``planner`` (``episode``: the columns naming it)."""
    plan = planner.plan(scene, start)
    L, rev, dk = plan.metrics() if plan.success else (float("nan"), -1, float("nan"))
    return {"scene": episode["scene"], "start_id": episode["start_id"], "method": method_name(config),
            "connector": config.connector or planner.env_config.connector.mode,
            "checkpoint": episode["checkpoint"], "seed": planner.policy.train.seed,
            "seed_index": episode["seed_index"],
            "success": int(plan.success), "reason": plan.reason, "L": L, "reversals": rev,
            "delta_kappa": dk, "plan_time_ms": 1e3 * plan.plan_time_s,
            "exact_footprint_valid": int(plan_valid(scene, plan, "exact", "footprint", vehicle)),
            "exact_ref_point_valid": int(plan_valid(scene, plan, "exact", "reference_point", vehicle))}


def format_table(records: list[dict[str, Any]], n_seeds: int) -> str:
    """Markdown table: success (full set), L / reversals / Δκ on the common-success cohort, plan time."""
    by_seed = [[r for r in records if r["seed_index"] == s] for s in range(n_seeds)]
    solved = [{(r["scene"], r["start_id"]) for r in rows if r["success"]} for rows in by_seed]
    cohort = set.intersection(*solved) if solved else set()
    success = [np.mean([r["success"] for r in rows]) for rows in by_seed]
    exact = {key: [np.mean([r[key] for r in rows]) for rows in by_seed]
             for key in ("exact_footprint_valid", "exact_ref_point_valid")}
    metric = {key: [np.mean([r[key] for r in rows if (r["scene"], r["start_id"]) in cohort]) if cohort else np.nan
                    for rows in by_seed] for key in ("L", "reversals", "delta_kappa")}
    times = np.array([r["plan_time_ms"] for r in records])
    header = ("| Method | Succ. | Exact-valid footprint (ref. point) | L (m) | Rev. | Δκ | cohort | "
              "plan time median / p90 (ms) |\n|---|---|---|---|---|---|---|---|")
    row = (f"| {records[0]['method']} ({records[0]['connector']}) | {mean_sd(success)} | "
           f"{mean_sd(exact['exact_footprint_valid'])} ({mean_sd(exact['exact_ref_point_valid'])}) | "
           f"{mean_sd(metric['L'])} | "
           f"{mean_sd(metric['reversals'])} | {mean_sd(metric['delta_kappa'])} | {len(cohort)} | "
           f"{np.median(times):.2f} / {np.percentile(times, 90):.2f} |")
    return header + "\n" + row


@cli_boundary
def main(argv=None) -> dict[str, Any]:
    """Command-line entry point (usage in the module docstring; a user's mistake exits 2 with one error line)."""
    parser = argparse.ArgumentParser(prog="python -m experiments.evaluate", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--benchmark", choices=["factorial", "topology"], default="factorial")
    parser.add_argument("--checkpoints", type=existing_file, nargs="+", required=True,
                        help="one checkpoint per seed")
    parser.add_argument("--preset", choices=sorted(PRESETS), default="paper",
                        help="how the planner plays the policy (np_policy.config.PRESETS; default paper: the "
                             "deterministic planner of the paper and docs/specification.md); the flags below "
                             "replace one field of it")
    parser.add_argument("--connector", choices=CONNECTOR_VARIANTS, default=None,
                        help="override the terminal connector (centred: the fixed nine, target-aligned first)")
    parser.add_argument("--samples", type=non_negative_int, default=None, metavar="N",
                        help="plan with the best of the mean rollout and N seeded sampled rollouts (paper preset: 0)")
    parser.add_argument("--action", choices=ACTIONS, default=None,
                        help="mean (paper preset): the deterministic planner; sample: one rollout of sampled actions "
                             "per start, as a Tianshou PPO policy acts at test time by default")
    parser.add_argument("--action-seed", type=non_negative_int, default=None, metavar="S",
                        help="noise seed of --action sample (with the start pose) and of --samples' rollouts "
                             "(paper preset: 0)")
    parser.add_argument("--vehicle", type=vehicle_spec, default=VehicleSpec(),
                        help="vehicle planned for: a preset (sedan, the default; van) or a vehicle JSON file "
                             "(docs/vehicles.md); the checkpoints must have been trained for it")
    parser.add_argument("--out", type=Path,
                        help="new or empty run folder (default: a fresh results/evaluate/<timestamp>)")
    parser.add_argument("--resume", action="store_true",
                        help="continue the interrupted run in --out where it stopped (the same other arguments; a "
                             "new or empty --out starts a fresh run)")
    add_split_arguments(parser, ("test", "validation", "holdout"))
    parser.add_argument("--limit", type=positive_int, help="only the first N frozen episodes (smoke runs)")
    args = parser.parse_args(argv)
    check_out(parser, args.out, args.resume)
    fields = {"connector": args.connector, "samples": args.samples, "action": args.action, "seed": args.action_seed}
    config = dataclasses.replace(PRESETS[args.preset], **{k: v for k, v in fields.items() if v is not None})
    result = evaluate(args.benchmark, args.checkpoints, config, args.out, args.limit, vehicle=args.vehicle,
                      resume=args.resume, split=args.split, starts_per_scene=args.starts_per_scene)
    print(result["table"])
    print(f"records: {result['folder'] / 'records.csv'}")
    return result


if __name__ == "__main__":
    main()
