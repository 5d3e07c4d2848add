"""Fig. 3 (``fig:main-comparison``): NeuralParker versus the adapted HOPE planner on the Factorial
Parking Benchmark (paper §V-A), from the sweep's run folders.

Usage, outputs and how the rows are read: `experiments.paper_table`.
"""

from __future__ import annotations

from experiments.paper_numbers import MAIN_COMPARISON
from experiments.paper_table import table_cli

main = table_cli(MAIN_COMPARISON, "main_comparison", __doc__)

if __name__ == "__main__":
    main()
