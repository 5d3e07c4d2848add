"""Table III (``tab:topology-stress``) and Fig. 5 (``fig:global-family``): the scene-representation
ablation on Topology-Stress, two backbones (NeuralParker, HOPE-style) × three added inputs (none, BEV, vertices;
paper §V-C), from the sweep's run folders.

Usage, outputs and how the rows are read: `experiments.paper_table`.
"""

from __future__ import annotations

from experiments.paper_numbers import TOPOLOGY_STRESS
from experiments.paper_table import family_figure, table_cli

main = table_cli(TOPOLOGY_STRESS, "representation", __doc__, extra_figure=family_figure)

if __name__ == "__main__":
    main()
