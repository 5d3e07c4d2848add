"""What every planner of the testbed is (spec §7): ``plan(scene, start) -> Plan``, a collision ``convention`` and a
registry ``name``.

The experiments, the tracker and the closed loop see planners only through this protocol: a planner object plans
one query at a time from a start pose [x, y, θ] to ``scene.target`` and returns a `np_sim.plan.Plan` (a failure is
a plan with ``success=False`` and a reason, never an exception or a print); ``convention`` is the collision rule
its plans are scored by ('reference_point': the paper's sampled reference points; 'footprint': the vehicle
rectangle), which is also what the closed loop checks its replans against; ``name`` is the planner's key in the
experiments' registry (`experiments.registry`).
"""

from __future__ import annotations

from typing import Protocol, runtime_checkable

from np_sim.config import Convention
from np_sim.plan import Plan
from np_sim.scene import Scene

CONVENTIONS: tuple[Convention, ...] = ("reference_point", "footprint")
"""The collision conventions a planner plans under."""


@runtime_checkable
class Planner(Protocol):
    """A planner: one query from ``start`` to ``scene.target`` gives one `Plan`."""

    name: str
    """Registry key of the planner kind ('hybrid_astar', 'neuralparker', …)."""
    convention: Convention
    """Collision convention the plans are scored by: 'reference_point' or 'footprint'."""

    def plan(self, scene: Scene, start) -> Plan:
        """Plan from ``start`` [x, y, θ] to ``scene.target``; a failure is a plan with a reason."""
