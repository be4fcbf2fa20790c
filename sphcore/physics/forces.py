"""One force evaluation: the rates (accelerations, density rates) of the current state.

    [hook sph_before_forces] -> sources (fluid + [hook sph_extra_sources]) -> cell grid
    -> [hook sph_wall_terms] -> kernel-gradient matrices (optional) -> pair sums
    (:func:`sphcore.physics.equations.sph_rates`) -> [hook sph_accelerations]

A scheme that keeps a full pair list of the current state (the incompressible scheme's)
offers it in ``Forces.listed``: the pair sums then walk that list instead of the cells
(:mod:`sphcore.physics.listedrates`).

Called by the integrators (:mod:`sphcore.physics.integrators`) whenever they need rates; the
pressure field the momentum equation uses is kept here too (:class:`PressureField`).
Only what the case models runs; ``ctx.counters`` records which kernels did.
"""

from __future__ import annotations

import numba
import numpy as np

from sphcore.errors import CaseError, Instability
from sphcore.neighbours.cellgrid import CellGrid
from sphcore.neighbours.pairlist import PairList
from sphcore.physics import eos
from sphcore.physics.corrections import neighbour_sums
from sphcore.physics.equations import WallTerms, sph_rates, uniform_acceleration
from sphcore.physics.listedrates import listed_rates
from sphcore.physics.pairterms import WORK_COLUMNS
from sphcore.physics.particles import Fields, StateMark


class PressureField:
    """The equation of state applied to the particles.

    ``state.p`` is always the physical pressure (Pa, for output and probes). With modified
    pressure (Batchelor 1967) the momentum equation uses its dynamic part
    P = p - rho0 g (surface_level - z) instead, kept in ``p_dyn``.
    """

    def __init__(self, prm):
        self.prm = prm
        self.p_dyn = np.zeros(0)
        self._z = np.zeros(0)  # scratch: height of each particle (m)

    def force_pressure(self, state) -> np.ndarray:
        """The pressure array the momentum equation uses (Pa)."""
        if not self.prm.modified_pressure:
            return state.p
        if self.p_dyn.shape[0] != state.n:
            self.p_dyn = np.zeros(state.n)
        return self.p_dyn

    def update(self, state, counters):
        """Tait pressure of every particle from its density (:mod:`sphcore.physics.eos`)."""
        prm = self.prm
        if not prm.sph:
            return
        eos.fill_pressure(state.rho, prm.rho0, prm.c0, prm.gamma, prm.p_background, self.force_pressure(state))
        if prm.modified_pressure:
            # p = P + rho0 g (surface - z), in place (this runs twice a step)
            if self._z.shape[0] != state.n:
                self._z = np.zeros(state.n)
            z = self._z
            np.matmul(state.pos, prm.up, out=z)
            np.subtract(prm.surface_level, z, out=z)
            z *= prm.rho0 * prm.g_abs
            np.add(self.p_dyn, z, out=state.p)
        counters["eos"] += 1


def wall_completion(ctx, hook):
    """The compiled completion of a particle's sums that the run's wall model supplies
    (``sph_wall_completion``): one function, however many plugins supply wall terms."""
    found = []
    for fn in hook.sph_wall_completion(dim=ctx.params.dim):
        if fn is not None and all(fn is not f for f in found):
            found.append(fn)
    if len(found) != 1:
        what = "none" if not found else ", ".join(f"{f.__module__}.{f.__name__}" for f in found)
        raise CaseError(getattr(ctx.case, "file", "case.toml"), "plugins.use", "the plugins that supply wall terms (sph_wall_terms) must "
                        f"supply one wall completion (sph_wall_completion); they supply {what}")
    return found[0]


