"""Errors of the closed-loop testbed, in the package's one exception family (np_sim.errors)."""

from np_sim.errors import NPSimError


class TrackingError(NPSimError, ValueError):
    """Invalid input to the tracker or executor: the message says what was expected and what came."""
