"""Divergence-free SPH (DFSPH; Bender & Koschier 2015, 2017): the incompressible scheme.

``[scheme] name = "dfsph"``. The pressure is not a function of the density, as in the
weakly compressible scheme, but the solution of two constraints solved every step, so
the step follows the flow (a CFL number on the flow's velocity) instead of an artificial
sound speed ten times faster than the flow. A step (Bender & Koschier 2017, Algorithm 2,
written around sphcore's step):

    rates:        a_np = g + viscosity + the walls' hydrostatic push  (pressure zero),
                  summed over the pair list of these positions (the last finish's,
                  renumbered after a reorder; listed here after a restore or restart)
    dt:           cfl h / |v|max, the force and viscous limits, dt_max, plugins' bounds
    free motion:  v* = v + dt a_np
                  density solve: kappa such that rho_i + dt D rho_i(v*) = rho0
                  x += dt v*
    [walls]       the reflective boundary corrects x and v (sph_after_integrate)
    finish:       pairs, density and diagonal at the new positions
                  divergence solve: kappa_v such that D rho_i(v) = 0

with kappa = p / rho the solves' variable: the pressure acceleration of particle i is
a_i = -sum_j m_j (kappa_i/rho_i + kappa_j/rho_j) grad_i W_ij - 2 (kappa_i/rho_i) rho0 G_i,
the last term the wall's, the mirror image of the particle over the walls' share of its
support (G the share's gradient from the wall model, :class:`sphcore.physics.equations.WallTerms`).
The density is the kernel sum plus the walls' part, rho_i = sum_j m_j W_ij / sigma0 +
w_i, sigma0 the kernel sum of the initial lattice and w_i = rho0 s_i at the start, s_i the
walls' share measured against that lattice (the wall model's ``fill``), so that the initial
lattice is at rho0 exactly, next to walls too; w_i then follows the rate below
(:meth:`DivergenceFree._move_walls_density`), so it is not rho0 s_i once the particle has
moved. Its rate is D rho_i = [sum_j m_j v_ij . grad W_ij +
2 rho0 (v_i - v_w) . G_i] / sigma0: the walls' part is the mirror image's, which comes
towards the particle at twice its normal velocity, as the wall's force is the image's
(twice the particle's own pressure). With the same factor 2 in the rate as in the force, the
pressure kick is the density rate's adjoint and each solve's operator is symmetric
(``tests/test_solve_operator.py``). With the factor 1 of the walls' share alone, the
operator was not: the wall terms then drove a circulation in water at rest (down the side
walls, up the middle) that grew for as long as the run; the 3D tank's largest displacement
from 1 s to 5 s was 9.9 dx, against 1.9 dx symmetric
(``benchmarks/accuracy/tank_at_rest_splishsplash.py``).

Each solve is projected Jacobi on kappa with the diagonal of Bender & Koschier (Eq. 9,
the wall terms added; :func:`sphcore.physics.solvepairs.diagonal`), accelerated by
Chebyshev polynomials (:mod:`sphcore.physics.pressuresolve`). A solve iterates until the
mean error falls below the tolerance (density: |rho* - rho0| / rho0; divergence:
dt |D rho| / rho0) after at least two (density) and one (divergence) iterations. kappa
never falls below zero (the pressure pushes, never pulls): a particle at zero pressure that
expands is at the free surface and counts no error. With ``[scheme] error = "compression"``
the error counts compression only (max(rho* - rho0, 0), SPlisHSPlasH's measure); the
iterations still correct expansion. The divergence solve leaves particles with a thin
neighbourhood alone (``FULL_SHARE``).

Warm start: each solve starts from the last step's kappa. The density solve's is first
replaced by its kernel average about the hydrostatic part (kappa - g . x averaged, so that
a fluid at rest keeps its pressure next to walls and the surface too): the symmetric
gradient does not see a kappa that alternates between particle layers, so the solves
neither make nor remove it, and what each solve leaves in that mode would accumulate
through a raw warm start.

The pressure the particles report (``state.p``) is rho kappa of the density solve. The
walls' hydrostatic push (the mirror fluid's pressure grows with depth across the wall) is
the wall model's completion with the solved pressure set to zero, in the rates: it is
known from the positions alone.
"""

from __future__ import annotations

