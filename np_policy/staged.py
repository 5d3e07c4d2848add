"""Learned-classical hybrids on the Plan interface (spec §7): NP-Guided A* and the staged Hybrid A* → learned planner.

* ``NPGuidedAStar`` (paper §IV-B, §V-F): the NeuralParker policy is rolled out once from the query; its path
  (sampled positions, kept up to a collision when the rollout fails) is the guide of ``HybridAStar.plan``, whose
  search and feasibility tests are unchanged. Plan time includes the rollout.
* ``StagedPlanner`` (paper Table ``tab:twostage``): a region-goal Hybrid A* prefix to the first state within
  ``handoff_radius_m`` (10 m) of the target, then a learned planner from that state, without retraining:
  NeuralParker (``staged_astar_np``) or the adapted HOPE (``staged_astar_hope``, `hope_policy.planner`). The
  raw prefix is handed over (the paper's "frozen raw-path fallback"; no continuous-curvature smoothing here).
  ``StagedPlan.metrics()`` adds the prefix and downstream metrics (eq:metrics) and excludes the single hand-off
  curvature jump, as the table caption prescribes; a gear change at the hand-off is a real reversal and counts.
"""

from __future__ import annotations

import dataclasses
import time
from dataclasses import dataclass

import numpy as np

from np_policy.planner import NeuralParkerPlanner
from np_sim.kinematics import arc_step
from np_sim.metrics import plan_metrics
from np_sim.plan import Plan
from np_sim.planners import HybridAStar
from np_sim.scene import Scene


@dataclass(frozen=True, eq=False)
class GuidedPlan(Plan):
    """An NP-Guided A* plan; ``plan_time_s`` covers rollout and search."""

    guide_time_s: float = 0.0
    """Time of the NeuralParker rollout that made the guide (s)."""


class NPGuidedAStar:
    """Hybrid A* guided by one NeuralParker rollout from the query (node cost + weight × distance to it)."""

    name = "np_guided_astar"
    """Registry key of the planner kind (`np_sim.planners.protocol.Planner`)."""

    def __init__(self, learned: NeuralParkerPlanner, search: HybridAStar | None = None, guide_spacing_m: float = 0.5):
        if not guide_spacing_m > 0:
            raise ValueError(f"NPGuidedAStar: guide_spacing_m must be > 0, got {guide_spacing_m!r}")
        self.learned = learned
        self.search = HybridAStar() if search is None else search
        self.guide_spacing_m = guide_spacing_m

    @property
    def convention(self) -> str:
        """The search's collision convention: its plans are the search's."""
        return self.search.convention

    def plan(self, scene: Scene, start) -> GuidedPlan:
        """Roll out the policy from ``start``, then search with its path as the guide; time covers both."""
        t0 = time.perf_counter()
        rollout = self.learned.plan(scene, start)
        guide = rollout.sample(self.guide_spacing_m)[:, :2]
        t1 = time.perf_counter()
        plan = self.search.plan(scene, start, guide=guide)
        fields = {f.name: getattr(plan, f.name) for f in dataclasses.fields(Plan)}
        fields["plan_time_s"] = time.perf_counter() - t0
        return GuidedPlan(**fields, guide_time_s=t1 - t0)


@dataclass(frozen=True, eq=False)
class StagedPlan(Plan):
    """A plan of a Hybrid A* prefix (``arcs[:handoff_index]``) followed by a learned planner's plan."""

    handoff_index: int = 0
    """Number of prefix arcs: ``arcs[handoff_index:]`` and ``hermite`` belong to the downstream planner."""

    def metrics(self) -> tuple[float, int, float]:
        """(L, reversals, Δκ) of eq:metrics summed over prefix and downstream; the hand-off curvature jump
        |κ_first downstream − κ_last prefix| is excluded, a gear change at the hand-off counts as a reversal."""
        prefix, down = self.arcs[: self.handoff_index], self.arcs[self.handoff_index:]
        h = self.hermite
        l_p, rev_p, dk_p = plan_metrics(prefix)
        if h is None:
            l_d, rev_d, dk_d = plan_metrics(down)
        else:
            l_d, rev_d, dk_d = plan_metrics(down, h.length, h.delta_kappa, h.forward)
        handoff_reversal = 0
        if len(prefix) and len(down) and prefix[-1, 1] * down[0, 1] < 0:
            handoff_reversal = 1
        elif len(prefix) and not len(down) and h is not None and prefix[-1, 1] * (1.0 if h.forward else -1.0) < 0:
            handoff_reversal = 1
        return l_p + l_d, rev_p + rev_d + handoff_reversal, dk_p + dk_d


class StagedPlanner:
    """Region-goal Hybrid A* prefix to ``handoff_radius_m`` of the target, then the learned planner ``learned`` (any
    planner with ``plan(scene, start) -> Plan``: NeuralParker or the adapted HOPE); ``name`` is the registry key."""

    def __init__(self, learned, search: HybridAStar | None = None, handoff_radius_m: float = 10.0,
                 name: str = "staged_astar_np"):
        if not handoff_radius_m > 0:
            raise ValueError(f"StagedPlanner: handoff_radius_m must be > 0, got {handoff_radius_m!r}")
        self.name = name
        self.learned = learned
        self.search = HybridAStar() if search is None else search
        self.handoff_radius_m = handoff_radius_m

    @property
    def convention(self) -> str:
        """The search's collision convention (the convention the staged plans are scored by)."""
        return self.search.convention

    def plan(self, scene: Scene, start) -> StagedPlan:
        """Prefix to the hand-off state, then the learned plan from there; failure reasons name the stage."""
        t0 = time.perf_counter()
        start = np.asarray(start, float)
        prefix = self.search.plan_to_region(scene, start, self.handoff_radius_m)
        if not prefix.success:
            return StagedPlan(start=start, reason=f"prefix: {prefix.reason}", plan_time_s=time.perf_counter() - t0,
                              expanded_nodes=prefix.expanded_nodes)
        handoff = start
        for kappa, length in prefix.arcs:
            handoff = arc_step(handoff, kappa, length)
        down = self.learned.plan(scene, handoff)
        return StagedPlan(start=start, arcs=np.concatenate([prefix.arcs, down.arcs]).reshape(-1, 2),
                          hermite=down.hermite, success=down.success,
                          reason="" if down.success else f"downstream: {down.reason}",
                          plan_time_s=time.perf_counter() - t0, expanded_nodes=prefix.expanded_nodes,
                          handoff_index=len(prefix.arcs))
