"""Apply the shared-geometry adoption rule fixed in ../2026-12-06-shared-geometry.md to the records on disk.

Rule: the check run (``factorial_np`` seed 0 trained with ``--shared-geometry``) is adopted if its success on the
1,080 frozen Factorial starts is at least the three seeds' mean minus two sample SDs (the seeds trained without the
flag), and at least 0.963, the figure the rule wrote down from the rounded 0.985 ± 0.011 (the exact mean minus two
SDs is 0.9620; the stricter of the two applies). Printed for information beside it: success on the validation starts of the training scenes, and the path
metrics of each run on the common-success cohort of all four runs, and each run's training curve in four windows of
60 epochs (mean ``train_success`` of its ``metrics.jsonl`` rows).

    python docs/results/2026-12-06-shared-geometry/check_rule.py [--runs checkpoints/runs]
"""

from __future__ import annotations

import argparse
import csv
import json
import math
from pathlib import Path
from statistics import mean, stdev

SEEDS = ("factorial_np_seed0_lot", "factorial_np_seed1_lot", "factorial_np_seed2_lot")
CHECK = "factorial_np_seed0_shared_geometry"
WRITTEN_FLOOR = 0.963
SPLITS = {"test": ("eval_factorial", 1080), "validation": ("eval_factorial_validation", 810)}
PATH_METRICS = ("L", "reversals", "delta_kappa")


def records(run: Path, split: str) -> dict[tuple[str, str], dict]:
    """The run's per-start records of ``split``, keyed by (scene, start_id); refuses a wrong episode count."""
    folder, episodes = SPLITS[split]
    path = run / folder / "records.csv"
    with path.open() as f:
        rows = {(r["scene"], r["start_id"]): r for r in csv.DictReader(f)}
    if len(rows) != episodes:
        raise SystemExit(f"error: {path}: {len(rows)} episodes, expected {episodes}")
    return rows


def success(rows: dict) -> float:
    return mean(int(r["success"]) for r in rows.values())


def curve_windows(run: Path, width: int = 60) -> list[float]:
    """Mean training success over epochs 1–60, 61–120, 121–180, 181–240 of the run's ``metrics.jsonl``."""
    rows = [json.loads(line) for line in (run / "metrics.jsonl").read_text().splitlines() if line.strip()]
    success = {int(r["epoch"]): float(r["train_success"]) for r in rows}
    return [mean(success[e] for e in range(a, a + width) if e in success) for a in range(1, 241, width)]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    parser.add_argument("--runs", type=Path, default=Path("checkpoints/runs"))
    root = parser.parse_args().runs
    for split in SPLITS:
        seeds = [records(root / name, split) for name in SEEDS]
        check = records(root / CHECK, split)
        values = [success(rows) for rows in seeds]
        m, sd = mean(values), stdev(values)
        print(f"{split}: seeds without the flag {' / '.join(f'{v:.4f}' for v in values)} "
              f"(mean {m:.4f} ± {sd:.4f}); check run {success(check):.4f}")
        if split == "test":
            floor = max(m - 2 * sd, WRITTEN_FLOOR)
            verdict = "adopted" if success(check) >= floor else "not adopted"
            print(f"rule: check run's test success {success(check):.4f} against max(mean - 2 SD = {m - 2 * sd:.4f}, "
                  f"written {WRITTEN_FLOOR}): {verdict}")
        cohort = set.intersection(*({k for k, r in rows.items() if r["success"] == "1"} for rows in seeds + [check]))
        for metric in PATH_METRICS:
            per_seed = [mean(float(rows[k][metric]) for k in cohort) for rows in seeds]
            ours = mean(float(check[k][metric]) for k in cohort)
            spread = stdev(per_seed) if len(per_seed) > 1 else math.nan
            print(f"  {metric} on the common-success cohort (n = {len(cohort)}): seeds {mean(per_seed):.3f} ± "
                  f"{spread:.3f}, check run {ours:.3f}")
    print("training success, mean over epochs 1-60 / 61-120 / 121-180 / 181-240:")
    for name in (*SEEDS, CHECK):
        print(f"  {name}: " + " / ".join(f"{v:.3f}" for v in curve_windows(root / name)))


if __name__ == "__main__":
    main()
