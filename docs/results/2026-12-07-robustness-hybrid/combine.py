"""The learned-first hybrid's robustness rows (this folder's records.csv) beside the 2026-12-02 study's four planners
(same clips, factors, levels and seed, so the same disturbance draws): writes table.md here and prints it.

    python docs/results/2026-12-07-robustness-hybrid/combine.py
"""

import csv
from pathlib import Path

from experiments.robustness_report import format_table
from tracking.disturbance import FACTORS

HERE = Path(__file__).parent
EARLIER = HERE.parent / "2026-12-02-robustness" / "records.csv"
PLANNERS = ["neuralparker", "neuralparker_footprint", "neuralparker_search", "np_guided_astar", "hybrid_astar"]


def main() -> None:
    rows = [row for path in (EARLIER, HERE / "records.csv") for row in csv.DictReader(path.open())]
    table = format_table(rows, list(FACTORS), PLANNERS)
    (HERE / "table.md").write_text(table + "\n")
    print(table)


if __name__ == "__main__":
    main()
