"""One exception family for the package; each subclasses a built-in so callers can catch either."""


class NPSimError(Exception):
    """Base of every error raised by np_sim."""


class SceneError(NPSimError, ValueError):
    """A scene file or dict is malformed: the message names the file, the field path and what was expected."""


class CapacityError(SceneError):
    """A scene exceeds a capacity of what it is used with: the observation's object or boundary limits, or a
    planner's memory bound (``HybridAStarConfig.max_lattice_bytes``)."""


class ConfigError(NPSimError, ValueError):
    """A configuration value or key is invalid."""


class StartInCollisionError(ConfigError):
    """A start pose given to an environment reset (and so to a planner rolling out from it) is in collision under
    the collision convention in use: the message names the pose, the scene and the convention."""
