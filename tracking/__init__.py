"""Closed-loop validation in MuJoCo (SPEC §8): vehicle model, scene worlds, reference paths, path-tracking
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
