"""NeuralParker kinematic planning core: geometry kernels, scenes, arcs, Hermite connector, LiDAR, environments.

`np_sim` imports neither torch nor mujoco (spec §1).
"""

__version__ = "0.1.0"
