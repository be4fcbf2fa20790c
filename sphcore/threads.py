"""How many threads a run uses: measured while it runs, so that a shared machine is never
slower with more threads than with fewer.

Every kernel gives the same bits for any thread count (the pair loop's slabs fix the order
of the additions, the other parallel loops are independent per particle: see
:mod:`sphcore.parallel` and :mod:`sphcore.neighbours`), so the count may change from one
step to the next without changing the result. The runner times each step and asks a
:class:`ThreadTuner` which count to use for the next one. The tuner alternates two phases:

- **probe**: a few steps with each candidate count (numba's full count, half of it, one),
  in the order A B .. B A so that a flow that slowly gets more expensive favours none;
  each candidate's time is the mean over its two windows;
- **use**: the fastest candidate for ``use_windows`` times as many steps as the probe took,
  then probe again (another job may have started or stopped on the machine). The last
  choice is kept unless another count is faster by more than ``MARGIN`` (3 %): two counts
  within the timing noise of each other do not make the run switch back and forth.

A window is about ``window_s`` of wall time (at least ``min_steps`` steps), so that a
window of small, fast steps is not all timer noise. The cost is the probe's windows spent
on the slower counts: with ``use_windows = 12`` about one step in thirteen runs at a
slower count. Measured on two cores (docs/speed.md, ``benchmarks/bench_loaded.py``).
"""

from __future__ import annotations

import numba

WINDOW_S = 0.03  # wall time of one probe window
MIN_STEPS = 4  # steps per window, at least
USE_WINDOWS = 12  # windows of the chosen count per probe window
WARMUP_STEPS = 3  # the first steps compile or fill caches: not timed
MARGIN = 0.03  # another count is chosen when it is this much faster than the last choice


def candidates(most: int) -> list[int]:
    """Thread counts worth comparing: all, half and one (distinct, largest first)."""
    return sorted({most, max(most // 2, 1), 1}, reverse=True)


class ThreadTuner:
    """Picks numba's thread count step by step from measured step times (module docstring).

    ``most``: the largest count to use (numba's ``NUMBA_NUM_THREADS`` or less);
    ``adapt = False`` or ``most = 1``: always ``most``."""

    def __init__(self, most: int, adapt: bool = True, window_s: float = WINDOW_S, min_steps: int = MIN_STEPS,
                 use_windows: int = USE_WINDOWS):
        self.counts = candidates(most) if adapt else [most]
        self.window_s, self.min_steps, self.use_windows = window_s, min_steps, use_windows
        self.current = self.chosen = self.counts[0]
        self.steps = {c: 0 for c in self.counts}  # steps taken with each count
        self.probes: list[dict[int, float]] = []  # s per step of each count, per probe
        self._skip = WARMUP_STEPS
        self._plan: list[int] = []  # counts of the probe windows still to run
        self._times: dict[int, list[float]] = {}  # this probe's s per step, per window
        self._window = min_steps  # steps per window
        self._left = 0  # steps left in the current window or use phase
        self._spent = 0.0  # wall time of the current window
        if self.active:
            self._start_probe()

    @property
    def active(self) -> bool:
        return len(self.counts) > 1

    def _start_probe(self):
        self._plan = self.counts + self.counts[::-1]
        self._times = {c: [] for c in self.counts}
        self._next_window()

    def _next_window(self):
        self.current = self._plan.pop(0)
        self._left, self._spent = self._window, 0.0

    def after_step(self, seconds: float) -> int:
        """Record the wall time of the step just taken; return the count for the next one."""
        self.steps[self.current] += 1
        if not self.active:
            return self.current
        if self._skip > 0:  # compiling or filling caches
            self._skip -= 1
            return self.current
        if self._skip == 0:  # the first warm step sizes the windows
            self._skip = -1
            self._window = self._left = max(self.min_steps, int(self.window_s / max(seconds, 1e-9)))
        self._left -= 1
        if self._times:  # probing
            self._spent += seconds
            if self._left == 0:
                self._times[self.current].append(self._spent / self._window)
                if self._plan:
                    self._next_window()
                else:
                    self._choose()
        elif self._left == 0:
            self._start_probe()
        return self.current

    def _choose(self):
        per_step = {c: sum(t) / len(t) for c, t in self._times.items()}
        best = min(per_step, key=per_step.get)
        if per_step[self.chosen] > (1.0 + MARGIN) * per_step[best]:  # a change must pay clearly
            self.chosen = best
        self.current = self.chosen
        self.probes.append(per_step)
        self._times = {}
        self._left = self.use_windows * self._window * 2 * len(self.counts)

    def summary(self) -> dict:
        """What summary.json says about the threads: steps per count, probes, last choice."""
        return {"counts": self.counts, "adaptive": self.active, "probes": len(self.probes),
                "steps_per_count": {str(c): n for c, n in self.steps.items()},
                "last_probe_us_per_step": {str(c): round(t * 1e6, 1) for c, t in self.probes[-1].items()}
                if self.probes else {}}


def tuner_for(config: dict) -> ThreadTuner:
    """The tuner a case's ``[parallel]`` table asks for: ``threads`` (0: numba's count, which
    ``NUMBA_NUM_THREADS`` sets) and ``adapt``."""
    most = numba.config.NUMBA_NUM_THREADS
    if config["parallel"]["threads"]:
        most = min(most, config["parallel"]["threads"])
    return ThreadTuner(most, adapt=config["parallel"]["adapt"])
