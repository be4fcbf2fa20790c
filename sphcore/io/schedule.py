"""When an output writer writes a frame: every ``every_dt`` of simulated time or every N steps.

Shared by the VTU and netCDF writers (each owns one :class:`Schedule`). A schedule
counts the frames it has fired instead of accumulating a next-output time, so round-off
in ``t`` (a sum of thousands of variable steps) can neither skip nor double a frame.
"""

from __future__ import annotations

import math

from sphcore.case.options import Option
from sphcore.errors import CaseError

#: simulated time between frames (s) when a case sets neither every_dt nor every_steps
DEFAULT_EVERY_DT = 0.01

#: relative tolerance on "t has reached k * every_dt" (covers the rounding of k * every_dt)
REL_TOL = 1e-12


def schedule_options(what: str) -> dict[str, Option]:
    """The two schedule keys a writer declares in its own table (``what`` names the frame)."""
    return {
        # None rather than 0.01 as the declared default: a validated table fills every
        # default, so a declared 0.01 could not be told from one the case set, and a case
        # that sets only every_steps would then have both set.
        "every_dt": Option(
            None, "float", "s",
            f"simulated time between {what}s; {DEFAULT_EVERY_DT} s when neither key is set",
            positive=True, nullable=True,
        ),
        "every_steps": Option(
            None, "int", "", f"write a {what} every N steps instead of every_dt",
            positive=True, nullable=True,
        ),
    }


class Schedule:
    """Decides per call whether a frame is due; remembers what it has fired.

    Fires at step 0, whenever ``t`` has reached the next multiple of ``every_dt`` (s) or
    ``step`` is a multiple of ``every_steps``, and on the final call unless a frame was
    already written at that step. At most one frame per step: a step longer than
    ``every_dt`` writes one frame and the count skips to the next multiple after ``t``.
    """

    def __init__(self, every_dt: float | None = None, every_steps: int | None = None):
        if every_dt is not None and every_steps is not None:
            raise ValueError("set only one of every_dt and every_steps")
        if every_dt is None and every_steps is None:
            every_dt = DEFAULT_EVERY_DT
        if every_dt is not None and not (math.isfinite(every_dt) and every_dt > 0):
            raise ValueError(f"every_dt must be a positive number of seconds, got {every_dt!r}")
        if every_steps is not None and not every_steps > 0:
            raise ValueError(f"every_steps must be a positive integer, got {every_steps!r}")
        self.every_dt = every_dt
        self.every_steps = every_steps
        self._k = 0  # index of the next multiple of every_dt that fires a frame
        self._last_step: int | None = None  # step of the last frame fired
        self.frames = 0  # frames fired so far (this process)

    @classmethod
    def from_config(cls, case, table: str) -> "Schedule":
        """Build from ``case.config[table]``; both keys set is a CaseError naming file and key."""
        cfg = case.config.get(table, {})
        every_dt, every_steps = cfg.get("every_dt"), cfg.get("every_steps")
        if every_dt is not None and every_steps is not None:
            raise CaseError(
                getattr(case, "file", "case.toml"), f"{table}.every_steps",
                f"set only one of {table}.every_dt and {table}.every_steps "
                f"(every_dt = {every_dt!r}, every_steps = {every_steps!r})",
            )
        return cls(every_dt=every_dt, every_steps=every_steps)

    def due(self, t: float, step: int, final: bool = False) -> bool:
        """True when a frame is due at time ``t`` (s) and ``step``; True counts it as written."""
        if step == self._last_step:
            return False  # this step's frame exists already (e.g. the final call after it)
        if self.every_steps is not None:
            fire = step % self.every_steps == 0
        else:
            fire = self._reached(t, step)
        if fire or final or step == 0:
            self._count(t, step)
            return True
        return False

    def resume(self, t: float, step: int | None) -> None:
        """Count frames up to time ``t`` (s) as written (a restart found them on disk).

        ``step`` is the step of that last frame if the restart is at that same step, so
        the restart's first call does not write it again; None otherwise.
        """
        self._count(t, step)
        self.frames = 0

    def _tol(self, t: float, step: int | None) -> float:
        """How far (s) below a multiple of every_dt ``t`` may sit and still count as on it.

        REL_TOL * every_dt alone is too tight: t is a sum of ``step`` rounded additions,
        each off by up to half an ulp of t, and 0.001 s summed 1100 times is already
        1.03e-14 s short of 1.1 s, more than 1e-12 * 0.01 s. So the worst-case sum error,
        step * ulp(t), is added; with steady steps that is below 2 % of a step up to 1e7 steps.
        """
        return REL_TOL * self.every_dt + (step or 0) * math.ulp(t)

    def _reached(self, t: float, step: int | None) -> bool:
        return t >= self._k * self.every_dt - self._tol(t, step)

    def _count(self, t: float, step: int | None) -> None:
        if self.every_dt is not None:
            # next frame: the first multiple after t (within the tolerance). The max() keeps
            # the count moving forward even if floor() rounds down at a multiple.
            k_next = math.floor((t + self._tol(t, step)) / self.every_dt) + 1
            self._k = max(self._k + self._reached(t, step), k_next)
        self._last_step = step
        self.frames += 1
