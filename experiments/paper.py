"""The reproduction report: every table and figure of the paper's §V from what is on disk (no training).

``python -m experiments.paper [--out docs/reproduction.md] [--runs checkpoints/runs] [--no-evaluate]``

For each of the paper's simulation tables (``tab:twostage``, ``tab:topology-stress``, ``tab:hermite``,
``tab:app-controls``) and figures (``fig:sceneexamples``, ``fig:main-comparison``, ``fig:overview``,
``fig:global-family``, ``fig:hermite-case``) the report has a section with the paper's numbers
(`experiments.paper_numbers`) beside ours and the seeds each row has. A row's seed counts when its training run
(the sweep's run folder, `experiments.sweep_plan`) is finished, i.e. its ``metrics.jsonl`` reaches its config's
epochs (episodes for the adapted HOPE) and it holds its trainer's output (``best.pt``; the adapted HOPE's
``final.pt``: `experiments.sweep_plan.RunSpec.output`), and its frozen-start evaluation records exist in the run
folder (``eval_<benchmark>/records.csv``: the checkpoint's own connector, `experiments.evaluate`, or the ``hope``
method of `experiments.planners` for an adapted-HOPE checkpoint; ``eval_<benchmark>_ensemble/``: the ensemble
connector swapped in at evaluation only; ``eval_<benchmark>_staged/``: the Hybrid A* → NP planner,
`experiments.planners`; ``eval_<benchmark>_validation/``: the own planner on the validation starts of the training
scenes, ``--split validation``, for the test-against-training-scenes tables of Table III's and Fig. 3's rows). A
finished run without records is evaluated here (``--no-evaluate``: reported as not evaluated; an evaluation
killed mid-way continues where it stopped, `experiments.progress`); a run that is not
finished is named with its state ("0 of 3 seeds: not trained yet"), never left out. Success is on the full set,
L, reversals and Δκ (eq:metrics) on the within-seed common-success cohort of the rows measured, each the mean ±
sample SD over seeds. Each of the paper's claims gets one verdict (`claim_verdict`). Compute per table: training
CPU-hours from the runs' ``metrics.jsonl`` epoch times and the evaluation's planning time. Figures are written
beside the report under ``figures/``; this run's case folders under a fresh ``results/paper/<timestamp>/``.
"""

from __future__ import annotations

import argparse
import csv
import json
import os
import shutil
import subprocess
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from matplotlib.figure import Figure

from experiments import hermite_case, overview_case, scenes
from experiments.common import run_folder
from experiments.progress import holds_progress
from experiments.paper_numbers import (CURRICULUM, GLOBAL_FAMILY, HERMITE, HIGHER_IS_BETTER, MAIN_COMPARISON,
                                       METRIC_NAMES, METRICS, TOPOLOGY_STRESS, TWOSTAGE, PaperTable)
from experiments.sweep_plan import (PAPER_PLAN, TRAINERS, RunSpec, active_trainers, expand, metrics_rows,
                                    run_state)
from np_sim.benchmarks import load_benchmark
from np_sim.benchmarks.frozen import VALIDATION_STARTS_PER_SCENE
from np_sim.cli import cli_boundary

SEEDS = (0, 1, 2)
PATH_METRICS = ("L", "reversals", "delta_kappa")


@dataclass(frozen=True)
class Arm:
    """One row of our reproduction: a sweep configuration evaluated one way."""

    label: str
    """The paper's row label."""
    configuration: str
    """`experiments.sweep_plan.Configuration.name` whose runs give the checkpoints."""
    evaluation: str = "own"
    """'own' (the checkpoint's connector), 'ensemble' (ensemble swapped in at evaluation), 'staged',
    'validation' (the own planner on the validation starts of the training scenes), or, adapted HOPE only, 'mean'
    and 'staged_mean' (its mean action or most probable anchor instead of `HOPE_ACTION`)."""


HOPE_ACTION = "sampled"
"""How the adapted-HOPE rows play their policy: HOPE's evaluation protocol (`hope_policy.planner`)."""
EVAL_FOLDERS = {"own": "eval_{benchmark}", "ensemble": "eval_{benchmark}_ensemble", "staged": "eval_{benchmark}_staged",
                "validation": "eval_{benchmark}_validation", "mean": "eval_{benchmark}_mean",
                "staged_mean": "eval_{benchmark}_staged_mean"}
"""The evaluation's records folder inside a run folder."""

ARMS = {
    MAIN_COMPARISON.label: (Arm("NeuralParker", "factorial_np"), Arm("Adapted HOPE", "factorial_hope")),
    TWOSTAGE.label: (Arm("Unified NP", "factorial_np"), Arm("Hybrid A* → NP", "factorial_np", "staged"),
                     Arm("Hybrid A* → HOPE", "factorial_hope", "staged")),
    TOPOLOGY_STRESS.label: tuple(Arm(f"{name} backbone: {rep}", f"topology_{stem}_{key}")
                                 for name, stem in (("NeuralParker", "np"), ("HOPE-style", "hope"))
                                 for rep, key in (("none", "none"), ("BEV", "bev"), ("vertices", "vertices"))),
    HERMITE.label: (Arm("Fixed Hermite", "factorial_np_fixed"),
                    Arm("Ensemble, eval. only", "factorial_np_fixed", "ensemble"),
                    Arm("Ensemble, train + eval.", "factorial_np")),
    CURRICULUM.label: (Arm("No curriculum", "factorial_np_nocurriculum"), Arm("Geodesic curriculum", "factorial_np")),
}
"""Our rows of each table (and of the bar figures), labelled as in the paper."""
GLOBAL_FAMILY_ARMS = ARMS[TOPOLOGY_STRESS.label]
GENERALISATION_TABLES = (TOPOLOGY_STRESS, MAIN_COMPARISON)
"""The tables whose rows the report also measures on the validation starts of their training scenes."""


