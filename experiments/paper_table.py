"""One of the paper's simulation tables as its own experiment: the shared driver of `experiments.main_comparison`
(Fig. 3), `experiments.staged` (Table II), `experiments.representation` (Table III and Fig. 5),
`experiments.connector` (Table IV) and `experiments.curriculum` (Table V).

``python -m experiments.<table> [--runs checkpoints/runs] [--out DIR] [--no-evaluate]``

Each reads the table's rows from the sweep's run folders exactly as the reproduction report does
(`experiments.paper.measure`: a finished run's frozen-start records, evaluated first when a finished run has none,
its evaluation CLI replaying every frozen start), prints the table in the paper's form (success on the full set, L,
reversals and Δκ on the within-seed common-success cohort of the rows measured, three-seed mean ± sample SD beside
the paper's printed numbers, the seeds each row has, the table's claims and its compute) and writes a fresh
``results/<table>/<timestamp>/`` (spec §9): ``table.md``, ``records.csv``/``records.json`` (one row per row of the
table, seed and episode), ``config.json`` and a bar figure of the rows (mean ± sample SD, each seed a circle;
Table III adds the per-family Fig. 5). ``python -m experiments.paper`` puts every table into one report.
"""

from __future__ import annotations

import argparse
import json
from collections.abc import Callable
from pathlib import Path
from typing import Any

from experiments.common import run_folder, write_records
from experiments.paper import (ARMS, HOPE_ACTION, SEEDS, ArmResult, bar_figure, family_lines, family_success,
                               measure, run_root, summarise, table_section)
from experiments.paper_numbers import METRICS, PaperTable
from experiments.sweep_plan import PAPER_PLAN, active_trainers, expand
from np_sim.cli import cli_boundary, fresh_folder
from np_sim.provenance import provenance

HOW = __doc__[__doc__.index("Each reads"):]
"""What every table module does, for its ``--help``."""

ExtraFigure = Callable[[list[ArmResult], Path], list[str]]
"""``figure(results, folder) -> lines``: writes more PNGs of a table into its run folder; Markdown lines for them."""


def episode_records(results: list[ArmResult]) -> list[dict[str, Any]]:
    """One record per table row, seed and frozen episode (spec §9's columns)."""
    return [{"row": r.arm.label, "configuration": r.arm.configuration, "evaluation": r.arm.evaluation, "seed": seed,
             "scene": row["key"][0], "start_id": row["key"][1], "success": row["success"], "reason": row["reason"],
             "L": row["L"], "reversals": row["reversals"], "delta_kappa": row["delta_kappa"],
             "plan_time_ms": row["plan_time_ms"]}
            for r in results for seed, rows in sorted(r.records.items()) for row in rows]


def run(paper: PaperTable, experiment: str, runs_root: Path = Path("checkpoints/runs"), out: Path | None = None,
        evaluate: bool = True, extra_figure: ExtraFigure | None = None) -> dict[str, Any]:
    """Measure ``paper``'s rows on the runs under ``runs_root`` and write the run folder (module docstring);
    returns the per-row results, the table text and the folder."""
    runs = {(r.config.name, r.seed): r for r in expand(PAPER_PLAN, SEEDS, runs_root)}
    active = active_trainers()
    results = [measure(arm, runs, paper.episodes_per_seed, evaluate, active) for arm in ARMS[paper.label]]
    folder = run_folder(experiment, out)
    stats, _ = summarise(results)
    lines = table_section(paper, results, runs)
    png = folder / f"{experiment}.png"
    if bar_figure({r.arm.label: stats[r.arm.label] for r in results}, METRICS, png,
                  f"{paper.number}: ours (mean ± sample SD; circles: seeds)"):
        lines += [f"![{paper.label}]({png.name})", ""]
    if extra_figure is not None:
        lines += extra_figure(results, folder)
    table = "\n".join(lines).rstrip() + "\n"
    (folder / "table.md").write_text(table)
    records = episode_records(results)
    if records:
        write_records(folder, records)
    (folder / "config.json").write_text(json.dumps({
        "table": paper.label, "runs": str(runs_root), "evaluate": evaluate, "hope_action": HOPE_ACTION,
        "rows": {r.arm.label: {"configuration": r.arm.configuration, "evaluation": r.arm.evaluation,
                               "seeds": r.seeds_text()} for r in results},
        **provenance()}, indent=2))
    return {"results": results, "table": table, "folder": folder}


def family_figure(results: list[ArmResult], folder: Path) -> list[str]:
    """Fig. 5 (`fig:global-family`): per-family success of the Topology-Stress rows, when any row has a seed."""
    png = folder / "global_family.png"
    if bar_figure(family_success(results), ("type1", "type2", "type3"), png,
                  "Fig. 5: family-level success, ours (mean ± sample SD; circles: seeds)"):
        return [f"![fig:global-family]({png.name})", "", *family_lines(family_success(results))]
    return []


def table_cli(paper: PaperTable, experiment: str, doc: str,
              extra_figure: ExtraFigure | None = None) -> Callable[..., dict[str, Any]]:
    """The ``main(argv=None)`` of the table module ``experiments.<experiment>`` (usage in the module docstring)."""

    @cli_boundary
    def main(argv=None) -> dict[str, Any]:
        parser = argparse.ArgumentParser(prog=f"python -m experiments.{experiment}",
                                         description=f"{doc.split('Usage, outputs')[0]}"
                                         f"python -m experiments.{experiment} [--runs DIR] [--out DIR] "
                                         f"[--no-evaluate]\n\n{HOW}",
                                         formatter_class=argparse.RawDescriptionHelpFormatter)
        parser.add_argument("--runs", type=run_root, default=Path("checkpoints/runs"),
                            help="run root of the sweep (default checkpoints/runs)")
        parser.add_argument("--out", type=fresh_folder,
                            help=f"new or empty run folder (default: a fresh results/{experiment}/<timestamp>)")
        parser.add_argument("--no-evaluate", action="store_true",
                            help="do not evaluate finished runs that have no records; report them as not evaluated")
        args = parser.parse_args(argv)
        result = run(paper, experiment, args.runs, args.out, not args.no_evaluate, extra_figure)
        print(result["table"], end="")
        print(f"written: {result['folder']}")
        return result

    return main
