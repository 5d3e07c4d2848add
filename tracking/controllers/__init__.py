"""Path-tracking controllers behind one interface (spec §8).

Lateral controllers map the tracking state to a physical steering curvature c (1/m, positive = left, spec §2):
`LQRController` (kinematic path-error model, python-control gains scheduled on speed and gear, curvature
feed-forward), `StanleyController`, `PurePursuitController`. `SteeringLimiter` applies the angle and rate limits;
`SpeedController` is the longitudinal PI loop. `make_lateral(name, config)` builds one by name.
"""

from tracking.controllers.base import LateralController
from tracking.controllers.longitudinal import SpeedController
from tracking.controllers.lqr import LQRController
from tracking.controllers.pure_pursuit import PurePursuitController
from tracking.controllers.stanley import StanleyController
from tracking.controllers.steering import SteeringLimiter
from tracking.errors import TrackingError

CONTROLLERS = {"lqr": LQRController, "stanley": StanleyController, "pure_pursuit": PurePursuitController}
"""Lateral controllers by name."""


def make_lateral(name: str, config) -> LateralController:
    """The lateral controller called ``name`` ('lqr', 'stanley' or 'pure_pursuit') for a `TrackerConfig`."""
    if name not in CONTROLLERS:
        raise TrackingError(f"controller: expected one of {sorted(CONTROLLERS)}, got {name!r}")
    return CONTROLLERS[name](config)


__all__ = ["CONTROLLERS", "LQRController", "LateralController", "PurePursuitController", "SpeedController",
           "StanleyController", "SteeringLimiter", "make_lateral"]
