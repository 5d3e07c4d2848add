"""The paper's two procedural benchmarks (paper §IV-A, spec §4.1–4.3): Factorial Parking and Topology-Stress.

```python
from np_sim.benchmarks import load_benchmark, frozen_starts
scenes = load_benchmark("factorial", "test")     # 27 scenes (topology: 18); "train": 81 (topology: 48)
starts = frozen_starts("factorial")              # (27, 40, 3) world-frame frozen evaluation starts
val = validation_starts("topology")              # (48, 10, 3) starts on the training scenes (seed 1), for tuning
```

Modules: `factorial` and `topology` (generators), `common` (their shared geometry: shapes, irregular
boundaries, clutter, start regions by geodesic band), `validity` (the four checks), `layout` (layout distance
and disjointness floor), `frozen` (files, frozen starts, build loop), `generate` (regeneration CLI:
``python -m np_sim.benchmarks.generate [--check]``), `summary` (``python -m np_sim.benchmarks --summary`` /
``--figure DIR``).
"""

from np_sim.benchmarks.frozen import (
    BENCHMARK_NAMES,
    SPLITS,
    benchmark_path,
    frozen_starts,
    load_benchmark,
    validation_starts,
)

__all__ = ["BENCHMARK_NAMES", "SPLITS", "benchmark_path", "frozen_starts", "load_benchmark", "validation_starts"]