import numpy as np

from sphcore.physics import pressuresolve
from sphcore.physics import solvepairs as sp
from sphcore.physics.forces import PressureField
from sphcore.physics.integrators import SchemeBase
from sphcore.physics.kernels import kernel_w
from sphcore.physics.solvelist import SolveList

# the divergence solve corrects only particles with at least this share of a full
# neighbourhood (the lattice's neighbours; a wall counts with its share of the support):
# a splash or surface particle with few partners has a near-zero diagonal, and a pair of
# droplets closing in at the support's edge took kappa_v = 3e9 and flew off at 5 km/s (the
# Buchner dam break at 1.25 s). SPlisHSPlasH's DFSPH skips such particles likewise (7 of 8
# lattice neighbours in 2D, 20 of 26 in 3D at its support of 2 dx).
FULL_SHARE = 0.75
KEPT = "dfsph"  # the run state's namespace of the warm starts (run.kept) and the solves' figures
# run.kept[KEPT][MEASURED]: the walls' part of the density was measured (at the run's first listing; in
# the run state, so that a restored snapshot taken before that listing measures it again)
MEASURED = "walls_measured"


class SolvedPressure(PressureField):
    """The pressure of the divergence-free scheme: ``state.p`` is set by the solves, and the
    rates see a zero pressure (the non-pressure accelerations)."""

    def __init__(self, prm):
        super().__init__(prm)
        self._zero = np.zeros(0)

    def force_pressure(self, state) -> np.ndarray:
        if self._zero.shape[0] != state.n:
            self._zero = np.zeros(state.n)
        return self._zero

    def update(self, state, counters):
        """No equation of state: the solves set the pressure."""


