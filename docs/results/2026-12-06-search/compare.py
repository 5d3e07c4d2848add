"""Per-run summary of the closed-loop runs in this folder against the anytime preset's runs of the same clips
(`../2026-12-06-guarded/`): footprint and reference-point successes, failure reasons, planner calls by stage and
the median / 90th percentile of all calls, and the clips each variant gained or lost.

    python docs/results/2026-12-06-search/compare.py
"""

import csv
import gzip
import json
from collections import Counter
from pathlib import Path

import numpy as np

HERE = Path(__file__).parent
PRESET = HERE.parent / "2026-12-06-guarded"
STAGES = ("mean", "search", "sampled", "rescue", "")


def load(folder: Path, *names: str) -> dict[str, dict]:
    rows = {}
    for name in names:
        with gzip.open(folder / f"{name}.csv.gz", "rt") as f:
            rows.update({r["clip"]: r for r in csv.DictReader(f)})
    return rows


def summary(label: str, runs: dict[str, dict], reference: dict[str, dict] | None) -> str:
    times = np.array([t for r in runs.values() for t in json.loads(r["plan_times_ms"])])
    stages = Counter(s for r in runs.values() for s in json.loads(r["plan_stages"].replace("'", '"')))
    failures = Counter(r["reason"] for r in runs.values() if r["footprint_success"] == "0")
    line = (f"{label}: footprint {sum(int(r['footprint_success']) for r in runs.values())} of {len(runs)} "
            f"(ref. point {sum(int(r['reference_point_success']) for r in runs.values())}), failures {dict(failures)}; "
            f"{len(times)} calls, mean / search / sampled / rescue / failed "
            f"{' / '.join(str(stages[s]) for s in STAGES)}, median {np.median(times):.1f} ms, "
            f"p90 {np.percentile(times, 90):.1f} ms")
    if reference is not None:
        gained = [c for c in runs if runs[c]["footprint_success"] > reference[c]["footprint_success"]]
        lost = [c for c in runs if runs[c]["footprint_success"] < reference[c]["footprint_success"]]
        line += f"; gained {', '.join(gained) or '-'}; lost {', '.join(lost) or '-'}"
    return line


def main() -> None:
    first, following = load(PRESET, "first94_without"), load(PRESET, "next94_without")
    print(summary("footprint_anytime, first 94", first, None))
    print(summary("footprint_anytime, next 94", following, None))
    for name in ("first94_search_steer0.1", "first94_search_start_limited_steer0.1",
                 "first94_search_start_limited_aligned_steer0.1", "first94_footprint_search"):
        print(summary(name, load(HERE, name), first))
    for name in ("next94_search_start_limited_steer0.1", "next94_footprint_search"):
        print(summary(name, load(HERE, name), following))
    held = load(HERE, "heldout_footprint_anytime_same_session")
    print(summary("held out, footprint_anytime (same session)", held, None))
    for name in ("heldout_footprint_search_steer0.1", "heldout_footprint_search"):
        print(summary(f"held out, {name}", load(HERE, name), held))


if __name__ == "__main__":
    main()
