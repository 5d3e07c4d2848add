"""Per-run summary of the target-capped runs in this folder against the `footprint_search` runs of the same clips
before the cap (`../2026-12-06-search/`), and of the learned row with both caps against its preset: successes,
failure reasons, calls by stage, and the clips gained or lost.

    python docs/results/2026-12-06-target-cap/compare.py
"""

import importlib.util
from pathlib import Path

HERE = Path(__file__).parent
BEFORE = HERE.parent / "2026-12-06-search"
_spec = importlib.util.spec_from_file_location("search_compare", BEFORE / "compare.py")
search_compare = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(search_compare)


def main() -> None:
    for half in ("first94", "next94"):
        before = search_compare.load(BEFORE, f"{half}_footprint_search")
        print(search_compare.summary(f"{half}, footprint_search before the target cap", before, None))
        for name in (f"{half}_target_cap", f"{half}_target_cap_grid0.5"):
            print(search_compare.summary(name, search_compare.load(HERE, name), before))
        preset = search_compare.load(search_compare.PRESET, f"{half}_without")
        print(search_compare.summary(f"{half}, footprint_anytime (the learned row)", preset, None))
        capped = search_compare.load(HERE, f"{half}_learned_row_both_caps")
        print(search_compare.summary(f"{half}_learned_row_both_caps", capped, preset))


if __name__ == "__main__":
    main()
