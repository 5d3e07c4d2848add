"""Table V (``tab:app-controls``): the geodesic start curriculum against sampling the full start range from
the first epoch (paper App. A), from the sweep's run folders.

Usage, outputs and how the rows are read: `experiments.paper_table`.
"""

from __future__ import annotations

from experiments.paper_numbers import CURRICULUM
from experiments.paper_table import table_cli

main = table_cli(CURRICULUM, "curriculum", __doc__)

if __name__ == "__main__":
    main()
