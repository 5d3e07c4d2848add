"""Classical planners on the common ``Plan`` interface (spec §7): Hybrid A* (optionally NP-guided) and the OMPL
peer (``np_sim.planners.ompl_peer``, imported on demand since OMPL is a test extra); ``Planner`` is the protocol every
planner of the testbed follows (``np_sim.planners.protocol``)."""

from np_sim.planners.hybrid_astar import HybridAStar, HybridAStarConfig
from np_sim.planners.protocol import CONVENTIONS, Planner

__all__ = ["CONVENTIONS", "HybridAStar", "HybridAStarConfig", "Planner"]