@dataclass
class ArmResult:
    """The measured seeds of one arm: per-episode records by seed, and why each other seed is missing."""

    arm: Arm
    records: dict[int, list[dict]] = field(default_factory=dict)
    missing: dict[int, str] = field(default_factory=dict)
    shared_geometry: dict[int, str] = field(default_factory=dict)
    """Measured seeds trained with `np_policy.train --shared-geometry`: 'all epochs' or the epochs that were."""

    def shared_geometry_text(self) -> str:
        """'–', or 'seed 1' / 'seeds 1, 2 (seed 2: epochs 121–240)' for the seeds in `shared_geometry`."""
        if not self.shared_geometry:
            return "–"
        seeds = sorted(self.shared_geometry)
        partial = "; ".join(f"seed {s}: {self.shared_geometry[s]}" for s in seeds
                            if self.shared_geometry[s] != "all epochs")
        return (f"seed{'s' if len(seeds) > 1 else ''} {', '.join(map(str, seeds))}"
                + (f" ({partial})" if partial else ""))

    def seeds_text(self) -> str:
        """'2 of 3 (seeds 0, 1; seed 2: training, epoch 95 of 240)' or '0 of 3 seeds: not trained yet (…)'."""
        have = sorted(self.records)
        if not have:
            reasons = sorted(set(self.missing.values()))
            detail = reasons[0] if len(reasons) == 1 else "; ".join(f"seed {s}: {r}" for s, r in self.missing.items())
            return f"0 of {len(SEEDS)} seeds: {detail}"
        text = f"{len(have)} of {len(SEEDS)} (seed{'s' if len(have) > 1 else ''} {', '.join(map(str, have))}"
        return text + "".join(f"; seed {s}: {r}" for s, r in self.missing.items()) + ")"


def state_text(run: RunSpec, state) -> str:
    """A run's state in the report's words (no process ids, so the report only changes when the runs do)."""
    if state.kind == "not available yet":
        return f"not available yet ({state.detail})"
    if state.kind == "not started":
        return "not trained yet (not started)"
    if state.kind in ("training now", "interrupted", "started, no snapshot"):
        word = "training" if state.kind == "training now" else state.kind
        unit = TRAINERS[run.config.trainer][0].rstrip("s")
        return f"not trained yet ({word}, {unit} {state.epoch} of {run.epochs})"
    return f"not usable ({state.kind}: {state.detail})"


def read_records(path: Path) -> list[dict]:
    """Per-episode rows of a ``records.csv`` (scene, start_id, success, reason, L, reversals, delta_kappa,
    plan_time_ms; ``exact``: its ``exact_ref_point_valid``, None in records written without it)."""
    with path.open(newline="") as fh:
        return [{"key": (row["scene"], int(row["start_id"])), "success": int(row["success"]),
                 "reason": row.get("reason") or "",
                 "L": float(row["L"]), "reversals": float(row["reversals"]),
                 "delta_kappa": float(row["delta_kappa"]), "plan_time_ms": float(row["plan_time_ms"]),
                 "exact": int(row["exact_ref_point_valid"]) if row.get("exact_ref_point_valid") else None}
                for row in csv.DictReader(fh)]


def evaluation_missing(arm: Arm, run: RunSpec) -> str:
    """Why ``arm`` cannot be evaluated on ``run``'s checkpoint (empty when it can): an adapted-HOPE checkpoint has
    no ensemble-swapped evaluation."""
    if run.config.trainer == "hope_policy.train" and arm.evaluation == "ensemble":
        return f"trained; the {arm.evaluation} evaluation of an adapted-HOPE checkpoint is not built yet"
    return ""


def hope_action(arm: Arm) -> str:
    """The action an adapted-HOPE ``arm`` plays: 'mean' for its 'mean' and 'staged_mean' evaluations, else
    `HOPE_ACTION`."""
    return "mean" if arm.evaluation in ("mean", "staged_mean") else HOPE_ACTION


def stale_protocol(arm: Arm, run: RunSpec, folder: Path) -> str:
    """Why ``folder``'s records of an adapted-HOPE run were made under another action than ``arm`` plays
    (`hope_action`; records written before ``config.json`` said which played the mean action); empty when not."""
    if run.config.trainer != "hope_policy.train":
        return ""
    config_file = folder / "config.json"
    config = json.loads(config_file.read_text()) if config_file.exists() else {}
    action, wanted = config.get("hope", {}).get("action", "mean"), hope_action(arm)
    if action == wanted:
        return ""
    return (f"trained; {folder} was evaluated with the {action} action, this row plays {wanted} actions (move the "
            f"folder aside to re-evaluate)")


def evaluation_argv(arm: Arm, run: RunSpec, folder: Path) -> list[str]:
    """The experiment CLI that writes ``folder``'s records for ``run``'s output checkpoint (`RunSpec.output`)."""
    checkpoint, benchmark = str(run.output), run.config.benchmark
    split = ["--split", "validation"] if arm.evaluation == "validation" else []
    if run.config.trainer == "hope_policy.train":
        method = "staged_astar_hope" if arm.evaluation in ("staged", "staged_mean") else "hope"
        return [sys.executable, "-m", "experiments.planners", "--benchmark", benchmark, "--methods", method,
                "--hope-checkpoint", checkpoint, "--hope-action", hope_action(arm), "--out", str(folder), *split]
    if arm.evaluation == "staged":
        return [sys.executable, "-m", "experiments.planners", "--benchmark", benchmark, "--checkpoint", checkpoint,
                "--methods", "staged_astar_np", "--out", str(folder)]
    argv = [sys.executable, "-m", "experiments.evaluate", "--benchmark", benchmark, "--checkpoints", checkpoint,
            "--out", str(folder), *split]
    return argv + (["--connector", "ensemble"] if arm.evaluation == "ensemble" else [])


def row_seconds(row: dict, steps: int) -> float:
    """Wall-clock seconds of one ``metrics.jsonl`` row: its ``epoch_s``, its steps over ``steps_per_s`` in older
    rows (the same quantity, `np_policy.train`), or an adapted-HOPE update's ``collect_s + update_s``
    (`hope_policy.train`); ``steps`` is the previous row's ``env_steps``."""
    if "epoch_s" in row:
        return float(row["epoch_s"])
    if "collect_s" in row:
        return float(row["collect_s"]) + float(row["update_s"])
    return (int(row["env_steps"]) - steps) / float(row["steps_per_s"])


