"""Table III (Topology-Stress scene-representation ablation) for seed 0 of each of the six configurations, from the
run folders' frozen-start records, beside the paper's three-seed means: success over the 720 episodes, L / Rev. /
Δκ over the episodes every available row parks (the seed-0 common-success cohort). Writes ``table.md`` here.

    python docs/results/2026-12-06-table3-seed0/make.py
"""

import csv
import math
from pathlib import Path

from experiments.paper_numbers import TOPOLOGY_STRESS

HERE = Path(__file__).parent
RUNS = Path("checkpoints/runs")
FOLDERS = {"NeuralParker backbone: none": "topology_np_none_seed0_lot",
           "NeuralParker backbone: BEV": "topology_np_bev_seed0_lot",
           "NeuralParker backbone: vertices": "topology_np_vertices_seed0_lot",
           "HOPE-style backbone: none": "topology_hope_none_seed0",
           "HOPE-style backbone: BEV": "topology_hope_bev_seed0",
           "HOPE-style backbone: vertices": "topology_hope_vertices_seed0"}
METRICS = ("L", "reversals", "delta_kappa")


def records(folder: str) -> dict[tuple[str, str], dict] | None:
    path = RUNS / folder / "eval_topology" / "records.csv"
    if not path.exists():
        return None
    with path.open() as f:
        return {(r["scene"], r["start_id"]): r for r in csv.DictReader(f)}


def main() -> None:
    rows = {label: records(folder) for label, folder in FOLDERS.items()}
    present = {label: recs for label, recs in rows.items() if recs is not None}
    cohort = set.intersection(*({k for k, r in recs.items() if r["success"] == "1"} for recs in present.values()))
    paper = {row.label: row.values for row in TOPOLOGY_STRESS.rows}
    lines = [f"Seed 0 of each row; success over 720 episodes, L / Rev. / Δκ over the {len(cohort)} episodes all "
             f"{len(present)} rows with records park. Paper: three-seed mean ± SD, its cohort n = 328/317/281.", "",
             "| Row | Succ. (ours, seed 0) | Succ. (paper) | L (m) | paper | Rev. | paper | Δκ | paper |",
             "|---|---|---|---|---|---|---|---|---|"]
    for label, recs in rows.items():
        p = paper[label]
        if recs is None:
            paper_success = f"{p['success'][0]:.3f} ± {p['success'][1]:.3f}"
            lines.append(f"| {label} | not evaluated | {paper_success} | – | | – | | – | |")
            continue
        success = sum(r["success"] == "1" for r in recs.values()) / len(recs)
        means = [sum(float(recs[k][m]) for k in cohort) / len(cohort) if cohort else math.nan for m in METRICS]
        cells = " | ".join(f"{v:.2f} | {p[m][0]:.2f} ± {p[m][1]:.2f}" for v, m in zip(means, METRICS))
        lines.append(f"| {label} | {success:.3f} | {p['success'][0]:.3f} ± {p['success'][1]:.3f} | {cells} |")
    text = "\n".join(lines) + "\n"
    (HERE / "table.md").write_text(text)
    print(text)


if __name__ == "__main__":
    main()
