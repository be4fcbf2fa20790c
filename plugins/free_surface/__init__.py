"""The ``free_surface`` plugin: particles at the free surface are held at zero pressure.

The seed paper (section 4.2) marks the free-surface particles of its dam break and applies
the constant (zero) pressure condition to them at every iteration. Detection: the
divergence of position (see :mod:`.detect`) below ``threshold`` (default 1.5 in 2D,
2.4 in 3D; Lee et al. 2008), with wall images so that particles along a wall are not
taken for a surface. Fires in ``sph_before_forces``: the momentum equation of that force
evaluation sees p = 0 there, and so does the output; the density of those particles is
held at rho0, the density of zero Tait pressure.
"""

from __future__ import annotations

import numpy as np

from sphcore.api import CaseError, CellGrid, Option, hookimpl

from .detect import position_divergence


class FreeSurfacePlugin:
    @hookimpl
    def sph_options(self):
        return {"free_surface": {
            "threshold": Option(None, "float", doc="div r below which a particle is at the free surface; "
                                "1.5 in 2D, 2.4 in 3D when unset", positive=True, nullable=True),
            "mirror_walls": Option(True, "bool", doc="count wall images in div r, so walls are not surfaces"),
        }}

    @hookimpl
    def sph_configure(self, case):
        cfg = case.config["free_surface"]
        if not case.config["physics"]["sph"]:
            raise CaseError(case.file, "plugins.use", "free_surface needs physics.sph = true")
        if case.config["scheme"]["name"] == "dfsph":
            # the surface is held in the rates' pressure, which dfsph does not read: its solves
            # would still give those particles a pressure
            raise CaseError(case.file, "plugins.use", "free_surface sets the equation of state's pressure, which dfsph "
                            "does not use (its solves keep the free surface at zero pressure themselves): remove it "
                            "with scheme.name = \"dfsph\"")
        self.threshold = cfg["threshold"] or (1.5 if case.dim == 2 else 2.4)
        self.mirror = cfg["mirror_walls"]
        self.normals = np.ascontiguousarray(case.planes.normals)
        self.offsets = np.ascontiguousarray(case.planes.offsets)
        self.div = np.zeros(0)
        self.count = 0

    @hookimpl
    def sph_before_forces(self, ctx):
        st = ctx.state
        if self.div.shape[0] != st.n:
            self.div = np.zeros(st.n)
        grid = CellGrid(st.pos, ctx.params.support)
        position_divergence(st.n, st.pos, st.rho, st.m, grid.view, ctx.params, self.normals, self.offsets,
                            self.mirror, self.div)
        surface = self.div < self.threshold
        # p = 0 and rho = rho0 together: the Tait pressure of rho0 is zero, so the surface
        # density cannot drift away from the pressure it is held at (without this the
        # continuity density of separating surface particles falls without bound)
        ctx.force_pressure[surface] = 0.0
        st.rho[surface] = ctx.params.rho0
        self.count = int(surface.sum())
        ctx.stats(self)["free_surface_particles"] = self.count