def epoch_hours(metrics: Path) -> float:
    """Wall-clock hours of a run's epochs (updates, for the adapted HOPE): the sum of `row_seconds`."""
    seconds, steps = 0.0, 0
    for row in metrics_rows(metrics):
        try:
            seconds += row_seconds(row, steps)
            steps = int(row["env_steps"])
        except (ValueError, KeyError, TypeError, ZeroDivisionError):
            continue
    return seconds / 3600.0


def shared_geometry_epochs(metrics: Path) -> str:
    """'' when no epoch of a run's ``metrics.jsonl`` trained with the shared geometry branch (rows without the field
    predate it: off), 'all epochs' when every one did, else the epochs that did ('epochs 121–240', 'epochs 1–5,
    9'); a torn last line is skipped."""
    flags = {}
    for row in metrics_rows(metrics):
        try:
            flags[int(row["epoch"])] = row.get("shared_geometry") is True
        except (ValueError, KeyError, TypeError):
            continue
    shared = [epoch for epoch, flag in flags.items() if flag]
    if not shared:
        return ""
    if len(shared) == len(flags):
        return "all epochs"
    spans, start = [], shared[0]
    for previous, epoch in zip(shared, shared[1:] + [None]):
        if epoch != previous + 1:
            spans.append(f"{start}–{previous}" if previous > start else str(start))
            start = epoch
    return "epochs " + ", ".join(spans)


def measure(arm: Arm, runs: dict, episodes: int, evaluate: bool, active: dict) -> ArmResult:
    """Records of every finished seed of ``arm`` (evaluating a finished run that has none when ``evaluate``)."""
    result = ArmResult(arm)
    for seed in SEEDS:
        run = runs[(arm.configuration, seed)]
        state = run_state(run, active)
        if state.kind != "finished":
            result.missing[seed] = state_text(run, state)
            continue
        folder = run.run_dir / EVAL_FOLDERS[arm.evaluation].format(benchmark=run.config.benchmark)
        if evaluation_missing(arm, run):
            result.missing[seed] = evaluation_missing(arm, run)
            continue
        if not (folder / "records.csv").exists():
            resumable = holds_progress(folder)  # a killed experiments.planners run continues where it stopped
            if folder.exists() and any(folder.iterdir()) and not resumable:
                result.missing[seed] = f"trained; {folder} holds an interrupted evaluation (remove it to re-run)"
                continue
            if not evaluate:
                result.missing[seed] = "trained, " + ("evaluation interrupted" if resumable else "not evaluated yet")
                continue
            argv = evaluation_argv(arm, run, folder) + (["--resume"] if resumable else [])
            subprocess.run(argv, check=True, stdout=subprocess.DEVNULL)
        stale = stale_protocol(arm, run, folder)
        if stale:
            result.missing[seed] = stale
            continue
        rows = read_records(folder / "records.csv")
        if len(rows) != episodes:
            result.missing[seed] = f"{folder / 'records.csv'} has {len(rows)} episodes, expected {episodes}"
            continue
        result.records[seed] = rows
        shared = shared_geometry_epochs(run.run_dir / "metrics.jsonl")
        if shared:
            result.shared_geometry[seed] = shared
    return result


def summarise(results: list[ArmResult]) -> tuple[dict[str, dict[str, list[float]]], dict[int, int]]:
    """Per arm label and metric, the per-seed values (success on the full set, path metrics on the within-seed
    common-success cohort of the arms measured at that seed); and the cohort size per seed."""
    seeds = sorted({s for r in results for s in r.records})
    cohorts = {s: set.intersection(*[{row["key"] for row in r.records[s] if row["success"]}
                                     for r in results if s in r.records]) for s in seeds}
    stats = {}
    for r in results:
        stats[r.arm.label] = {m: [] for m in METRICS}
        for s in sorted(r.records):
            rows = r.records[s]
            stats[r.arm.label]["success"].append(float(np.mean([row["success"] for row in rows])))
            for m in PATH_METRICS:
                values = [row[m] for row in rows if row["key"] in cohorts[s]]
                stats[r.arm.label][m].append(float(np.mean(values)) if values else float("nan"))
    return stats, {s: len(c) for s, c in cohorts.items()}


def fmt(values, digits: int) -> str:
    """'m ± sd' over seeds (sample SD), 'm' for one seed, '–' for none."""
    v = np.asarray(values, float)
    if len(v) == 0:
        return "–"
    return f"{v[0]:.{digits}f}" if len(v) == 1 else f"{v.mean():.{digits}f} ± {v.std(ddof=1):.{digits}f}"


def compare(better: list[float], worse: list[float], metric: str, kind: str = "better") -> tuple[str, str]:
    """One metric of a claim: (outcome, text). ``kind='better'``: the first row is claimed better (the paper's
    arrow); 'similar': claimed equal. The noise is the larger of the two rows' sample SDs over seeds (the paper
    calls a gap within one seed SD a match); a gap beyond it in the claimed direction agrees, against it
    disagrees, inside it is within noise ('similar' agrees inside, disagrees beyond). Needs two seeds a row."""
    a, b = np.asarray(better, float), np.asarray(worse, float)
    if len(a) < 2 or len(b) < 2:
        raise ValueError(f"compare: {metric} needs at least two seeds per row, got {len(a)} and {len(b)}")
    gain = (a.mean() - b.mean()) * (1.0 if HIGHER_IS_BETTER[metric] else -1.0)
    noise = max(a.std(ddof=1), b.std(ddof=1))
    if kind == "similar":
        outcome = "agrees" if abs(gain) <= noise else "disagrees"
    else:
        outcome = "within noise" if abs(gain) <= noise else ("agrees" if gain > 0 else "disagrees")
    return outcome, f"{METRIC_NAMES[metric]} {a.mean() - b.mean():+.3g} (noise {noise:.2g}: {outcome})"


@dataclass(frozen=True)
class Claim:
    """One of the paper's claims: comparisons (better row, worse row, metrics, kind) within one table."""

    text: str
    table: str
    comparisons: tuple[tuple[str, str, tuple[str, ...], str], ...]


