"""The off-the-shelf peer: OMPL's RRT* in a Reeds–Shepp state space with our collision check (spec §7).

OMPL (PyPI ``ompl``, a test extra, imported on first use) plans in ``ReedsSheppStateSpace(1/κ_max)`` bounded by
the scene's bounding box; our compiled check (``np_sim.kernels.collision.pose_valid``, reference-point or
footprint convention) is its state-validity checker, and motions are checked at ``check_spacing_m`` along the
Reeds–Shepp curves (OMPL's discrete motion validator). The planner is RRT* (Karaman & Frazzoli 2011,
asymptotically optimal, path-length objective), run for the whole time budget — by default the Hybrid A* budget.
Its solution states are joined by our shortest Reeds–Shepp paths (``np_sim.reeds_shepp``) into arcs and
validated like Hybrid A*'s before a success is claimed (`np_sim.validate.validation_failure`: the rule the plan is
scored by, and the exact swept footprint under the footprint convention).
"""

from __future__ import annotations

import math
import time
from dataclasses import dataclass

import numpy as np

from np_sim.config import Convention
from np_sim.errors import ConfigError
from np_sim.kernels.collision import pose_valid
from np_sim.kinematics import arc_step, wrap_angle
from np_sim.plan import Plan
from np_sim.planners.hybrid_astar import HybridAStarConfig
from np_sim.reeds_shepp import shortest_path
from np_sim.scene import Scene
from np_sim.scene_arrays import packed_scene
from np_sim.validate import validation_failure
from np_sim.vehicle import VehicleSpec


@dataclass(frozen=True)
class OmplPeerConfig:
    """OMPL RRT* settings; the defaults share Hybrid A*'s budget, tolerance and check spacing."""

    vehicle: VehicleSpec = VehicleSpec()
    """Footprint and curvature bound (κ_max) of the Reeds–Shepp space."""
    time_budget_s: float = HybridAStarConfig().time_budget_s
    """Wall time given to RRT* per query (s): the Hybrid A* budget."""
    check_spacing_m: float = 0.1
    """Spacing of the validity checks along motions (m)."""
    goal_threshold_m: float = 0.05
    """OMPL goal threshold in Reeds–Shepp distance (m); ≤ 0.1 m keeps the end within 0.1 m and 10°."""
    seed: int = 0
    """OMPL's random seed (set once per planner)."""

    def __post_init__(self) -> None:
        for name in ("time_budget_s", "check_spacing_m", "goal_threshold_m"):
            value = getattr(self, name)
            if not (isinstance(value, (int, float)) and math.isfinite(value) and value > 0):
                raise ConfigError(f"OmplPeerConfig.{name}: expected a finite positive number, got {value!r}")


class OmplPeer:
    """RRT* (OMPL) on a Reeds–Shepp state space with our state-validity checker; ``plan(scene, start) -> Plan``."""

    name = "ompl_rrtstar"
    """Registry key (`np_sim.planners.protocol.Planner`); ``convention`` is set per instance."""

    def __init__(self, config: OmplPeerConfig | None = None, convention: Convention = "reference_point"):
        if convention not in ("reference_point", "footprint"):
            raise ConfigError(f"OmplPeer: convention must be 'reference_point' or 'footprint', got {convention!r}")
        from ompl import util as ou

        self.config = OmplPeerConfig() if config is None else config
        self.convention = convention
        self._local = self.config.vehicle.footprint_local()
        ou.setLogLevel(ou.LOG_ERROR)
        ou.RNG.setSeed(self.config.seed)

    def plan(self, scene: Scene, start) -> Plan:
        """Run RRT* for the time budget from ``start`` to ``scene.target``; a plan of RS pieces as eq:arc arcs."""
        from ompl import base as ob
        from ompl import geometric as og

        t0 = time.perf_counter()
        c = self.config
        p = np.asarray(start, dtype=float)
        if p.shape != (3,) or not np.all(np.isfinite(p)):
            raise ValueError(f"OmplPeer.plan: start must be a finite [x, y, θ] of shape (3,), got {start!r}")
        geo = packed_scene(scene).geometry
        footprint = self.convention == "footprint"
        local, corners = self._local, np.empty((4, 2))
        if not pose_valid(geo, 0, p[0], p[1], p[2], footprint, local, corners):
            return Plan(start=p, reason="start in collision", plan_time_s=time.perf_counter() - t0)

        space = ob.ReedsSheppStateSpace(1.0 / c.vehicle.kappa_max)
        b = np.asarray(scene.boundary, float)
        bounds = ob.RealVectorBounds(2)
        for axis in range(2):
            bounds.setLow(axis, float(b[:, axis].min()))
            bounds.setHigh(axis, float(b[:, axis].max()))
        space.setBounds(bounds)
        setup = og.SimpleSetup(space)
        setup.setStateValidityChecker(
            lambda s: bool(pose_valid(geo, 0, s.getX(), s.getY(), s.getYaw(), footprint, local, corners)))
        info = setup.getSpaceInformation()
        info.setStateValidityCheckingResolution(c.check_spacing_m / space.getMaximumExtent())
        s0, s1 = space.allocState(), space.allocState()
        s0.setX(p[0]), s0.setY(p[1]), s0.setYaw(p[2])
        goal = np.asarray(scene.target, float)
        s1.setX(goal[0]), s1.setY(goal[1]), s1.setYaw(goal[2])
        setup.setStartAndGoalStates(s0, s1, c.goal_threshold_m)
        planner = og.RRTstar(info)
        setup.setPlanner(planner)
        setup.solve(c.time_budget_s)
        data = ob.PlannerData(info)
        planner.getPlannerData(data)
        vertices = int(data.numVertices())
        if not setup.haveExactSolutionPath():
            return Plan(start=p, reason="budget", plan_time_s=time.perf_counter() - t0, expanded_nodes=vertices)
        path = setup.getSolutionPath()
        states = [np.array([s.getX(), s.getY(), s.getYaw()])
                  for s in (path.getState(i) for i in range(path.getStateCount()))]
        arcs = np.concatenate([shortest_path(a, b_, c.vehicle.kappa_max) for a, b_ in zip(states[:-1], states[1:])])
        arcs = arcs.reshape(-1, 2)
        reason = self._check(scene, p, arcs, goal)
        return Plan(start=p, arcs=arcs, success=reason == "", reason=reason, plan_time_s=time.perf_counter() - t0,
                    expanded_nodes=vertices)

    def _check(self, scene: Scene, start: np.ndarray, arcs: np.ndarray, goal: np.ndarray) -> str:
        """'' when the end meets the goal tolerance and the plan passes its validation, else the reason."""
        pose = start
        for kappa, length in arcs:
            pose = arc_step(pose, kappa, length)
        if math.hypot(*(pose[:2] - goal[:2])) > 0.1 or abs(wrap_angle(pose[2] - goal[2])) > math.radians(10.0):
            return "goal missed"
        return validation_failure(scene, Plan(start=start, arcs=arcs, success=True), self.convention,
                                  self.config.vehicle)
