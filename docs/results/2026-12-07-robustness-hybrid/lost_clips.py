"""Which clips each learned row and Hybrid A* lose under one factor, against their own undisturbed runs: per level the
clips parked undisturbed and lost there (with the reason and the undisturbed run's sim time) and the clips won.
Reads this folder's records.csv and the 2026-12-02 study's (same clips, seed and draws).

    python docs/results/2026-12-07-robustness-hybrid/lost_clips.py [FACTOR]     # default detection_noise
"""

import csv
import sys
from pathlib import Path

HERE = Path(__file__).parent
EARLIER = HERE.parent / "2026-12-02-robustness" / "records.csv"
PLANNERS = ("neuralparker_footprint", "neuralparker_search", "hybrid_astar")


def parked(row: dict) -> bool:
    return row["footprint_success"] == "1"


def report(rows: list[dict], factor: str, planner: str) -> list[str]:
    """Lines for one planner: its undisturbed count, then per level the clips lost and won against it."""
    base = {r["clip"]: r for r in rows if r["planner"] == planner and r["factor"] == "none"}
    lines = [f"{planner}: {sum(map(parked, base.values()))} of {len(base)} parked undisturbed"]
    for level in ("mild", "moderate", "severe"):
        runs = {r["clip"]: r for r in rows if r["planner"] == planner and r["factor"] == factor and r["level"] == level}
        lost = [f"{c} {runs[c]['reason']} ({float(base[c]['sim_time_s']):.1f} s undisturbed)"
                for c in sorted(base) if parked(base[c]) and not parked(runs[c])]
        won = [c for c in sorted(base) if not parked(base[c]) and parked(runs[c])]
        timeouts = sum("timeout" in entry for entry in lost)
        lines.append(f"  {level}: {sum(map(parked, runs.values()))} parked; lost {len(lost)} ({timeouts} timeouts): "
                     f"{', '.join(lost) or '-'}; won: {', '.join(won) or '-'}")
    return lines


def main(argv: list[str]) -> None:
    factor = argv[0] if argv else "detection_noise"
    rows = [row for path in (EARLIER, HERE / "records.csv") for row in csv.DictReader(path.open())]
    for planner in PLANNERS:
        print("\n".join(report(rows, factor, planner)))


if __name__ == "__main__":
    main(sys.argv[1:])