CLAIMS = (
    Claim("The ensemble connector beats the fixed one at evaluation only", HERMITE.label,
          (("Ensemble, eval. only", "Fixed Hermite", METRICS, "better"),)),
    Claim("Training with the ensemble is at least as good as swapping it in at evaluation (train + eval. ≥ "
          "eval. only)", HERMITE.label, (("Ensemble, train + eval.", "Ensemble, eval. only", METRICS, "better"),)),
    Claim("Target-relative vertices are best within each backbone on Topology-Stress", TOPOLOGY_STRESS.label,
          tuple((f"{b} backbone: vertices", f"{b} backbone: {other}", METRICS, "better")
                for b in ("NeuralParker", "HOPE-style") for other in ("none", "BEV"))),
    Claim("Unified planning has lower path costs than the staged decompositions", TWOSTAGE.label,
          tuple(("Unified NP", staged, PATH_METRICS, "better")
                for staged in ("Hybrid A* → NP", "Hybrid A* → HOPE"))),
    Claim("The geodesic curriculum improves the path metrics at similar success", CURRICULUM.label,
          (("Geodesic curriculum", "No curriculum", PATH_METRICS, "better"),
           ("Geodesic curriculum", "No curriculum", ("success",), "similar"))),
    Claim("NeuralParker is above the adapted HOPE planner on every metric", MAIN_COMPARISON.label,
          (("NeuralParker", "Adapted HOPE", METRICS, "better"),)),
)
"""The paper's claims the report checks (§V-A to §V-D)."""


def claim_verdict(claim: Claim, stats: dict[str, dict[str, list[float]]],
                  seeds_text: dict[str, str] | None = None) -> str:
    """One line: 'agrees', 'disagrees' or 'within noise', with the per-metric gaps; a comparison one of whose rows
    has fewer than two seeds makes it 'not measurable yet (missing: …)', followed by the verdict of the comparisons
    that are measured, if any. Over several metrics and comparisons: any disagreement makes it 'disagrees', all
    agreeing 'agrees', anything else 'within noise'."""
    seeds_text = seeds_text or {}

    def short(label: str) -> bool:
        """The row has fewer than two seeds."""
        return len(stats.get(label, {}).get("success", [])) < 2

    missing = [label for label in dict.fromkeys(x for c in claim.comparisons for x in c[:2]) if short(label)]
    outcomes, texts = [], []
    for better, worse, metrics, kind in claim.comparisons:
        if short(better) or short(worse):
            continue
        parts = [compare(stats[better][m], stats[worse][m], m, kind) for m in metrics]
        outcomes += [o for o, _ in parts]
        texts.append(f"{better} vs {worse}: " + ", ".join(t for _, t in parts))
    verdict = ("disagrees" if "disagrees" in outcomes else "agrees" if set(outcomes) == {"agrees"}
               else "within noise")
    measured = f"{verdict} ({'; '.join(texts)})" if texts else ""
    if not missing:
        return measured
    gap = "not measurable yet (missing: " + "; ".join(
        f"{label}: {seeds_text.get(label, 'fewer than 2 seeds')}" for label in missing) + ")"
    return f"{gap}; measured so far: {measured}" if texts else gap


DIGITS = {"success": 3, "L": 2, "reversals": 2, "delta_kappa": 2}
FIGURE_FILES = {"fig:sceneexamples": "scene_examples.png", "fig:main-comparison": "main_comparison.png",
                "fig:overview": "overview_case.png", "fig:global-family": "global_family.png",
                "fig:hermite-case": "hermite_case.png"}


def table_lines(paper: PaperTable, results: list[ArmResult], stats, cohorts: dict[int, int]) -> list[str]:
    """The side-by-side table (paper | ours per metric) and the cohort line."""
    printed = {row.label: row for row in paper.rows}
    head = " | ".join(f"{METRIC_NAMES[m]} paper | ours" for m in METRICS)
    lines = [f"| Row | Seeds | {head} |", "|---" * (2 + 2 * len(METRICS)) + "|"]
    for r in results:
        cells = []
        for m in METRICS:
            mean_sd = printed[r.arm.label].values[m] if r.arm.label in printed else None
            cells += ["–" if mean_sd is None else f"{mean_sd[0]:.{DIGITS[m]}f} ± {mean_sd[1]:.{DIGITS[m]}f}",
                      fmt(stats[r.arm.label][m], DIGITS[m])]
        lines.append(f"| {r.arm.label} | {r.seeds_text()} | " + " | ".join(cells) + " |")
    ours = "/".join(str(cohorts[s]) for s in sorted(cohorts))
    theirs = "/".join(map(str, paper.cohort)) or "not printed"
    lines += ["", f"Success uses all {paper.episodes_per_seed} episodes per seed; L, Rev. and Δκ the within-seed "
                  f"common-success cohort of the rows measured: n = {ours or '–'}"
                  f"{' (seeds ' + '/'.join(map(str, sorted(cohorts))) + ')' if cohorts else ''}. The paper's "
                  f"cohort, over all its rows: n = {theirs}. Rows not measured yet would shrink our cohort."]
    return lines


def training_hours(configurations, runs: dict) -> float:
    """Wall-clock hours of every epoch the runs of ``configurations`` have trained so far (all seeds)."""
    return sum(epoch_hours(runs[(c, s)].run_dir / "metrics.jsonl") for c in configurations for s in SEEDS)


def compute_line(results: list[ArmResult], runs: dict) -> str:
    """Training CPU-hours, at most (epoch wall times × this machine's cores: runs on fewer threads used fewer) and
    planning CPU-hours."""
    cores = os.cpu_count() or 1
    hours = training_hours(dict.fromkeys(r.arm.configuration for r in results), runs)
    planning_s = sum(row["plan_time_ms"] for r in results for rows in r.records.values() for row in rows) / 1e3
    planning = f"{planning_s / 60:.1f} CPU-min" if planning_s >= 60 else f"{planning_s:.0f} CPU-s"
    return (f"Compute: training {hours:.1f} h wall-clock so far (at most {hours * cores:.1f} CPU-h on this "
            f"{cores}-core machine: a run given every core counts them all, one run on one thread beside another "
            f"counts one; from the runs' `metrics.jsonl` epoch times; runs shared with other tables are counted in "
            f"each), evaluation {planning} of planning (sum of the records' plan times).")


