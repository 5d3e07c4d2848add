"""Table II (``tab:twostage``): unified NeuralParker versus the staged decompositions Hybrid A* → NP and
Hybrid A* → HOPE (hand-off at the first state within 10 m; Δκ without the single hand-off jump; paper §V-B), from
the sweep's run folders.

Usage, outputs and how the rows are read: `experiments.paper_table`.
"""

from __future__ import annotations

from experiments.paper_numbers import TWOSTAGE
from experiments.paper_table import table_cli

main = table_cli(TWOSTAGE, "staged", __doc__)

if __name__ == "__main__":
    main()
