"""Semi-analytical (boundary-integral) walls as the sphcore plugin ``wall_integral``.

The reflective boundary keeps particles inside but leaves their kernel support truncated at
the walls: a particle near a wall misses part of its density sum and feels no wall pressure.
This plugin completes the sums with the wall's exact share of each particle's kernel
support, computed from the wall planes (``share.wall_terms``: closed forms for planes,
corners and wedges of any angle, 2D and 3D). Through the core's ``sph_wall_terms`` hook it
supplies, per particle, the wall share s, its gradient G and the hydrostatic moment T g,
and the core then solves (:mod:`sphcore.equations`)

    drho_i/dt = (sum_j m_j v_ij . grad W_ij + rho_i v_i . G_i) / gamma_i
    dv_i/dt   = g - (sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) grad W_ij
                     + 2 (p_i/rho_i) G_i + ((rho_i - rho_ref)/rho_i) T_i g) / gamma_i,
    gamma_i = 1 - s_i,

the renormalised semi-analytical wall of Kulasegaram et al. (2004) and Ferrand et al.
(2013) with the wall pressure extrapolated hydrostatically from the particle (Ferrand's p_s
with the hydrostatic term; Mayrhofer et al. 2015 discuss the same consistency). Why this
formulation: it needs no wall particles (the paper's walls stay planes), it is exact for
the geometry (no quadrature error at corners), and in the continuum limit it makes water at
rest hydrostatic for any wall shape: the truncated pair sum is gamma grad p - 2 p_i G - M grad p,
so adding 2 p_i G + rho T g (T g = M g) and dividing by gamma leaves grad p = rho g.

Use it beside ``reflective`` (which keeps every particle inside; the wall model adds the
wall's pressure and density): ``[plugins] use = ["reflective", "wall_integral", ...]``.

Case table::

    [wall_integral]
    hydrostatic = true   # extrapolate the wall pressure hydrostatically (T g term); false: p_wall = p_i

Run summary (under "wall_integral"): ``near_wall_last`` particles within 2h of a wall at
the last force evaluation.
"""

from __future__ import annotations

import numpy as np

from sphcore.api import CaseError, Option, hookimpl

from .normals import near_wall_projector
from .share import wall_terms

TABLE = "wall_integral"


class WallIntegralPlugin:
    """Boundary-integral wall terms of the case's planes; one instance per run."""

    def __init__(self):
        self.share = np.zeros(0)
        self.grad = np.zeros((0, 2))
        self.hydro = np.zeros((0, 2))

    @hookimpl
    def sph_options(self):
        return {TABLE: {
            "hydrostatic": Option(True, "bool", doc="extrapolate the wall pressure hydrostatically from each "
                                  "particle (the T g term); false takes the wall pressure equal to the particle's"),
        }}

    @hookimpl
    def sph_configure(self, case):
        file = getattr(case, "file", "case.toml")
        if not case.config["physics"]["sph"]:
            raise CaseError(file, "plugins.use", "wall_integral completes SPH sums; physics.sph is false")
        if case.planes.count == 0:
            raise CaseError(file, "plugins.use", "wall_integral needs wall planes ([domain] min/max or planes)")
        self.normals = np.ascontiguousarray(case.planes.normals, dtype=np.float64)
        self.offsets = np.ascontiguousarray(case.planes.offsets, dtype=np.float64)
        self.hydrostatic = case.config[TABLE]["hydrostatic"]

    @hookimpl
    def sph_wall_terms(self, ctx, terms):
        st, prm = ctx.state, ctx.params
        n, dim = st.n, prm.dim
        if self.share.shape[0] != n:
            self.share, self.grad, self.hydro = np.zeros(n), np.zeros((n, dim)), np.zeros((n, dim))
        gravity = prm.gravity if self.hydrostatic else np.zeros(3)
        wall_terms(st.pos, self.normals, self.offsets, prm.kernel_id, prm.h, gravity, self.share, self.grad,
                   self.hydro)
        np.add(terms.share, self.share, out=terms.share)  # several wall plugins add up
        np.add(terms.grad, self.grad, out=terms.grad)
        np.add(terms.hydro, self.hydro, out=terms.hydro)
        near_wall_projector(st.pos, self.normals, self.offsets, prm.support, terms.normals)
        ctx.stats(self)["near_wall_last"] = int(np.count_nonzero(self.share))