class Forces:
    """Evaluates rates for one run. ``hook``: the run's :class:`sphcore.plugin.pluginhost.HookRelay`;
    ``keep_pairs``: keep a Verlet pair list (``neighbours.skin``) where the run can (a scheme
    that lists its own pairs every step asks for none)."""

    def __init__(self, ctx, hook, pressure: PressureField, keep_pairs: bool = True):
        self.ctx, self.hook, self.pressure = ctx, hook, pressure
        self.wants_walls = "sph_wall_terms" in hook.implemented
        self.completion = wall_completion(ctx, hook) if self.wants_walls else None
        self.n_sources = 0  # plugin sources (ghosts) of the last evaluation
        self.records_reaction = False  # keep WallTerms.react without moving walls (set by the scheme)
        # the density's rate is wanted (a scheme that sums its density, set by it, wants the
        # accelerations only: its evaluations leave the density diffusion out of the pair loop)
        self.density_rates = True
        # the wall terms are reused while the particles, their order and the clock are those
        # they were computed at (set by a scheme that asks for them again at the same state; the
        # plugins' terms then depend on positions and time alone, as the wall model's do when
        # the force pressure is zero)
        self.reuse_wall_terms = False
        self._wall_at = StateMark()  # the state of the last wall terms, when reused
        # a scheme that keeps a full pair list of the current state offers it here: a callable
        # returning (start, end, nb, w, g) (sphcore.physics.listedrates), or None when stale
        self.listed = None
        self._L = np.zeros((1, 3, 3))
        self._grid = None
        skin = ctx.case.config["neighbours"]["skin"] * ctx.params.support
        # plugin sources (ghosts) change every step: such runs walk the cells at every evaluation
        keep = keep_pairs and skin > 0 and ctx.params.sph and "sph_extra_sources" not in hook.implemented
        self.pairs = PairList(ctx.params.support, skin) if keep else None
        self._shepard = np.zeros(1)
        self._work = np.zeros((0, WORK_COLUMNS))
        self._spos = np.zeros((0, ctx.params.dim))
        self._src_buf = None  # fluid + plugin sources, reused between evaluations
        self._wall = WallTerms(np.zeros(0), np.zeros((0, 3)), np.zeros((0, 3)), np.zeros((0, 3, 3)), np.zeros(0),
                               False)

    # -- pieces -----------------------------------------------------------------------

    def sources(self) -> Fields:
        """The fluid followed by any plugin source particles (ghosts), with the pressure the
        momentum equation uses; with sources, views of arrays reused between evaluations
        (valid until the next call)."""
        ctx = self.ctx
        st = ctx.state
        extra = [s for s in self.hook.sph_extra_sources(ctx=ctx) if s is not None and s.n]
        self.n_sources = sum(s.n for s in extra)
        fluid = Fields(st.pos, st.vel, st.rho, self.pressure.force_pressure(st), st.m)
        if not extra:
            return fluid
        ctx.counters["extra_sources"] += 1
        n = st.n + self.n_sources
        if self._src_buf is None or self._src_buf.pos.shape[0] < n or self._src_buf.pos.shape[1] != st.dim:
            size = n + n // 4  # grows by a quarter: the ghost count changes from step to step
            self._src_buf = Fields(*(np.empty((size,) + a.shape[1:], a.dtype) for a in fluid))
        out = Fields(*(b[:n] for b in self._src_buf))
        for a, b, name in zip(fluid, out, Fields._fields):
            b[:st.n] = a
            k = st.n
            for s in extra:
                part = getattr(s, name)
                b[k:k + s.n] = part
                k += s.n
        return out

    def grid(self, pos, count=True) -> CellGrid:
        """The cell grid of ``pos``, rebuilt in the arrays of the last one (no allocation)."""
        try:
            if self._grid is None:
                self._grid = CellGrid(pos, self.ctx.params.support)
            else:
                self._grid.rebuild(pos)
        except OverflowError as e:
            self._search_failed(pos, e)
        if count:
            self.ctx.counters["neighbour_search"] += 1
        return self._grid

    def pair_view(self, src: Fields):
        """The grid view the pair loop walks: with a kept pair list (:mod:`sphcore.neighbours.pairlist`,
        ``neighbours.skin`` > 0) when the run has no plugin sources, else a fresh cell grid."""
        if self.pairs is None or self.n_sources:
            return self.grid(src.pos).view
        self.ctx.counters["neighbour_search"] += 1
        return self._kept_view(src.pos)

    def reorder_plan(self, pos):
        """The permutation that puts the particles in cell order (new index k = old index
        ``order[k]``), or None when they are in it already: the kept pair list's order (the
        list stays valid, see :meth:`sphcore.neighbours.pairlist.PairList.follow`), else a fresh grid's."""
        if self.pairs is None:
            return self.grid(pos, count=False).order
        view = self._kept_view(pos)
        return None if self.pairs.sorted else view.order

    def _kept_view(self, pos):
        """The kept pair list's view of ``pos`` (rebuilt when due, counted)."""
        try:
            view, rebuilt = self.pairs.view_of(pos)
        except OverflowError as e:
            self._search_failed(pos, e)
        if rebuilt:
            self.ctx.counters["pair_list_builds"] += 1
        return view

    def reordered(self, order):
        """The particles were permuted by ``order`` (from :meth:`reorder_plan`)."""
        if self.pairs is not None:
            self.pairs.follow(order)

    def _search_failed(self, pos, e):
        ctx = self.ctx
        far = int(np.argmax(np.abs(pos - np.median(pos, axis=0)).sum(axis=1)))
        pid = int(ctx.state.id[far]) if far < ctx.state.n else -1
        raise Instability(ctx.step, ctx.t, pid, f"neighbour search failed: {e}") from None

    def wall_terms_last(self) -> WallTerms:
        """The wall terms of the last evaluation (for studies of the wall model; read only)."""
        return self._wall

    def work_last(self) -> np.ndarray:
        """The per-particle scratch of the last evaluation's pair loop, in particle order
        (columns: sphcore.physics.pairterms.W_*; the wall completion's near-wall sums among
        them); read only."""
        return self._work

    def wall_react(self):
        """The acceleration the wall completion gave each particle at the last evaluation
        (``WallTerms.react``: runs with moving walls, or where a scheme asks for it), or None."""
        react = self._wall.react
        return react if self._wall.active and react.shape[0] == self.ctx.state.n else None

    def forget_wall_terms(self):
        """Compute the wall terms at the next call even at the same state (a restored
        snapshot: the plugins' side effects, such as a moving wall's load, were undone)."""
        self._wall_at.clear()

    def wall_terms(self) -> WallTerms:
        """Per-particle wall terms from the plugins that supply them (``sph_wall_terms``);
        with ``reuse_wall_terms``, the last ones while the state is the one they were
        computed at."""
        if not self.wants_walls:
            return self._wall
        st = self.ctx.state
        n, dim = st.n, self.ctx.params.dim
        if self._wall.share.shape[0] == n and self._wall_at.holds(st, self.ctx.t):
            return self._wall
        if self._wall.share.shape[0] != n:
            moving = n if getattr(self.ctx.case, "moving", ()) else 0  # moving walls' terms, else empty
            # the completion's own acceleration: the loads of moving walls, and the incompressible
            # scheme's scaling of the walls' hydrostatic push (sphcore.physics.incompressible)
            react = n if moving or self.records_reaction else 0
            self._wall = WallTerms(np.zeros(n), np.zeros((n, dim)), np.zeros((n, dim)), np.zeros((n, dim, dim)),
                                   np.zeros(n), True, np.zeros(moving), np.zeros((moving, dim)),
                                   np.zeros((react, dim)))
        w = self._wall
        w.share[:] = 0.0
        w.grad[:] = 0.0
        w.hydro[:] = 0.0
        w.normals[:] = 0.0
        w.fill[:] = 0.0
        w.flux[:] = 0.0
        w.accel[:] = 0.0
        w.react[:] = 0.0
        self.hook.sph_wall_terms(ctx=self.ctx, terms=w)
        self.ctx.counters["wall_terms"] += 1
        if self.reuse_wall_terms:
            self._wall_at.mark(st, self.ctx.t)
        return w

    def _buffers(self, n, n_src):
        prm = self.ctx.params
        if prm.kernel_gradient and self._L.shape[0] != n:
            self._L = np.zeros((n, 3, 3))
        if self._work.shape[0] < n_src:
            self._work = np.zeros((n_src + n_src // 4, WORK_COLUMNS))
            self._spos = np.zeros((self._work.shape[0], self.ctx.params.dim))

    # -- the evaluation ---------------------------------------------------------------

    def evaluate(self, acc, drho):
        """Fill ``acc`` (n, dim) and ``drho`` (n,) with the rates of the current state."""
        ctx = self.ctx
        st, prm, counters = ctx.state, ctx.params, ctx.counters
        if not self.density_rates and prm.delta > 0.0:
            prm = prm._replace(delta=0.0)  # the diffusion changes drho only
        counters["rates"] += 1
        if not prm.sph:
            uniform_acceleration(prm.gravity, acc)
        else:
            self.hook.sph_before_forces(ctx=ctx)
            src = self.sources()
            listed = self._listed_pairs(prm)
            if listed is not None:
                wall = self.wall_terms()
                self._buffers(st.n, st.n)
                listed_rates(st.n, src, prm, wall, *listed, acc, drho, self._work[:st.n], self.completion)
                counters["rates_from_pair_list"] += 1
            else:
                self._walk_cells(src, prm, acc, drho)
            self._count_terms(prm)
        self.hook.sph_accelerations(ctx=ctx, acc=acc)

    def _walk_cells(self, src, prm, acc, drho):
        """The pair sums over the cells (or the kept Verlet list) of the sources."""
        st, counters = self.ctx.state, self.ctx.counters
        view = self.pair_view(src)
        wall = self.wall_terms()
        self._buffers(st.n, src.pos.shape[0])
        if prm.kernel_gradient:
            neighbour_sums(st.n, src, view, prm, True, self._L, False, self._shepard)
            counters["kernel_gradient_correction"] += 1
        n_src = src.pos.shape[0]
        sph_rates(st.n, src, view, prm, self._L, wall, acc, drho, self._work[:n_src], self._spos[:n_src],
                  numba.get_num_threads(), self.completion)

    def _listed_pairs(self, prm):
        """The scheme's pair list of the current state, when the rates can be summed over it
        (:mod:`sphcore.physics.listedrates`: no plugin sources, kernel gradient correction or
        density diffusion), else None."""
        if self.listed is None or self.n_sources or prm.kernel_gradient or prm.delta > 0.0:
            return None
        return self.listed()

    def _count_terms(self, prm):
        counters = self.ctx.counters
        counters["continuity"] += 1
        counters["momentum"] += 1
        if prm.alpha > 0 or prm.beta > 0:
            counters["artificial_viscosity"] += 1
        if prm.nu > 0:
            counters["laminar_viscosity"] += 1
        if prm.delta > 0:
            counters["density_diffusion"] += 1

    def shepard_density(self, out):
        """out <- Shepard-filtered density (Chen et al. 1999, CSPH zeroth order) over the
        fluid and any plugin sources (ghosts complete the sums at walls)."""
        ctx = self.ctx
        if self._shepard.shape[0] != ctx.state.n:
            self._shepard = np.zeros(ctx.state.n)
        src = self.sources()
        grid = self.grid(src.pos)
        neighbour_sums(ctx.state.n, src, grid.view, ctx.params, False, self._L, True, self._shepard)
        out[:] = self._shepard
