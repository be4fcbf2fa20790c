"""energy_log: the fluid's kinetic energy every ``every_steps`` steps, its peak in the
summary (summary.json, under "energy_log") and the series in energy.csv. Select it with
``[plugins] use = [..., "energy_log"]``; options in ``[energy_log]``."""

import numpy as np

from sphcore.api import FLUID, CaseError, Option, hookimpl


class EnergyLog:
    @hookimpl
    def sph_options(self):
        return {"energy_log": {"every_steps": Option(10, "int", doc="steps between samples", positive=True),
                               "file": Option("energy.csv", "str", doc="series file in the output directory")}}

    @hookimpl
    def sph_configure(self, case):
        self.cfg = case.config["energy_log"]
        if "/" in self.cfg["file"] or self.cfg["file"].startswith("."):
            raise CaseError(case.file, "energy_log.file", "expected a plain file name")

    @hookimpl
    def sph_setup(self, ctx):
        self.series = ctx.kept(self).setdefault("series", [])  # survives a restart

    @hookimpl
    def sph_after_step(self, ctx):
        if ctx.step % self.cfg["every_steps"] == 0:
            st = ctx.state
            fluid = st.kind == FLUID
            e = 0.5 * float(np.sum(st.m[fluid] * np.sum(st.vel[fluid] ** 2, axis=1)))  # J (J/m in 2D)
            self.series.append([ctx.t, e])
            stats = ctx.stats(self)
            if e >= stats.get("kinetic_peak_J", -1.0):
                stats["kinetic_peak_J"], stats["kinetic_peak_t_s"] = e, ctx.t

    @hookimpl
    def sph_finish(self, ctx):
        if ctx.output_dir is not None and self.series:
            np.savetxt(ctx.output_dir / self.cfg["file"], np.array(self.series), delimiter=",",
                       header="t_s,kinetic_J", comments="")
