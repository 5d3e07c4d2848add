"""Table IV (``tab:hermite``): the terminal connector: fixed Hermite; the ensemble swapped in at evaluation
only; the ensemble in training and evaluation (paper §V-D), from the sweep's run folders.

Usage, outputs and how the rows are read: `experiments.paper_table`.
"""

from __future__ import annotations

from experiments.paper_numbers import HERMITE
from experiments.paper_table import table_cli

main = table_cli(HERMITE, "connector", __doc__)

if __name__ == "__main__":
    main()