def bar_figure(groups: dict[str, dict[str, list[float]]], metrics, png: Path, title: str) -> bool:
    """Bars of the seed mean with sample-SD error bars and each seed as an open circle, one panel per metric,
    one bar per row; False (and no file) when no row has a seed."""
    groups = {label: values for label, values in groups.items() if any(len(values.get(m, ())) for m in metrics)}
    if not groups:
        return False
    figure = Figure(figsize=(3.2 * len(metrics), 3.6), layout="constrained")
    for ax, m in zip(figure.subplots(1, len(metrics), squeeze=False)[0], metrics):
        for x, (label, values) in enumerate(groups.items()):
            v = np.asarray(values.get(m, ()), float)
            if not len(v):
                continue
            ax.bar(x, v.mean(), yerr=v.std(ddof=1) if len(v) > 1 else 0.0, capsize=4, color=f"C{x}", alpha=0.8)
            ax.plot(np.full(len(v), x), v, "o", mfc="none", color="black")
        ax.set_xticks(range(len(groups)), list(groups), rotation=20, ha="right", fontsize="small")
        ax.set_title(METRIC_NAMES.get(m, m))
    figure.suptitle(title)
    figure.savefig(png, dpi=110)
    return True


def family_success(results: list[ArmResult]) -> dict[str, dict[str, list[float]]]:
    """Per arm, per route-choice family (scene name field 'typeN'), the per-seed success (Fig. 5)."""
    out = {}
    for r in results:
        families = sorted({key[0].split("-")[2] for rows in r.records.values() for key in (row["key"] for row in rows)})
        out[r.arm.label] = {f: [float(np.mean([row["success"] for row in rows if row["key"][0].split("-")[2] == f]))
                                for rows in r.records.values()] for f in families}
    return out


def family_lines(groups: dict[str, dict[str, list[float]]]) -> list[str]:
    """Fig. 5's numbers: per measured row, each route-choice family's success (mean ± sample SD over seeds)."""
    families = ("type1", "type2", "type3")
    measured = {label: values for label, values in groups.items() if any(values.get(f) for f in families)}
    if not measured:
        return []
    lines = ["| Row | Type 1 | Type 2 | Type 3 |", "|---|---|---|---|"]
    lines += [f"| {label} | " + " | ".join(fmt(values.get(f, []), 3) for f in families) + " |"
              for label, values in measured.items()]
    return lines + [""]


def success_values(result: ArmResult, seeds) -> list[float]:
    """``result``'s success rate at each of ``seeds``."""
    return [float(np.mean([row["success"] for row in result.records[s]])) for s in seeds]


def generalisation_lines(test: list[ArmResult], validation: list[ArmResult]) -> list[str]:
    """A table's rows on the frozen test starts beside the validation starts of their training scenes (mean ± sample
    SD over the seeds measured on both) and the gap: a policy that has learned its training scenes but does not carry
    them over to the held-out ones shows a large gap."""
    lines = ["| Row | Seeds | Succ. test scenes | Succ. training scenes (validation starts) | test − training |",
             "|---|---|---|---|---|"]
    for t, v in zip(test, validation):
        seeds = sorted(set(t.records) & set(v.records))
        if not seeds:
            continue
        ours, theirs = success_values(t, seeds), success_values(v, seeds)
        lines.append(f"| {t.arm.label} | {', '.join(map(str, seeds))} | {fmt(ours, 3)} | {fmt(theirs, 3)} | "
                     f"{fmt([a - b for a, b in zip(ours, theirs)], 3)} |")
    if len(lines) == 2:
        return ["No row has a seed measured on both sets yet (" + "; ".join(
            f"{v.arm.label}: {v.seeds_text()}" for v in validation) + ").", ""]
    return lines + [""]


def exact_rule_section(results: dict[str, list[ArmResult]]) -> list[str]:
    """Beyond the paper: each measured row's success under the rule it is scored by (the paper's sampled reference
    point) beside its success when the plan must also pass the exact reference-point rule (`np_sim.validate`, the
    records' ``exact_ref_point_valid``): mean ± sample SD over the seeds whose records carry it."""
    lines = ["## Beyond the paper: successes under the exact rule", "",
             "Every success above is scored as the paper scores it: the reference point collision-free at 30 samples "
             "per arc and 100 per Hermite candidate, the rule each planner checks before it claims success. The exact "
             "rule sweeps the reference point continuously along the arcs and the Hermite cubic "
             "(`np_sim.validate.plan_valid(..., \"exact\", \"reference_point\")`, recorded by every evaluation); a "
             "success that fails it crosses an obstacle edge between two samples. The paper reports only the sampled "
             "rule. Where those crossings lie and how deep they go: [a diagnosis of the Factorial connector rows]"
             "(results/2026-12-07-exact-rule/README.md); what checking 1,000 points per Hermite candidate instead "
             "of 100 changes, on validation starts: [Hermite density](results/2026-12-07-hermite-density/README.md).",
             "",
             "| Row | Seeds | Succ. (sampled rule) | Succ. (also exact) | Successes that pass the exact rule |",
             "|---|---|---|---|---|"]
    measured: dict[tuple[str, str], list[ArmResult]] = {}  # rows of several tables that share their records
    for r in (r for arms in results.values() for r in arms):
        measured.setdefault((r.arm.configuration, r.arm.evaluation), []).append(r)
    for (configuration, evaluation), same in measured.items():
        r = same[0]
        seeds = [s for s in sorted(r.records) if all(row.get("exact") is not None for row in r.records[s])]
        if not seeds:
            continue
        sampled = success_values(r, seeds)
        exact = [float(np.mean([row["success"] * row["exact"] for row in r.records[s]])) for s in seeds]
        labels = " / ".join(dict.fromkeys(x.arm.label for x in same))
        lines.append(f"| {labels} (`{configuration}`, {evaluation}) | {', '.join(map(str, seeds))} | "
                     f"{fmt(sampled, 3)} | {fmt(exact, 3)} | "
                     f"{fmt([e / s if s else float('nan') for e, s in zip(exact, sampled)], 3)} |")
    return lines + [""]


def claim_lines(table_label: str, stats, results: list[ArmResult]) -> list[str]:
    """The verdict line of every claim made on ``table_label``."""
    seeds = {r.arm.label: r.seeds_text() for r in results}
    return [f"- **{c.text}** ({c.table}): {claim_verdict(c, stats, seeds)}" for c in CLAIMS if c.table == table_label]


