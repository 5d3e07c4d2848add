"""The adapted HOPE baseline (paper §IV-B, App. B; spec §7): its environment on the project's arc kinematics,
HOPE's action mask, reward and Reeds–Shepp takeover, and the HOPE-style representation variants.

Dependencies point one way: ``np_sim`` ← ``np_policy`` ← ``hope_policy``.
"""

from hope_policy.config import HopeEnvConfig, HopeRewardConfig
from hope_policy.spaces import action_space, observation_space

__all__ = ["HopeEnvConfig", "HopeRewardConfig", "action_space", "observation_space"]
