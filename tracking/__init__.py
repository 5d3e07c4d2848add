"""Closed-loop validation in MuJoCo (spec §8): vehicle model, scene worlds, reference paths, path-tracking
controllers, the executor, planned-path validators and Rerun logging.

```python
from tracking.executor import execute
record = execute(scene, plan, controller="lqr")        # .success, .reason, .contacts, .final_error, ...
```

Modules: `config` (frozen configs), `mjcf` (vehicle MJCF from `VehicleSpec`), `geometry` (convex pieces of
obstacles and walls), `world` (scene → MuJoCo world), `reference` (plan → gear segments with speed profile),
`controllers` (LQR, Stanley, pure pursuit, longitudinal), `executor` (closed loop), `validators`, `render`
(off-screen frames), `rerun_log` (``.rrd`` files), `bench` (``python -m tracking.bench``).
"""

import os

# MuJoCo reads MUJOCO_GL once, when first imported: default to headless EGL (Mesa on CPU) before any module here
# imports mujoco; a value the user set wins.
os.environ.setdefault("MUJOCO_GL", "egl")