def measure_all(runs: dict, evaluate: bool, active: dict) -> dict[str, list[ArmResult]]:
    """Every table's arms measured (an arm shared by tables is measured once); ``active``: `active_trainers`."""
    done = {}
    tables = {MAIN_COMPARISON.label: MAIN_COMPARISON, TWOSTAGE.label: TWOSTAGE, TOPOLOGY_STRESS.label:
              TOPOLOGY_STRESS, HERMITE.label: HERMITE, CURRICULUM.label: CURRICULUM}
    out = {}
    for label, arms in ARMS.items():
        out[label] = []
        for arm in arms:
            if arm not in done:
                done[arm] = measure(arm, runs, tables[label].episodes_per_seed, evaluate, active)
            out[label].append(done[arm])
    return out


NOTES = {
    MAIN_COMPARISON.label: "Both rows on the 1,080 frozen Factorial starts: NeuralParker's selected `best.pt` of each "
                           "seed (`python -m experiments.evaluate`), the adapted HOPE's `final.pt` after 10,000 "
                           "episodes (`python -m experiments.planners --methods hope --hope-checkpoint RUN/final.pt`).",
    TWOSTAGE.label: "Our staged rows (`np_policy.staged.StagedPlanner`) hand over the raw Hybrid A* prefix (the "
                    "paper smooths it to continuous curvature where feasible, with the raw path as fallback); Δκ "
                    "sums prefix and downstream and leaves out the single hand-off jump, as the caption says. Records: "
                    "`python -m experiments.planners --methods staged_astar_np --checkpoint RUN/best.pt`.",
    TOPOLOGY_STRESS.label: "All six rows use the fixed connector and the geodesic curriculum "
                           "([sweep.md](sweep.md)). How each row does on its own training scenes, against these "
                           "held-out ones: the table after Fig. 5.",
    HERMITE.label: "Fixed Hermite and Ensemble, eval. only are the same fixed-connector checkpoints, evaluated with "
                   "their own connector and with the ensemble swapped in "
                   "(`python -m experiments.evaluate --checkpoints a.pt [b.pt c.pt] --connector ensemble`, one file "
                   "per seed).",
    CURRICULUM.label: "The rows differ only in the start ordering: without the curriculum the same start pool is "
                      "sampled in full from the first epoch ([sweep.md](sweep.md)).",
}
"""What our rows do differently from, or in more detail than, the paper's text."""


def table_section(paper: PaperTable, results: list[ArmResult], runs: dict) -> list[str]:
    """A table's section: the side-by-side table, a note, its claims and its compute."""
    stats, cohorts = summarise(results)
    return [f"## {paper.number} (`{paper.label}`): {paper.title}", "", *table_lines(paper, results, stats, cohorts),
            "", NOTES[paper.label], "", *claim_lines(paper.label, stats, results), "", compute_line(results, runs),
            ""]


def overview_arguments(runs: dict) -> dict:
    """Fig. 4's ``overview_case.run`` arguments: the paper's Topology-Stress pocket case driven by the vertices policy
    once its run (the sweep's NeuralParker-backbone vertices run, seed 0) is finished, the Factorial stand-in until
    then."""
    run = runs.get(("topology_np_vertices", 0))
    if run is not None and run_state(run).kind == "finished":
        return {"benchmark": "topology", "checkpoint": run.output}
    return {"benchmark": "factorial"}


def overview_text(benchmark: str) -> str:
    """Fig. 4's note: what the case is pinned on, and that the table leaves out the live plan times."""
    pinned = ("The case is the paper's kind: a Topology-Stress pocket (Type 2) training scene driven by the "
              "Topology-Stress vertices policy (rule in `experiments.overview_case`)." if benchmark == "topology" else
              "The paper pins a Topology-Stress pocket case (Type 2) driven by the Topology-Stress vertices policy; "
              "that policy's run is not finished yet, so the case is pinned on a Factorial training scene with the "
              "shipped Factorial checkpoint (rule in `experiments.overview_case`).")
    return (f"{pinned} Plan times are left out here: they are measured live and move with the machine's load; "
            f"`python -m experiments.overview_case --benchmark {benchmark}` prints them.")


def case_sections(work: Path, figures: Path, overview: dict) -> dict[str, list[str]]:
    """Figs. 2, 4 (``overview``: its ``overview_case.run`` arguments) and 6: run the case modules into ``work`` and
    copy their PNGs to ``figures``."""
    made = {"fig:sceneexamples": scenes.run(out=work / "scenes"),
            "fig:overview": overview_case.run(out=work / "overview_case", **overview),
            "fig:hermite-case": hermite_case.run(out=work / "hermite_case")}
    for label, result in made.items():
        shutil.copyfile(result["png"], figures / FIGURE_FILES[label])
    grid = made["fig:sceneexamples"]["scenes"]
    return {
        "fig:sceneexamples": [
            "## Fig. 2 (`fig:sceneexamples`): representative held-out scenes", "",
            f"![scene examples](figures/{FIGURE_FILES['fig:sceneexamples']})", "",
            "Factorial (rows: near, medium, long; columns: reverse, lateral, random; hard difficulty): "
            + ", ".join(f"`{n}`" for row in grid["factorial"] for n in row) + ". Topology-Stress (rows: Types 1–3; "
            "columns: medium, hard): " + ", ".join(f"`{n}`" for row in grid["topology"] for n in row) + ".",
            "", "`python -m experiments.scenes`", ""],
        "fig:overview": [
            "## Fig. 4 (`fig:overview`): unified versus staged planning on one pinned case", "",
            f"![overview case](figures/{FIGURE_FILES['fig:overview']})", "", made["fig:overview"]["path_table"], "",
            made["fig:overview"]["comparison"] + " " + overview_text(overview["benchmark"]), ""],
        "fig:hermite-case": [
            "## Fig. 6 (`fig:hermite-case`): both connectors from one shared hand-off", "",
            f"![hermite case](figures/{FIGURE_FILES['fig:hermite-case']})", "", made["fig:hermite-case"]["table"], "",
            "The paper's claim for this figure, that both connectors are feasible from the hand-off and the ensemble "
            "picks another terminal shape, holds here by construction of the pick (rule in "
            "`experiments.hermite_case`, on a training scene). `python -m experiments.hermite_case`", ""],
    }


