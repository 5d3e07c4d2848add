"""The lateral-controller interface and the state it reads."""

from __future__ import annotations

from abc import ABC, abstractmethod
from dataclasses import dataclass

import numpy as np

from tracking.projection import Projection
from tracking.reference import Segment


@dataclass(frozen=True)
class TrackingState:
    """What a lateral controller sees at one control step."""

    pose: np.ndarray
    """Reference point [x, y, θ] (m, m, rad)."""
    speed_mps: float
    """Signed speed along the heading (m/s), negative in reverse."""
    steer_curvature: float
    """Physical steering curvature of the current front-wheel angles (1/m)."""
    segment: Segment
    """The gear segment being tracked."""
    projection: Projection
    """The pose's nearest point on the segment and the path-frame errors."""


class LateralController(ABC):
    """Maps the tracking state to a steering curvature command."""

    name: str = ""
    """Short name used in records and tables."""

    @abstractmethod
    def steer_curvature(self, state: TrackingState) -> float:
        """Physical steering curvature c to command (1/m, positive = left; limits are applied afterwards)."""
