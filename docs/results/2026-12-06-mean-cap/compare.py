"""The search hybrid with its plain mean rollout capped at 50 arcs (`mean_capped`) against the target-capped preset
on the same 188 difficult training clips (`../2026-12-06-target-cap/`): successes, failure reasons, calls by stage,
the median / 90th percentile of all calls (beside training runs: counts compare, times do not) and the clips gained
or lost.

    python docs/results/2026-12-06-mean-cap/compare.py
"""

import importlib.util
from pathlib import Path

HERE = Path(__file__).parent
BEFORE = HERE.parent / "2026-12-06-target-cap"
_spec = importlib.util.spec_from_file_location("search_compare", HERE.parent / "2026-12-06-search" / "compare.py")
search_compare = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(search_compare)


def main() -> None:
    for half in ("first94", "next94"):
        before = search_compare.load(BEFORE, f"{half}_target_cap")
        print(search_compare.summary(f"{half}, footprint_search before the mean cap", before, None))
        print(search_compare.summary(f"{half}_meancap", search_compare.load(HERE, f"{half}_meancap"), before))


if __name__ == "__main__":
    main()