def bar_section(paper: PaperTable, number_title: str, groups, metrics, png: Path, note: str) -> list[str]:
    """A bar figure's section: the figure when any row is measured, else what is missing."""
    lines = [f"## {paper.number} (`{paper.label}`): {number_title}", ""]
    if bar_figure(groups, metrics, png, f"{paper.number}: ours (mean ± sample SD; circles: seeds)"):
        lines += [f"![{paper.label}](figures/{png.name})", ""]
    return lines + [note, ""]


def status_lines(results: dict[str, list[ArmResult]]) -> list[str]:
    """One row per arm: which tables it feeds and its seeds."""
    feeds: dict[Arm, list[str]] = {}
    by_arm = {}
    for label, arms in results.items():
        for r in arms:
            feeds.setdefault(r.arm, []).append(label)
            by_arm[r.arm] = r
    lines = ["| Row (configuration, evaluation) | Feeds | Seeds | Shared geometry branch |", "|---|---|---|---|"]
    for arm, r in by_arm.items():
        lines.append(f"| {arm.label} (`{arm.configuration}`, {arm.evaluation}) | "
                     f"{', '.join(f'`{t}`' for t in feeds[arm])} | {r.seeds_text()} | {r.shared_geometry_text()} |")
    return lines


def generalisation_section(results: dict[str, list[ArmResult]], runs: dict, evaluate: bool, active: dict) -> list[str]:
    """Beyond the paper: each `GENERALISATION_TABLES` row's success on the frozen test starts beside its success on
    the validation starts of its training scenes (``eval_<benchmark>_validation``, evaluated here when missing)."""
    lines = ["## Beyond the paper: test scenes against training scenes", "",
             f"Each row's success on the frozen test starts beside its success on validation starts on its training "
             f"scenes (`np_sim.benchmarks.validation_starts`: the frozen-start protocol with seed 1, "
             f"{VALIDATION_STARTS_PER_SCENE} per scene; `python -m experiments.evaluate --split validation "
             "--checkpoints PATH`, and for the HOPE rows `python -m experiments.planners --split validation --methods "
             "hope --hope-checkpoint PATH`). The test scenes are structurally disjoint from the training scenes; the "
             "paper reports only the test side.", ""]
    for table in GENERALISATION_TABLES:
        episodes = validation_episodes(table.benchmark)
        test = results[table.label]
        validation = [measure(Arm(r.arm.label, r.arm.configuration, "validation"), runs, episodes, evaluate, active)
                      for r in test]
        lines += [f"**{table.number}** ({table.benchmark}: {table.episodes_per_seed} test starts, {episodes} "
                  "validation starts per seed):", "", *generalisation_lines(test, validation)]
    return lines


HOPE_ACTION_ROWS = ((MAIN_COMPARISON, "Adapted HOPE", "mean"), (TWOSTAGE, "Hybrid A* → HOPE", "staged_mean"))
"""The adapted-HOPE rows measured again with the mean action: (their table, their label, that evaluation)."""


def paper_success(table: PaperTable, label: str) -> str:
    """The paper's success of row ``label`` of ``table``, or, for a bar figure, the least success its caption's
    common-success cohort implies per seed."""
    row = next((r for r in table.rows if r.label == label), None)
    if row is not None:
        mean, sd = row.values["success"]
        return f"{mean:.3f} ± {sd:.3f}"
    bounds = " / ".join(f"{n / table.episodes_per_seed:.2f}" for n in table.cohort)
    return f"bars only; its cohort implies ≥ {bounds}"


def hope_action_section(results: dict[str, list[ArmResult]], runs: dict, evaluate: bool, active: dict) -> list[str]:
    """Beyond the paper: the adapted-HOPE rows played with the policy's mean action (the most probable masked
    anchor) beside the report's `HOPE_ACTION` rows (``eval_<benchmark>_mean`` and ``_staged_mean`` folders,
    evaluated here when missing), with the NeuralParker row they are compared with."""
    lines = ["## Beyond the paper: the adapted HOPE's action at evaluation", "",
             "The paper does not say how its adapted HOPE picks actions when it is evaluated; HOPE's own evaluation "
             f"code samples them, and so do the report's rows above ({HOPE_ACTION}). The same checkpoints played "
             "with the mean action (the most probable anchor under the mask; `python -m experiments.planners "
             "--methods hope --hope-action mean --hope-checkpoint PATH`):", "",
             "| Row | Seeds | Succ., sampled actions | Succ., mean action | Paper |", "|---|---|---|---|---|"]
    for table, label, evaluation in HOPE_ACTION_ROWS:
        sampled = next(r for r in results[table.label] if r.arm.label == label)
        mean = measure(Arm(label, sampled.arm.configuration, evaluation), runs, table.episodes_per_seed, evaluate,
                       active)
        seeds = sorted(set(sampled.records) & set(mean.records))
        if not seeds:
            lines.append(f"| {label} ({table.number}) | – | {sampled.seeds_text()} | {mean.seeds_text()} | "
                         f"{paper_success(table, label)} |")
            continue
        lines.append(f"| {label} ({table.number}) | {', '.join(map(str, seeds))} | "
                     f"{fmt(success_values(sampled, seeds), 3)} | {fmt(success_values(mean, seeds), 3)} | "
                     f"{paper_success(table, label)} |")
    reference = results[MAIN_COMPARISON.label][0]
    if reference.records:
        seeds = sorted(reference.records)
        lines.append(f"| {reference.arm.label} (mean action, as every NeuralParker row) | "
                     f"{', '.join(map(str, seeds))} | – | {fmt(success_values(reference, seeds), 3)} | "
                     f"{paper_success(TWOSTAGE, 'Unified NP')} |")
    return lines + ["", "Under sampling the trained actor matters little: the first training batch of "
                    "`factorial_hope_seed0`, before any update, already parked 0.64 of its episodes (`metrics.jsonl`, "
                    "update 1); sampled actions keep exploring until the attached terminators (the Reeds–Shepp "
                    "takeover within 10 m, the Hermite candidates) connect, and the mean action takes that "
                    "exploration away. The paper does not state which mode it played, so both are shown; the claim "
                    "lines above use the sampled rows.", ""]


