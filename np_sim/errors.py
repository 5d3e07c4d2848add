"""One exception family for the package; each subclasses a built-in so callers can catch either."""


class NPSimError(Exception):
    """Base of every error raised by np_sim."""


class SceneError(NPSimError, ValueError):
    """A scene file or dict is malformed: the message names the file, the field path and what was expected."""


class CapacityError(SceneError):
    """A scene exceeds the object or boundary capacity of the observation config it is used with."""


class ConfigError(NPSimError, ValueError):
    """A configuration value or key is invalid."""
