"""NeuralParker policy and PPO training (spec §6): scene encoder, actor–critic and the Tianshou-style PPO recipe.

Dependencies point one way: ``np_sim`` ← ``np_policy``. Nothing here is imported by ``np_sim``.
"""

from np_policy.config import NetworkConfig, PPOConfig

__all__ = ["NetworkConfig", "PPOConfig"]
