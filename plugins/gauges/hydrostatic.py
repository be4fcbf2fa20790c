"""The ``pressure_gauge`` plugin: how well a tank of water stays at rest.

At the end of a run it reports, against the initial state: the largest particle
displacement (m), over all particles and over those that started below the top
``skip_layers`` layers, the free-surface drift (m, highest particle), and the pressure profile
error: the pressure averaged over each horizontal particle layer against rho0 g (H - y),
H the initial free-surface level, largest relative error over the layers below the top
two (the validation criterion of the seed paper's hydrostatic case). The reference is the
incompressible one: the exact hydrostatic pressure of the weakly compressible Tait fluid,
which the core's hydrostatic start gives, exceeds it by about g d / (2 c0^2) at depth d
(0.25 % at the bottom of a column with c0 = 10 sqrt(2 g H)), and that counts as error.
"""

from __future__ import annotations

import numpy as np

from sphcore.api import Option, hookimpl


def layer_errors(y, p, dx, H, rho0, g):
    """(layer mean height, mean pressure, hydrostatic pressure, relative error) per layer."""
    layer = np.floor(y / dx).astype(int)
    rows = []
    for k in np.unique(layer):
        sel = layer == k
        ym = float(y[sel].mean())
        ph = rho0 * g * (H - ym)
        pm = float(p[sel].mean())
        rows.append((ym, pm, ph, (pm - ph) / ph if ph > 0 else np.nan))
    return np.array(rows)


def worst_layer_error(rows, H, dx, skip):
    """The largest |relative error| of the layers of ``rows`` (:func:`layer_errors`) whose mean
    height lies below the top ``skip`` layers of a column H high; NaN when none does."""
    below = rows[:, 0] < H - skip * dx
    return float(np.nanmax(np.abs(rows[below, 3]))) if below.any() else float("nan")


class PressureGauge:
    @hookimpl
    def sph_options(self):
        return {"pressure_gauge": {
            "skip_layers": Option(2, "int", doc="top particle layers left out of the pressure criterion", min=0),
        }}

    @hookimpl
    def sph_configure(self, case):
        self.skip = case.config["pressure_gauge"]["skip_layers"]

    @hookimpl
    def sph_setup(self, ctx):
        # the initial state is the reference: kept in the checkpoint, so a restarted run is
        # still measured against the start of the run, not the restart point
        kept = ctx.kept(self)
        if "pos0" not in kept:
            st = ctx.state
            order = np.argsort(st.id)
            pos0 = st.pos[order].copy()
            # blocks are filled dx/2 from their faces: floor and free surface lie half a
            # spacing beyond the outermost centres (the contact radius may differ)
            half = 0.5 * ctx.params.dx
            floor = float((pos0 @ ctx.params.up).min() - half) if ctx.params.g_abs > 0 else 0.0
            kept.update(ids0=st.id[order].copy(), pos0=pos0, floor=floor,
                        H=float((pos0 @ ctx.params.up).max() + half) - floor)
        self.ids0, self.pos0, self.floor, self.H = kept["ids0"], kept["pos0"], kept["floor"], kept["H"]

    @hookimpl
    def sph_summary(self, ctx):
        st = ctx.state
        order = np.argsort(st.id)
        pos, p = st.pos[order], st.p[order]
        if not np.array_equal(st.id[order], self.ids0):
            return {"particles_lost": int(self.ids0.size - st.n)}
        z = pos @ ctx.params.up - self.floor
        dx = ctx.params.dx  # layers one initial spacing thick (not the contact radius, which a case may set)
        rows = layer_errors(z, p, dx, self.H, ctx.params.rho0, ctx.params.g_abs)
        moved = np.linalg.norm(pos - self.pos0, axis=1)
        deep = (self.pos0 @ ctx.params.up - self.floor) < self.H - self.skip * dx  # started below the top layers
        return {
            "particles_lost": 0,
            "max_displacement_m": float(moved.max()),
            "max_displacement_below_top_m": float(moved[deep].max()) if deep.any() else float("nan"),
            "surface_drift_m": float(z.max() + dx / 2 - self.H),
            "pressure_max_layer_err": worst_layer_error(rows, self.H, dx, self.skip),
        }
