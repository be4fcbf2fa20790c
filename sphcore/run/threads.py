"""How many threads a run uses: measured while it runs, so that a shared machine is never
slower with more threads than with fewer.

Every kernel gives the same bits for any thread count (the pair loop's slabs fix the order
of the additions, the other parallel loops are independent per particle: see
:mod:`sphcore.jit.parallel` and :mod:`sphcore.neighbours.cellgrid`), so the count may change from one
step to the next without changing the result. The runner times each step and asks a
:class:`ThreadTuner` which count to use for the next one. The tuner alternates two phases:

- **probe**: a window of steps with each candidate count (the most allowed, half of it,
  one), in the order A B .. B A so that a flow that slowly gets more expensive favours
  none; a window lasts about ``window_s`` of wall time whatever the count (at least
  ``min_steps`` steps), and each candidate's time per step is the mean over its two;
- **use**: the fastest candidate, then probe again (another job may have started or
  stopped on the machine). The last choice is kept unless another count is faster by more
  than ``MARGIN`` (3 %): counts within the timing noise of each other do not make the run
  switch back and forth.

The cost of probing is the time its windows spend on slower counts (their excess over the
chosen count's time for the same steps). The use phase lasts ``excess / budget`` of wall
time, so that probing costs at most ``budget`` (2 %) of the run on any number of cores
(with 16 threads the one-thread windows are ~10x slower per step; the use phase grows to
match); it doubles each time a probe keeps the choice, up to ``MAX_USE_S``. Measured on
two cores by ``benchmarks/speed/bench_loaded.py`` (docs/explanation/performance.md).
"""

from __future__ import annotations

import numba

WINDOW_S = 0.03  # wall time of one probe window
MIN_STEPS = 4  # steps per window, at least
BUDGET = 0.02  # the share of the run's wall time that probing may cost
MAX_USE_S = 30.0  # longest use phase (wall time) between probes
WARMUP_STEPS = 3  # the first steps compile or fill caches: not timed
MARGIN = 0.03  # another count is chosen when it is this much faster than the last choice


def candidates(most: int) -> list[int]:
    """Thread counts worth comparing: all, half and one (distinct, largest first)."""
    return sorted({most, max(most // 2, 1), 1}, reverse=True)


class ThreadTuner:
    """Picks numba's thread count step by step from measured step times (module docstring).

    ``most``: the largest count to use; ``adapt = False`` or ``most = 1``: always ``most``."""

    def __init__(self, most: int, adapt: bool = True, window_s: float = WINDOW_S, min_steps: int = MIN_STEPS,
                 budget: float = BUDGET, max_use_s: float = MAX_USE_S):
        self.counts = candidates(most) if adapt else [most]
        self.window_s, self.min_steps, self.budget, self.max_use_s = window_s, min_steps, budget, max_use_s
        self.current = self.chosen = self.counts[0]
        self.steps = {c: 0 for c in self.counts}  # steps taken with each count
        self.probes: list[dict[int, float]] = []  # s per step of each count, per probe
        self._skip = WARMUP_STEPS
        self._plan: list[int] = []  # counts of the probe windows still to run
        self._windows: list[tuple[int, int, float]] = []  # this probe's (count, steps, seconds)
        self._n = 0  # steps of the current window
        self._spent = 0.0  # its wall time
        self._use_left = 0.0  # wall time left in the use phase
        self._stretch = 1.0  # use-phase factor, doubled while the choice holds
        if self.active:
            self._start_probe()

    @property
    def active(self) -> bool:
        return len(self.counts) > 1

    def _start_probe(self):
        self._plan = self.counts + self.counts[::-1]
        self._windows = []
        self._next_window()

    def _next_window(self):
        self.current = self._plan.pop(0)
        self._n, self._spent = 0, 0.0

    def after_step(self, seconds: float) -> int:
        """Record the wall time of the step just taken; return the count for the next one."""
        self.steps[self.current] += 1
        if not self.active:
            return self.current
        if self._skip > 0:  # compiling or filling caches
            self._skip -= 1
            return self.current
        if self._use_left > 0.0:  # use phase
            self._use_left -= seconds
            if self._use_left <= 0.0:
                self._start_probe()
            return self.current
        self._n += 1
        self._spent += seconds
        if self._n >= self.min_steps and self._spent >= self.window_s:
            self._windows.append((self.current, self._n, self._spent))
            if self._plan:
                self._next_window()
            else:
                self._n = 0
                self._choose()
        return self.current

    def _choose(self):
        steps = {c: 0 for c in self.counts}
        spent = {c: 0.0 for c in self.counts}
        for c, n, t in self._windows:
            steps[c] += n
            spent[c] += t
        per_step = {c: spent[c] / steps[c] for c in self.counts}
        best = min(per_step, key=per_step.get)
        kept = per_step[self.chosen] <= (1.0 + MARGIN) * per_step[best]  # a change must pay clearly
        if not kept:
            self.chosen = best
        self._stretch = min(2.0 * self._stretch, 64.0) if kept else 1.0
        self.current = self.chosen
        self.probes.append(per_step)
        # what the probe cost against running its steps with the chosen count
        excess = sum(t - n * per_step[self.chosen] for _, n, t in self._windows)
        self._windows = []
        # at least four probes' length (counts within noise of each other cost ~nothing to probe)
        use = max(excess / self.budget, 8 * len(self.counts) * self.window_s)
        self._use_left = min(self._stretch * use, self.max_use_s)

    def summary(self) -> dict:
        """What summary.json says about the threads: steps per count, probes, last choice."""
        return {"counts": self.counts, "adaptive": self.active, "probes": len(self.probes),
                "steps_per_count": {str(c): n for c, n in self.steps.items()},
                "last_probe_us_per_step": {str(c): round(t * 1e6, 1) for c, t in self.probes[-1].items()}
                if self.probes else {}}


def tuner_for(config: dict) -> ThreadTuner:
    """The tuner a case's ``[parallel]`` table asks for: ``threads`` caps the count (0: the
    count numba uses when the run starts, ``NUMBA_NUM_THREADS`` unless the caller set
    another), ``adapt`` switches the measuring on or off."""
    most = numba.get_num_threads()
    if config["parallel"]["threads"]:
        most = min(most, config["parallel"]["threads"])
    return ThreadTuner(most, adapt=config["parallel"]["adapt"])
