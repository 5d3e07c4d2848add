"""Classical planners on the common ``Plan`` interface (SPEC §7): Hybrid A* (optionally NP-guided) and the OMPL
peer (``np_sim.planners.ompl_peer``, imported on demand since OMPL is a test extra)."""

from np_sim.planners.hybrid_astar import HybridAStar, HybridAStarConfig

__all__ = ["HybridAStar", "HybridAStarConfig"]
