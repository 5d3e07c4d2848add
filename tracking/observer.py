"""Observers of a closed-loop run (logging, rendering): hooks the executor calls, no-ops by default."""

from __future__ import annotations


class RunObserver:
    """Base observer: every hook does nothing."""

    frames_rendered: int = 0
    """Off-screen frames rendered so far."""

    def on_start(self, world, plan, segments) -> None:
        """The world is built and the first plan's segments are known."""

    def on_plan(self, t: float, plan, segments) -> None:
        """A replanned plan replaced the followed one at sim time ``t``."""

    def on_step(self, t: float, world, state, command: float, target_speed: float) -> None:
        """A control step ended at sim time ``t``; ``state`` is what the controller saw before it, ``command`` the
        limited steering curvature sent and ``target_speed`` the signed speed target."""

    def on_end(self, record) -> None:
        """The run ended with ``record``."""


class Observers(RunObserver):
    """Several observers called in order."""

    def __init__(self, parts: list[RunObserver]):
        self.parts = parts

    @property
    def frames_rendered(self) -> int:
        return sum(p.frames_rendered for p in self.parts)

    def on_start(self, world, plan, segments) -> None:
        for p in self.parts:
            p.on_start(world, plan, segments)

    def on_plan(self, t, plan, segments) -> None:
        for p in self.parts:
            p.on_plan(t, plan, segments)

    def on_step(self, t, world, state, command, target_speed) -> None:
        for p in self.parts:
            p.on_step(t, world, state, command, target_speed)

    def on_end(self, record) -> None:
        for p in self.parts:
            p.on_end(record)


class TrajectoryRecorder(RunObserver):
    """Records the executed reference-point trajectory: (t, x, y, θ) at the start and after every control step."""

    def __init__(self, start_time_s: float = 0.0):
        self.start_time_s = float(start_time_s)
        self.rows: list[tuple[float, float, float, float]] = []

    def on_start(self, world, plan, segments) -> None:
        self.rows = [(self.start_time_s, *map(float, world.pose()))]

    def on_step(self, t, world, state, command, target_speed) -> None:
        self.rows.append((float(t), *map(float, world.pose())))

    def array(self):
        """(n, 4) float array t (s), x (m), y (m), θ (rad)."""
        import numpy as np

        return np.asarray(self.rows, dtype=float).reshape(-1, 4)
