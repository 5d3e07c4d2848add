"""Running mean-and-standard-deviation normalisation of the adapted HOPE's observation branches (paper App.
``app:hope-adaptation``, HOPE's ``StateNorm``).

Only the LiDAR, target and optional vertex branches are normalised; the action mask and the BEV image pass through
unchanged. Each normalised feature keeps its own running mean and population standard deviation over every
observation it has been updated with, and ``x`` becomes ``(x - mean) / (std + 1e-8)``. As in HOPE, the statistics
are updated with each observation an env step returns (and with the very first observation of the run) and are
stored in the checkpoint, so evaluation normalises exactly as training last did.

The vertex branch pads its unused obstacle and boundary slots with the observation's sentinel (−1e4). Padding is
not a measurement: its entries are left out of the statistics (each feature keeps its own count) and pass through
unchanged, so a slot filled in some scenes and empty in others is normalised over the scenes that fill it. Counting
the sentinel instead made such a slot's standard deviation thousands of metres and flattened every real coordinate
in it to about the same value.
"""

from __future__ import annotations

from typing import Any

import numpy as np

NORMALISED_KEYS = ("lidar", "target", "vertices")
"""Observation branches with running statistics (paper App. ``app:hope-adaptation``)."""
EPS = 1e-8
"""Added to the standard deviation before dividing (HOPE's ``state_norm``)."""


class RunningMeanStd:
    """Per-feature running mean and population variance of a stream of arrays of one shape.

    Batches are merged with Chan et al.'s parallel update, so the statistics after any split of the stream into
    batches equal ``np.mean`` and ``np.var`` over the whole stream (up to rounding). With a ``padding`` value,
    entries equal to it are left out feature by feature (``count`` is then per feature) and ``normalise`` returns
    them unchanged.
    """

    def __init__(self, shape: tuple[int, ...], padding: float | None = None):
        self.shape = tuple(shape)
        self.padding = padding
        self.count = 0 if padding is None else np.zeros(self.shape, np.int64)
        self.mean = np.zeros(self.shape, np.float64)
        self.m2 = np.zeros(self.shape, np.float64)

    @property
    def empty(self) -> bool:
        """Nothing has been counted yet (HOPE then starts the statistics with the first observation)."""
        return not np.any(self.count)

    @property
    def std(self) -> np.ndarray:
        """Population standard deviation ``sqrt(M2 / n)`` (zeros before any update)."""
        return np.sqrt(np.divide(self.m2, self.count, out=np.zeros(self.shape), where=np.asarray(self.count) > 0))

    def update(self, batch: np.ndarray) -> None:
        """Merge ``batch`` (``(n, *shape)``) into the statistics."""
        batch = np.asarray(batch, np.float64)
        if batch.shape[1:] != self.shape:
            raise ValueError(f"RunningMeanStd.update: expected a batch of shape (n, {self.shape}), got {batch.shape}")
        if batch.shape[0] == 0:
            return
        if self.padding is not None:
            self._update_unpadded(batch, batch != self.padding)
            return
        n = batch.shape[0]
        mean_b = batch.mean(axis=0)
        m2_b = ((batch - mean_b) ** 2).sum(axis=0)
        total = self.count + n
        delta = mean_b - self.mean
        self.mean = self.mean + delta * (n / total)
        self.m2 = self.m2 + m2_b + delta ** 2 * (self.count * n / total)
        self.count = total

    def _update_unpadded(self, batch: np.ndarray, real: np.ndarray) -> None:
        """``update`` over the ``real`` entries only, feature by feature (the same merge with per-feature counts)."""
        n = real.sum(axis=0)
        mean_b = np.divide(np.where(real, batch, 0.0).sum(axis=0), n, out=np.zeros(self.shape), where=n > 0)
        m2_b = np.where(real, (batch - mean_b) ** 2, 0.0).sum(axis=0)
        total = self.count + n
        delta = mean_b - self.mean
        seen = total > 0
        self.mean = self.mean + delta * np.divide(n, total, out=np.zeros(self.shape), where=seen)
        self.m2 = self.m2 + m2_b + delta ** 2 * np.divide(self.count * n, total, out=np.zeros(self.shape), where=seen)
        self.count = total

    def normalise(self, x: np.ndarray) -> np.ndarray:
        """``(x - mean) / (std + 1e-8)`` as float32 (padding entries unchanged)."""
        x = np.asarray(x, np.float64)
        out = (x - self.mean) / (self.std + EPS)
        if self.padding is not None:
            out = np.where(x == self.padding, x, out)
        return out.astype(np.float32)

    def state_dict(self) -> dict[str, Any]:
        """Count, mean and M2 (plain data and arrays)."""
        count = self.count if self.padding is None else self.count.copy()
        return {"count": count, "mean": self.mean.copy(), "m2": self.m2.copy()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Inverse of ``state_dict``; ValueError when the stored shape is not this one, or when its count is one
        number where padding needs one per feature (statistics made with the padding counted) or the reverse."""
        mean, m2 = np.asarray(state["mean"], np.float64), np.asarray(state["m2"], np.float64)
        if mean.shape != self.shape or m2.shape != self.shape:
            raise ValueError(f"RunningMeanStd: stored statistics have shape {mean.shape}, expected {self.shape}")
        count = np.asarray(state["count"])
        wanted = () if self.padding is None else self.shape
        if count.shape != wanted:
            raise ValueError(f"RunningMeanStd: stored count has shape {count.shape}, expected {wanted} (statistics "
                             f"{'with' if self.padding is None else 'without'} padding left out)")
        self.count = int(count) if self.padding is None else count.astype(np.int64)
        self.mean, self.m2 = mean.copy(), m2.copy()


class ObservationNormaliser:
    """One `RunningMeanStd` per normalised branch present in the observation (`NORMALISED_KEYS`)."""

    def __init__(self, shapes: dict[str, tuple[int, ...]], padding: dict[str, float] | None = None):
        padding = padding or {}
        self.stats = {key: RunningMeanStd(shape, padding.get(key)) for key, shape in shapes.items()
                      if key in NORMALISED_KEYS}

    @classmethod
    def for_space(cls, space, config) -> "ObservationNormaliser":
        """The normaliser of an observation space (`hope_policy.spaces.observation_space`) of the env ``config``
        (`HopeEnvConfig`): the vertex branch's padding is its observation sentinel."""
        return cls({key: box.shape for key, box in space.spaces.items()},
                   padding={"vertices": config.observation.sentinel})

    def update(self, obs: dict[str, np.ndarray]) -> None:
        """Add a batch of observations (each branch ``(n, *shape)``) to the statistics."""
        for key, stats in self.stats.items():
            stats.update(obs[key])

    def __call__(self, obs: dict[str, np.ndarray]) -> dict[str, np.ndarray]:
        """A new dict: normalised branches replaced, the others (mask, image) passed through as float32."""
        return {key: self.stats[key].normalise(value) if key in self.stats else np.asarray(value, np.float32)
                for key, value in obs.items()}

    def state_dict(self) -> dict[str, Any]:
        """The statistics of every branch, by branch name."""
        return {key: stats.state_dict() for key, stats in self.stats.items()}

    def load_state_dict(self, state: dict[str, Any]) -> None:
        """Inverse of ``state_dict``; ValueError naming the branches when they differ from this normaliser's."""
        if set(state) != set(self.stats):
            raise ValueError(f"ObservationNormaliser: stored branches {sorted(state)}, expected {sorted(self.stats)}")
        for key, stats in self.stats.items():
            stats.load_state_dict(state[key])
