"""The dam-break surge front: definition, comparison with experiment, and the
``front_gauge`` plugin that records it during a run.

Definition (robust to splashes): take the particles whose centre lies within ``band``
spacings of the floor (the two lowest layers by default); sort them by their distance from
the back wall; walk from the wall while consecutive centres are at most ``gap`` spacings
apart (2 by default). The last particle of that connected chain is the tip, and
x_front = its centre + its radius (the water's edge). A drop separated from the chain by
more than ``gap`` does not count.
"""

from __future__ import annotations

import math

import numpy as np

from sphcore.hookspecs import hookimpl
from sphcore.options import Option
from sphcore.outdir import write_atomically

from . import reference

G = 9.81


def front_position(pos, radius, floor=0.0, band=2.0, gap=2.0, axis=0, up=1) -> float:
    """x (m) of the connected surge tip; see the module docstring."""
    dx = 2.0 * float(np.median(radius))
    near = pos[:, up] - floor < band * dx
    if not near.any():
        return float("nan")
    order = np.argsort(pos[near, axis])
    xs = pos[near, axis][order]
    rs = radius[near][order]
    breaks = np.nonzero(np.diff(xs) > gap * dx)[0]
    tip = breaks[0] if breaks.size else xs.size - 1
    return float(xs[tip] + rs[tip])


def compare(t, x, a=0.114, x_wall=math.inf) -> dict:
    """Front errors against experiment.

    Cruchaga: relative error at its times (interpolated in the series). Martin & Moyce:
    RMS relative error of Z = x/a over their points with T <= 3 that the run covers and
    that lie before the front meets the opposite wall at ``x_wall``.
    """
    t, x = np.asarray(t, float), np.asarray(x, float)
    out = {}
    for tc, xe, xs in reference.cruchaga():
        xi = float(np.interp(tc, t, x)) if t.size and t[0] <= tc <= t[-1] else float("nan")
        out[f"x_front_{tc:.2f}s_m"] = xi
        out[f"err_cruchaga_{tc:.2f}s"] = (xi - xe) / xe
    mm = reference.martin_moyce()
    big_t = t * math.sqrt(2 * G / a)
    sel = (mm[:, 0] <= 3.0) & (mm[:, 0] <= (big_t[-1] if t.size else -1)) & (mm[:, 1] * a < x_wall)
    if sel.any():
        z_sim = np.interp(mm[sel, 0], big_t, x / a)
        out["rms_rel_err_martin_moyce_T3"] = float(np.sqrt(np.mean(((z_sim - mm[sel, 1]) / mm[sel, 1]) ** 2)))
    else:
        out["rms_rel_err_martin_moyce_T3"] = float("nan")
    out["martin_moyce_points"] = int(sel.sum())
    return out


class FrontGauge:
    """Records x_front(t) on a schedule; the run summary gets the errors against experiment
    and ``front.csv`` is written to the output directory."""

    @hookimpl
    def sph_options(self):
        return {"front_gauge": {
            "every_dt": Option(0.005, "float", "s", "sampling interval of the front", positive=True),
            "band": Option(2.0, "float", doc="floor band height, in particle spacings", positive=True),
            "gap": Option(2.0, "float", doc="largest gap inside the connected front, in spacings", positive=True),
            "column_width": Option(None, "float", "m", "initial column width a for Martin & Moyce's scaling; "
                                   "the fluid's initial extent along x when unset", positive=True, nullable=True),
        }}

    @hookimpl
    def sph_configure(self, case):
        self.cfg = case.config["front_gauge"]
        self.floor = float(case.config["domain"]["min"][1]) if case.config["domain"]["min"] else 0.0
        self.x_wall = float(case.config["domain"]["max"][0]) if case.config["domain"]["max"] else math.inf
        self.next_t = 0.0

    @hookimpl
    def sph_setup(self, sim):
        a = self.cfg["column_width"]
        if a is None:
            x = sim.state.pos[:, 0]
            a = float(x.max() - x.min() + 2 * sim.state.radius.max())
        self.a = a
        # samples live in sim.stats, which the checkpoint keeps: a restarted run continues
        # the series instead of starting a new one
        self.samples = sim.stats.setdefault("front_gauge_samples", [])
        if not self.samples:
            self._sample(sim)
        self.next_t = (math.floor(sim.t / self.cfg["every_dt"] + 1e-9) + 1) * self.cfg["every_dt"]

    def _sample(self, sim):
        st = sim.state
        self.samples.append((sim.t, front_position(st.pos, st.radius, self.floor, self.cfg["band"], self.cfg["gap"])))

    @hookimpl
    def sph_after_step(self, sim):
        if sim.t >= self.next_t - 1e-12:
            self._sample(sim)
            self.next_t = (math.floor(sim.t / self.cfg["every_dt"] + 1e-9) + 1) * self.cfg["every_dt"]

    @hookimpl
    def sph_summary(self, sim):
        if not self.samples:
            return None
        t, x = np.array(self.samples).T
        if sim.output_dir is not None and sim.output_dir.exists():
            # atomically (issue 13): a full disk keeps the previous front.csv, no temporary left
            write_atomically(sim.output_dir / "front.csv", lambda tmp: np.savetxt(
                tmp, np.c_[t, x], delimiter=",", header="t_s,x_front_m", comments="", fmt="%.8g"))
        out = compare(t, x, self.a, self.x_wall - 2 * float(np.median(sim.state.radius)))
        out["column_width_m"] = self.a
        return out
