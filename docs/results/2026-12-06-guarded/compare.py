"""Per-clip comparison of the closed-loop runs in this folder: footprint successes of each variant on the 188
difficult training clips (first 94 + next 94), and the runs the guarded rollout gained or lost.

    python docs/results/2026-12-06-guarded/compare.py
"""

import csv
import gzip
from pathlib import Path

HERE = Path(__file__).parent


def load(*names: str) -> dict[str, dict]:
    rows = {}
    for name in names:
        with gzip.open(HERE / f"{name}.csv.gz", "rt") as f:
            rows.update({r["clip"]: r for r in csv.DictReader(f)})
    return rows


def main() -> None:
    without = load("first94_without", "next94_without")
    variants = {"guarded, first park": load("first94_guarded_first_park", "next94_guarded_first_park"),
                "guarded, aligned park first": load("all188_guarded_aligned"),
                "anytime test requires an aligned end": load("all188_accept_aligned"),
                "aligned end + guarded": load("all188_accept_aligned_guarded")}
    clips = list(without)
    print(f"without (the preset): {sum(int(without[c]['footprint_success']) for c in clips)} of {len(clips)}")
    for name, runs in variants.items():
        gained = [c for c in clips if runs[c]["footprint_success"] > without[c]["footprint_success"]]
        lost = [c for c in clips if runs[c]["footprint_success"] < without[c]["footprint_success"]]
        print(f"{name}: {sum(int(runs[c]['footprint_success']) for c in clips)} of {len(clips)}; "
              f"gained {', '.join(gained) or '-'}; lost {', '.join(lost) or '-'}")


if __name__ == "__main__":
    main()