class DivergenceFree(SchemeBase):
    """The DFSPH step (module docstring), with the interface of the weakly compressible
    integrators (:mod:`sphcore.physics.integrators`): :meth:`rates`, :meth:`free_motion`,
    then the walls, then :meth:`finish`.

    ``run``: the run state; ``forces``: the run's :class:`sphcore.physics.forces.Forces`
    (its rates with zero pressure are the non-pressure accelerations, its wall terms the
    solves' walls); ``ctx``: the run context (clock, stats); ``scheme``: the case's
    ``[scheme]`` table.
    """

    name = "dfsph"

    def __init__(self, run, forces, ctx, scheme: dict):
        prm = ctx.params
        self.forces, self.ctx = forces, ctx
        self.tol_density = scheme["density_tolerance"]
        self.tol_divergence = scheme["divergence_tolerance"]
        self.max_iterations = scheme["max_iterations"]
        self.compression_only = scheme["error"] == "compression"  # the solves' error counts compression only
        self.sigma = sp.lattice_sum(prm.kernel_id, prm.h, prm.dx, prm.dim)
        self.inv_sigma = 1.0 / self.sigma
        # the Chebyshev interval of the diagonal-scaled operator (module docstring)
        lam = sp.lattice_eigenvalue(prm.kernel_id, prm.h, prm.dx, prm.dim)
        self.spectrum = pressuresolve.chebyshev_interval(lam)
        self.w0 = kernel_w(prm.kernel_id, 0.0, prm.h, prm.dim)
        self.full = self.sigma - prm.dx ** prm.dim * self.w0  # a full neighbourhood's sum_j V_j W_ij (self excluded)
        self.pairs = SolveList(prm, ctx)  # the pair list, listed at the positions pairs.mark holds
        self.one_mass = None  # the particles' one mass at the last listing, None if they differ
        self.n_full = self.pairs.n_full  # a full neighbourhood's partners
        # the walls' hydrostatic push, scaled from the lattice's gradient to the solved one's
        self.push_excess = 1.0 / prm.moment_norm - 1.0
        forces.records_reaction = True
        forces.density_rates = False  # the density is summed (the rates' drho is not read)
        forces.reuse_wall_terms = True  # the step's rates read the terms the last finish computed
        forces.listed = self._pairs_now  # the rates sum over the solves' pair list
        # the rates with zero pressure (SolvedPressure) are the non-pressure accelerations
        super().__init__(run, forces.evaluate, evolves_density=False)

    # -- arrays ---------------------------------------------------------------------------

    def _extra_arrays(self, n, dim):
        self.pairs.resize(n)
        self.alpha = np.zeros(n)
        self.alpha_v = np.zeros(n)
        self.partners = np.zeros(n)
        self.thick = np.zeros(n, bool)  # a neighbourhood full enough for the divergence solve
        self.rate = np.zeros(n)
        self.dkappa = np.zeros(n)
        self.step_d = np.zeros(n)
        self.kick_ratio = np.zeros(n)
        self.err = np.zeros(n)
        self.moved = np.zeros(n)
        self.kick = np.zeros((n, dim))
        self.grad_start = np.zeros((n, dim))
        self.no_walls = np.zeros((n, dim))  # the wall gradient of a run without wall terms
        self.no_flux = np.zeros(0)
        self.rho0_base = np.full(n, self.ctx.params.rho0)
        self.impulse = np.zeros((n, dim))  # the walls' impulse of the last solve (ctx.solved_impulse)
        if getattr(self.ctx.case, "moving", ()):  # walls that move: their loads take it from the start
            self.ctx.solved_impulse = self.impulse
        st = self.run.particles
        kept = self.run.kept.setdefault(KEPT, {})
        for key in ("kappa", "kappa_v", "wall_rho"):
            if key not in kept or kept[key].shape != (n,):
                kept[key] = np.zeros(n)
                kept[MEASURED] = False
        kept.setdefault(MEASURED, True)  # a checkpoint's run measured them
        if not self.ctx.restarting and not np.any(kept["kappa"]):
            # the start's hydrostatic pressure, at the gradient the lattice holds itself with (rates)
            kept["kappa"][:] = st.p / st.rho / self.ctx.params.moment_norm

    def reorder_plan(self, forces):
        """The order of the pair list's cells (:meth:`sphcore.physics.solvelist.SolveList.plan`)."""
        return self.pairs.plan(self.run.particles)

    def permute(self, order):
        """Follow a reordering of the particles: the rates, the warm starts and the walls'
        density part move with them, and so does the pair list: particle k's row is the old
        row of ``order[k]``, where it lies, its partners renumbered (a reorder comes at the
        start of a step, at the positions the last finish listed the pairs at: listing them
        again cost a fill, 37 of 395 in the 3D dam break). The walls' terms are taken again in
        the new order at the next listing's check."""
        super().permute(order)
        kept = self.run.kept[KEPT]
        for key in ("kappa", "kappa_v", "wall_rho"):
            kept[key] = kept[key][order]
        self.alpha[...] = self.alpha[order]
        self.pairs.permute(order)

    def restored(self):
        """The pairs were listed at a state that was undone (the start-up probe's rates):
        listed again at the next call, with the summed density they write into the state."""
        self.pairs.mark.clear()

    # -- the step -------------------------------------------------------------------------

    def rates(self):
        """The non-pressure accelerations: the rates with zero pressure, summed over the
        solves' pair list of the current positions (:mod:`sphcore.physics.listedrates`; the
        list is made here when a new run, a restart or a restored snapshot left none), the
        walls' hydrostatic push divided by lambda.

        The SPH gradient of a linear pressure on the lattice is lambda times the exact one
        (``Params.moment_norm``, 0.974 in 2D at h = 1.3 dx), so water at rest holds itself
        with a solved kappa whose gradient is g / lambda. The wall model's push extrapolates
        the mirror fluid's pressure with g: a column along a side wall was then held up by
        0.57 % of g less than the interior (the still tank at h = 1.3 dx), a shear the
        density solve does not see, and it sank. Extrapolated with g / lambda, the push is
        the completion's acceleration (``WallTerms.react``, with zero pressure) over lambda."""
        r = self.run.rates
        if r.fresh:
            return
        self._list_pairs(self.forces.wall_terms)
        self.rates_fn(r.acc, r.drho)
        react = self.forces.wall_react()
        if react is not None:
            np.multiply(react, self.push_excess, out=self.kick)
            r.acc += self.kick
        r.fresh = True

    def free_motion(self, dt):
        """v* = v + dt a_np, the density solve, x += dt v* (``pos0`` keeps x)."""
        st = self.run.particles
        self.rates()
        self._list_pairs(self.forces.wall_terms)
        np.multiply(self.run.rates.acc, dt, out=self.kick)
        st.vel += self.kick
        kept = self.run.kept[KEPT]
        smooth = self.dkappa  # scratch until the iterations (err and rate too)
        pl = self.pairs
        sp.run_pass(sp.kernel_average, smooth, pl.start, pl.end, pl.nb, pl.w, st.m, st.rho, st.pos,
                    kept["kappa"], self.ctx.params.gravity, self.w0, self.err, self.rate)
        np.maximum(smooth, 0.0, out=kept["kappa"])
        n_it, err = self._solve(kept["kappa"], st.rho, dt, self.tol_density, 2, "density")
        self._record("density", n_it, err)
        self._wall_impulse(kept["kappa"], dt)
        self.pos0[...] = st.pos
        np.multiply(st.vel, dt, out=self.kick)
        st.pos += self.kick
        self.grad_start[...] = self.grad

    def finish(self, dt) -> bool:
        """The pairs at the new positions, then the divergence solve; ``state.p`` = rho kappa."""
        st = self.run.particles
        wall = self.forces.wall_terms()
        if wall.active:
            self._move_walls_density(wall, dt)
        self._list_pairs(lambda: wall)
        kept = self.run.kept[KEPT]
        # the partners, a wall counted by its share: full neighbourhoods take part (FULL_SHARE)
        np.multiply(kept["wall_rho"], self.n_full / self.ctx.params.rho0, out=self.partners)
        self.partners += self.pairs.counts
        np.greater_equal(self.partners, FULL_SHARE * self.n_full, out=self.thick)
        np.multiply(self.alpha, self.thick, out=self.alpha_v)
        np.multiply(kept["kappa_v"], self.thick, out=kept["kappa_v"])
        n_it, err = self._solve(kept["kappa_v"], self.rho0_base, dt, self.tol_divergence, 1, "divergence",
                                self.alpha_v)
        self._record("divergence", n_it, err)
        self._wall_impulse(kept["kappa_v"], dt)
        np.multiply(st.rho, kept["kappa"], out=st.p)
        self.run.rates.fresh = False
        return False

    # -- pieces ---------------------------------------------------------------------------

    def _pairs_now(self):
        """The pair list (start, end, nb, w, g) when it was listed at the current state, else
        None (the rates then walk the cells)."""
        pl = self.pairs
        if not pl.mark.holds(self.run.particles):
            return None
        return pl.start, pl.end, pl.nb, pl.w, pl.g

    def _list_pairs(self, wall_terms):
        """The pairs, the summed density (into ``state.rho``), the diagonal and the
        walls' terms of the current positions; only the walls' terms when they were listed
        there (the wall terms of the state, reused, or taken in a reorder's new order)."""
        st, prm, pl = self.run.particles, self.ctx.params, self.pairs
        if pl.mark.holds(st):
            self._walls(wall_terms())
            return
        pl.fill(st)
        self._walls(wall_terms())
        self.one_mass = sp.one_mass(st.m)
        m = self.masses()
        sp.run_pass(sp.summed_density, st.rho, pl.start, pl.end, pl.nb, pl.w, m, self.w0, self.inv_sigma,
                    self.run.kept[KEPT]["wall_rho"])
        sp.run_pass(sp.diagonal, self.alpha, pl.start, pl.end, pl.nb, pl.g, m, st.rho, self.grad, prm.rho0,
                    self.inv_sigma)
        pl.mark.mark(st)
        self.ctx.counters["dfsph_pair_lists"] += 1

    def masses(self):
        """The masses as the passes take them: the one mass of all the particles at the last
        listing, else the array (:func:`sphcore.physics.solvepairs.one_mass`)."""
        return self.run.particles.m if self.one_mass is None else self.one_mass

    def _walls(self, wall):
        """The wall gradient and velocity the solves use; the walls' part of the density
        (``run.kept``) measured at the start of a run (:meth:`_start_walls_density`)."""
        n = self.run.particles.n
        if not wall.active:
            self.grad, self.flux = self.no_walls, self.no_flux
            return
        if not self.run.kept[KEPT][MEASURED]:
            self._start_walls_density(wall)
        self.grad = wall.grad
        self.flux = wall.flux if wall.flux.shape[0] == n else self.no_flux

    def _start_walls_density(self, wall):
        """rho0 s_i, s_i the walls' share of particle i's support measured against the
        initial lattice: 1 - (V W(0) + fill_i) / sigma0, ``fill`` the sum sum_j V_j W_ij a
        lattice particle has there (the wall model's), so that the initial lattice is at
        rho0 next to walls too; the plain share where the wall model gives no fill."""
        share, fill = wall.share, wall.fill
        s = np.where(fill > 0.0, (self.full - fill) * self.inv_sigma, share)
        self.run.kept[KEPT]["wall_rho"][:] = np.where(share > 0.0, s, 0.0) * self.ctx.params.rho0
        self.run.kept[KEPT][MEASURED] = True

    def _move_walls_density(self, wall, dt):
        """The walls' part of the density follows the step's displacement as the walls
        corrected it: 2 rho0 (G_n + G_n+1) / 2 . (x_n+1 - x_n) / sigma0, minus
        2 rho0 dt v_w . G / sigma0 for walls that move, the rate the density solve predicted
        with (the mirror image's, module docstring). Taken from the
        positions alone (rho0 s(x)), it would differ from the prediction, by the lattice
        error of the wall gradient already with the factor 1, which the solves then meet
        again every step (measured then: the floor's layer of the 2D dam break crept 0.3 %
        above rho0 in 300 steps and the density solve stalled), and now by the factor 2.
        Zero where no wall is within the support."""
        st, rho0 = self.run.particles, self.ctx.params.rho0
        w = self.run.kept[KEPT]["wall_rho"]
        np.add(self.grad_start, wall.grad, out=self.grad_start)
        self.grad_start *= 0.5
        np.subtract(st.pos, self.pos0, out=self.kick)
        np.einsum("ij,ij->i", self.grad_start, self.kick, out=self.moved)
        self.moved *= 2.0 * rho0 * self.inv_sigma
        w += self.moved
        if wall.flux.shape[0] == st.n:
            w -= 2.0 * rho0 * self.inv_sigma * dt * wall.flux
        w[wall.share <= 0.0] = 0.0
        np.maximum(w, 0.0, out=w)

    def _solve(self, kappa, base, dt, tol, min_it, what, alpha=None):
        """One solve from the warm start ``kappa`` (:func:`sphcore.physics.pressuresolve.solve`);
        ``alpha`` the Jacobi weights, the diagonal's inverse by default. Returns (iterations,
        mean error)."""
        return pressuresolve.solve(self, kappa, base, dt, tol, min_it, what, self.alpha if alpha is None else alpha)

    def _wall_impulse(self, kappa, dt):
        """``ctx.solved_impulse``: the walls' impulse on each particle through the solve just
        made, when walls move (their loads add its opposite). The solve's kicks of the warm
        start and of each change sum to its kappa, so their walls' part is
        -dt m_i 2 rho0 (kappa_i / rho_i) G_i (the mirror image's push, module docstring); the
        pair terms are equal and opposite and give the walls nothing."""
        if not getattr(self.ctx.case, "moving", ()):
            return
        st, kr = self.run.particles, self.kick_ratio  # the solve's scratch, free again
        np.divide(kappa, st.rho, out=kr)
        kr *= st.m
        kr *= -2.0 * self.ctx.params.rho0 * dt
        np.multiply(self.grad, kr[:, None], out=self.impulse)
        self.ctx.solved_impulse = self.impulse

    def _record(self, what, n_it, err):
        """The solves' figures in summary.json (under "dfsph"): iterations a step, the
        largest, and the mean error reached, over the run."""
        fig = self.ctx.stats(KEPT)
        fig[f"{what}_iterations_total"] = fig.get(f"{what}_iterations_total", 0) + n_it
        fig[f"{what}_iterations_max"] = max(fig.get(f"{what}_iterations_max", 0), n_it)
        fig[f"{what}_solves"] = fig.get(f"{what}_solves", 0) + 1
        fig[f"{what}_iterations_mean"] = fig[f"{what}_iterations_total"] / fig[f"{what}_solves"]
        fig[f"{what}_error_sum"] = fig.get(f"{what}_error_sum", 0.0) + err
        fig[f"{what}_error_mean"] = fig[f"{what}_error_sum"] / fig[f"{what}_solves"]
        fig[f"{what}_error_last"] = err
