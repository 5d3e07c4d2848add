"""The network's inputs from the adapted-HOPE env's observations (paper App. B, "Controlled Representation Inputs").

The env returns raw observations (`hope_policy.spaces`). The agent feeds every key to the network as it is, except
the BEV raster of the HOPE-style BEV control: as HOPE's image branch reads the latent of its frozen autoencoder, the
(3, 64, 64) image is replaced by the 128-D latent of the frozen encoder pretrained on the benchmark
(`np_policy.bev_encoder`, the file named by ``HopeTrainConfig.bev_encoder_file``) before normalisation and storage,
so a PPO batch holds latents, not images. The encoder's raster must be the env's (``HopeEnvConfig.bev``).
"""

from __future__ import annotations

import numpy as np
from gymnasium import spaces

from hope_policy.config import HopeEnvConfig
from hope_policy.network import Modalities
from hope_policy.spaces import vertex_shapes
from np_policy.bev_encoder import load_frozen_encoder
from np_sim.errors import ConfigError


class PolicyInputs:
    """Raw observations → network inputs (module docstring), and the network's input branches."""

    def __init__(self, env: HopeEnvConfig, bev_encoder_file: str = ""):
        self.env = env
        self.encoder = None
        if env.added_input == "bev":
            self.encoder = load_frozen_encoder(bev_encoder_file)
            if self.encoder.raster != env.bev:
                raise ConfigError(f"HopeTrainConfig.bev_encoder_file: {bev_encoder_file} was pretrained on the raster "
                                  f"{self.encoder.raster}, the env renders {env.bev}")

    def modalities(self, space: spaces.Dict) -> Modalities:
        """The network's input branches for an observation space: each key with its flat size, the BEV raster with
        its encoder's latent size, the vertices with their slots."""
        slots = tuple(vertex_shapes(self.env).values()) if "vertices" in space.spaces else ()
        return Modalities(tuple((key, self.encoder.latent_dim if key == "bev" else int(np.prod(box.shape)))
                                for key, box in space.spaces.items()), vertex_slots=slots)

    def __call__(self, obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """A batch of observations (each key ``(n, ...)``) with the BEV images replaced by their latents."""
        if self.encoder is None:
            return obs
        return {**obs, "bev": self.encoder(np.asarray(obs["bev"], np.uint8))}