def validation_episodes(benchmark: str) -> int:
    """Episodes per seed of a validation evaluation: the training scenes × `VALIDATION_STARTS_PER_SCENE`."""
    return len(load_benchmark(benchmark, "train")) * VALIDATION_STARTS_PER_SCENE


def build_report(runs_root: Path, out_md: Path, evaluate: bool = True) -> str:
    """Measure every arm, run the case figures and write the report to ``out_md`` (figures beside it)."""
    runs = {(r.config.name, r.seed): r for r in expand(PAPER_PLAN, SEEDS, runs_root)}
    active = active_trainers()
    figures = out_md.parent / "figures"
    figures.mkdir(parents=True, exist_ok=True)
    results = measure_all(runs, evaluate, active)
    cases = case_sections(run_folder("paper", None), figures, overview_arguments(runs))
    main = results[MAIN_COMPARISON.label]
    main_stats, main_cohorts = summarise(main)
    topo = results[TOPOLOGY_STRESS.label]
    lines = ["# Reproduction report", "",
             "Generated by `python -m experiments.paper` from the run folders under `checkpoints/runs/` (no "
             "training): the paper's printed numbers beside ours, the seeds each row has, and a verdict on each of "
             "the paper's claims. Ours: three-seed mean ± sample SD where seeds exist (one seed: its value); "
             "success on the full set of frozen test starts, path metrics on the within-seed common-success cohort "
             "of the rows measured. NeuralParker rows play the policy's mean action (the paper's deterministic "
             "rollout); adapted-HOPE rows play HOPE's own evaluation protocol, sampled actions (the masked anchor "
             "draw, or the clipped Gaussian sample where the mask is off) seeded per start. "
             "A claim is checked only when every row it compares has at least two seeds; a "
             "gap within the larger seed SD of the two rows is 'within noise'. Which runs are still missing and "
             "how to train them: [sweep.md](sweep.md). The rows table's last column names the seeds trained with "
             "`np_policy.train --shared-geometry`: the same recipe and network, the geometry branch computed once "
             "per distinct scene, so another float summation order ([its check](results/2026-12-06-shared-geometry.md)"
             ").", "",
             "Regenerate with `python -m experiments.paper` (about a minute here when the evaluation records exist; "
             "a finished run without records is evaluated first, about five minutes per seed and evaluation on this "
             "2-core machine; `--no-evaluate` skips that). The single figures: `python -m experiments.scenes`, "
             "`python -m experiments.overview_case`, `python -m experiments.hermite_case`.", "",
             "## Rows and their seeds", "", *status_lines(results),
             "", "## Claims", ""]
    claims_stats = {label: summarise(arms)[0] for label, arms in results.items()}
    for label in ARMS:
        lines += claim_lines(label, claims_stats[label], results[label])
    lines += ["", *cases["fig:sceneexamples"]]
    lines += bar_section(MAIN_COMPARISON, "NeuralParker versus the adapted HOPE planner",
                         {r.arm.label: main_stats[r.arm.label] for r in main}, METRICS,
                         figures / FIGURE_FILES[MAIN_COMPARISON.label],
                         "The paper draws this comparison as bars only (pairwise cohort n = "
                         f"{'/'.join(map(str, MAIN_COMPARISON.cohort))}). Ours:")
    lines += [*table_lines(MAIN_COMPARISON, main, main_stats, main_cohorts), "",
              *claim_lines(MAIN_COMPARISON.label, main_stats, main), ""]
    lines += table_section(TWOSTAGE, results[TWOSTAGE.label], runs) + cases["fig:overview"]
    lines += table_section(TOPOLOGY_STRESS, topo, runs)
    lines += bar_section(GLOBAL_FAMILY, "family-level success on Topology-Stress", family_success(topo),
                         ("type1", "type2", "type3"), figures / FIGURE_FILES[GLOBAL_FAMILY.label],
                         "The paper draws per-family success (240 episodes per family and seed) as bars only. "
                         + ("Ours:" if any(r.records for r in topo) else "Not measurable yet: no Topology-Stress row "
                            "has a seed (" + "; ".join(f"{r.arm.label}: {r.seeds_text()}" for r in topo) + ")."))
    lines += family_lines(family_success(topo))
    lines += generalisation_section(results, runs, evaluate, active)
    lines += hope_action_section(results, runs, evaluate, active)
    lines += table_section(HERMITE, results[HERMITE.label], runs) + cases["fig:hermite-case"]
    lines += table_section(CURRICULUM, results[CURRICULUM.label], runs)
    lines += exact_rule_section(results)
    text = "\n".join(lines).rstrip() + "\n"
    out_md.write_text(text)
    return text


def report_file(text: str) -> Path:
    """The report's path: a Markdown file name (``.md``) that is not a folder (refused at parse time otherwise)."""
    path = Path(text)
    if path.suffix != ".md" or path.is_dir():
        raise argparse.ArgumentTypeError(f"expected a Markdown file path ending in .md, got {text}")
    return path


def run_root(text: str) -> Path:
    """An existing folder of run folders (refused at parse time otherwise)."""
    path = Path(text)
    if not path.is_dir():
        raise argparse.ArgumentTypeError(f"expected an existing folder of run folders, got {text}")
    return path


@cli_boundary
def main(argv=None) -> str:
    """Command-line entry point (usage in the module docstring)."""
    parser = argparse.ArgumentParser(prog="python -m experiments.paper", description=__doc__,
                                     formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--out", type=report_file, default=Path("docs/reproduction.md"),
                        help="the report (Markdown; default docs/reproduction.md; figures go to figures/ beside it)")
    parser.add_argument("--runs", type=run_root, default=Path("checkpoints/runs"),
                        help="run root of the sweep (default checkpoints/runs)")
    parser.add_argument("--no-evaluate", action="store_true",
                        help="do not evaluate finished runs that have no records; report them as not evaluated")
    args = parser.parse_args(argv)
    text = build_report(args.runs, args.out, evaluate=not args.no_evaluate)
    print(f"wrote {args.out}")
    return text


if __name__ == "__main__":
    main()
