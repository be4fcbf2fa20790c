"""What a run does besides stepping, each on its own schedule.

An :class:`Activity` is an action on the simulation with a schedule that says when it is
due. A run holds two lists of them and nothing else decides timing:

- before a step (:meth:`sphcore.run.simulation.Simulation.advance`): the reorder of the
  particles by cell (``neighbours.sort_every``) and the Shepard density filter
  (``corrections.shepard_every``), in that order;
- after a step (:func:`sphcore.run.runner.run`): the thread tuner (every step: it times
  them), the progress display (its lines or redraws on a :class:`WallInterval`), the periodic checkpoint (``output.checkpoint_every_s`` of
  wall time and/or ``output.checkpoint_every_dt`` of simulated time).

Output writers are plugins: each owns its schedule and its file
(:class:`sphcore.io.schedule.Schedule`), and the runner calls them after every step.

Schedules answer :meth:`due` from the run's clock (:class:`sphcore.run.state.Clock`);
wall-time schedules read :func:`time.monotonic` themselves.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable


class EveryStep:
    """Due after every step."""

    def due(self, clock) -> bool:
        return True


@dataclass
class StepInterval:
    """Due when the step count is a multiple of ``n`` (``n`` <= 0: never); with
    ``skip_first`` not at step 0."""

    n: int
    skip_first: bool = False

    def due(self, clock) -> bool:
        return self.n > 0 and clock.step % self.n == 0 and not (self.skip_first and clock.step == 0)


class TimeInterval:
    """Due once each time the simulated time passes a multiple of ``dt`` (s) after ``t0``
    (the time the run starts or restarts from); the next multiple is computed from t, not
    accumulated, so round-off does not drift."""

    def __init__(self, dt: float, t0: float = 0.0):
        self.dt = dt
        self.next_t = (int(t0 / dt) + 1) * dt

    def due(self, clock) -> bool:
        if clock.t < self.next_t * (1 - 1e-12):
            return False
        self.next_t = (int(clock.t / self.dt * (1 + 1e-12)) + 1) * self.dt
        return True


class WallInterval:
    """Due when ``seconds`` of wall time have passed since it was last due (or created)."""

    def __init__(self, seconds: float):
        self.seconds = seconds
        self.last = time.monotonic()

    def restart(self):
        """Count the interval from now."""
        self.last = time.monotonic()

    def due(self, clock=None) -> bool:
        now = time.monotonic()
        if now - self.last < self.seconds:
            return False
        self.last = now
        return True


class AnyOf:
    """Due when any of its schedules is (each is asked every time, so that each keeps its
    own count); a wall-time schedule restarts its interval whenever the whole is due."""

    def __init__(self, *schedules):
        self.schedules = schedules

    def due(self, clock) -> bool:
        fired = [s.due(clock) for s in self.schedules]
        if any(fired):
            for s in self.schedules:
                if isinstance(s, WallInterval):
                    s.last = time.monotonic()
            return True
        return False


class Never:
    def due(self, clock) -> bool:
        return False


def periodic(every_s: float | None = None, every_dt: float | None = None, t0: float = 0.0):
    """The schedule of ``every_s`` of wall time and/or ``every_dt`` of simulated time from
    ``t0`` (None or 0 switches one off; both off: never)."""
    parts = ([WallInterval(every_s)] if every_s else []) + ([TimeInterval(every_dt, t0)] if every_dt else [])
    return AnyOf(*parts) if len(parts) > 1 else parts[0] if parts else Never()


@dataclass
class Activity:
    """``action(sim)`` when ``schedule`` is due."""

    name: str
    schedule: object
    action: Callable

    def __call__(self, sim) -> bool:
        """Run the action if due; whether it ran."""
        if self.schedule.due(sim.run.clock):
            self.action(sim)
            return True
        return False
