"""Progress while a run goes: a bar on a terminal, a plain line at a steady interval in a log."""

from __future__ import annotations

import sys
import time

from sphcore.run.activities import WallInterval


class Progress:
    """Shows simulated time, ETA, steps per second and particle-steps per second."""

    def __init__(self, t_end: float, n: int, mode: str = "auto", interval_s: float = 10.0, stream=None):
        self.stream = stream or sys.stderr
        if mode == "auto":
            mode = "bar" if self.stream.isatty() else "log"
        self.mode, self.t_end, self.n, self.interval = mode, t_end, n, interval_s
        # when a line is due (log) or a redraw (bar: at most ten a second)
        self.schedule = WallInterval(0.1 if mode == "bar" else interval_s)
        self.start = time.perf_counter()
        self.steps0 = None
        self.t0 = 0.0  # simulated time at the first update (a restart starts later)
        self.bar = None
        if mode == "bar":
            from tqdm import tqdm

            self.bar = tqdm(total=t_end, unit="s", unit_scale=False, file=self.stream, dynamic_ncols=True,
                            bar_format="{l_bar}{bar}| t={n:.4g}/{total:.4g} s [{elapsed}<{remaining}{postfix}]")

    def rates(self, step):
        el = max(time.perf_counter() - self.start, 1e-9)
        steps = step - (self.steps0 or 0)
        return steps / el, steps * self.n / el

    def update(self, sim):
        """After a step: the first call starts the clocks, later ones draw or log when
        ``schedule`` is due."""
        if self.steps0 is None:
            # rates and the ETA count from the end of the first step: that step compiles the
            # kernels on a first run (~10 s), which would otherwise inflate the first ETA
            self.steps0, self.t0 = sim.step, sim.t
            self.start = time.perf_counter()
            self.schedule.restart()
            if self.bar is not None:  # tqdm's own clock and rate start here too
                self.bar.reset(total=self.t_end)
                self.bar.initial = self.bar.n = min(sim.t, self.t_end)
                self.bar.refresh()
            return
        if self.mode == "off":
            return
        if not self.schedule.due() and not (self.bar is not None and sim.t >= self.t_end):
            return  # the last state is always drawn
        now = time.perf_counter()
        if self.bar is not None:
            sps, psps = self.rates(sim.step)
            self.bar.n = min(sim.t, self.t_end)
            self.bar.set_postfix_str(f"{sps:.0f} steps/s, {psps:.3g} particle-steps/s", refresh=False)
            self.bar.refresh()
            return
        sps, psps = self.rates(sim.step)
        frac = sim.t / self.t_end
        done = (sim.t - self.t0) / max(self.t_end - self.t0, 1e-300)  # of this process's share
        eta = (now - self.start) * (1 - done) / done if done > 0 else float("nan")
        eta_text = f"{eta:.0f}" if eta < 1e7 else f"{eta:.2g}"  # never a 300-digit number
        print(f"[sph] t = {sim.t:.5g}/{self.t_end:.5g} s ({100 * frac:.1f}%), step {sim.step}, "
              f"dt = {sim.dt:.3g} s, {sps:.0f} steps/s, {psps:.3g} particle-steps/s, ETA {eta_text} s",
              file=self.stream, flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()
