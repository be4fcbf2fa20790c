"""Weakly compressible SPH equations, as numba kernels over struct-of-arrays.

Destination particles are the first ``n_dest`` entries of the source arrays (the fluid);
further source entries (ghosts) act only as neighbours. With x_ij = x_i - x_j,
v_ij = v_i - v_j, grad_i W_ij = F_ij x_ij (see :mod:`sphcore.physics.kernels`):

- continuity (Monaghan 1992, Eq. 2.9 form): drho_i/dt = sum_j m_j v_ij . grad_i W_ij
- density diffusion (Molteni & Colagrossi 2009):
  + delta h c0 sum_j 2 psi_ij (m_j / rho_j) (x_ij . grad_i W_ij) / (|x_ij|^2 + eta^2),
  psi_ij = rho_i - rho_j, or with ``diffusion_hydrostatic`` its departure from the
  hydrostatic stratification (Fourtakas et al. 2019): psi_ij = rho_i - rho_j - k_ij g . x_ij,
  k_ij g . x_ij the hydrostatic density difference rho^H_i - rho^H_j across the pair, so water at
  rest is not diffused. Hydrostatics with the Tait equation gives d rho^H / dz = -g rho / c^2(rho),
  c^2 = dp/drho = c0^2 (rho/rho0)^(gamma - 1), so k = rho / c^2 = (rho0/c0^2) (rho/rho0)^(2 - gamma);
  k_ij = (k_i + k_j)/2 is the trapezoidal rule of that integral (error O(|x_ij|^3)), where
  k = rho0/c0^2 (Fourtakas et al.'s linearisation about rho0) leaves the curvature of the
  stratification, O(|x_ij|^2), to be diffused: 2.4% of the gradient at the floor of a 1 m tank
- momentum (Monaghan 1994): dv_i/dt = g - sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) grad_i W_ij
- artificial viscosity (Monaghan 1992): for v_ij . x_ij < 0,
  mu_ij = h v_ij . x_ij / (|x_ij|^2 + eta^2), Pi_ij = (-alpha c0 mu_ij + beta mu_ij^2) / rho_bar
- laminar viscosity (Morris et al. 1997, Lo & Shao 2002 form):
  + sum_j m_j 4 nu / (rho_i + rho_j) (x_ij . grad_i W_ij) / (|x_ij|^2 + eta^2) v_ij
- boundary-integral walls (:class:`WallTerms`; Kulasegaram et al. 2004, Ferrand et al. 2013):
  where a plugin supplies the wall share s_i of the kernel support, its gradient G_i, the
  hydrostatic moment H_i = T_i g and the near walls' normals, the missing support is filled
  with the mirror image of the fluid, its pressure extrapolated hydrostatically:
      drho_i/dt = sum_j ... + 2 rho_i v_i . G_w
      dv_i/dt   = g - sum_j ... - 2 (p_i/rho_i) G_w - ((rho_i - rho_ref)/rho_i) A_w g
  with G_w the wall gradient the plugin supplies (the exact G corrected for the lattice
  error of the truncated sum) and A_w g the discrete complement of the particle's own first
  moment along the walls' normals, lambda (T g + s g) along them; see
  the function of the ``sph_wall_completion`` hook, compiled into the pair loop.
- Tait equation of state: :mod:`sphcore.physics.eos`.

eta^2 = 0.01 h^2 keeps the denominators finite. Arguments are structured: ``src``
(:class:`Fields`), ``grid`` (:class:`sphcore.neighbours.cellgrid.Grid`), ``prm``
(:class:`sphcore.physics.params.Params`), ``wall`` (:class:`WallTerms`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from sphcore.jit.parallel import PARALLEL_MIN, twin
from sphcore.neighbours.cellgrid import candidates_bound, forward_pairs, forward_rows, listed_pairs
from sphcore.physics.eos import tait_power
from sphcore.physics.pairterms import (
    GATHER_ROWS,
    OUT_ROWS,
    W_B,
    W_GAMMA,
    W_GP,
    W_INV_RHO,
    W_KH,
    W_PR,
    W_VOL,
    constants,
    fused_partners,
    gather,
    scatter,
    terms,
)

PAIRS_PARALLEL_MIN = 1000  # particles: the pair loop runs serial below (one thread is faster)


class WallTerms(NamedTuple):
    """Per-particle boundary-integral terms of the walls (zero far from walls).

    ``share`` (n,): the wall's share s of the particle's kernel support, int_outside W;
    ``grad`` (n, dim): G = grad s (1/m), pointing towards the wall;
    ``hydro`` (n, dim): H = oint_wall W n_out g . (x_s - x) dS (m/s^2), the hydrostatic
    moment of the wall pressure; ``normals`` (n, dim, dim): the orthogonal projector onto
    the normals of the walls within the particle's support (n n^T near one plane, the
    identity in a corner), the directions in which its missing support is wall rather than
    free surface; ``fill`` (n,): the neighbour sum sum_j V_j W_ij (self excluded) that a
    particle of the initial lattice has at that place, against which the core measures how
    full the particle's own neighbourhood is (0: not supplied, no scaling); ``active``:
    false when no plugin supplies them (skipped). Plugins fill them in the
    ``sph_wall_terms`` hook; share, grad, hydro and fill of several plugins add up,
    ``normals`` is replaced by the projector onto the span of both.

    Walls that move (a run with ``case.moving``) add two terms, empty arrays otherwise:
    ``flux`` (n,): sum over the wall groups of v_w . G_w (m/s / m), each group's wall
    velocity at the particle against its part of G, which the continuity completion takes
    from v_i . G_w (the fluid's velocity relative to the wall); ``accel`` (n, dim): the
    outside first moment of minus the walls' acceleration, sum over the groups of
    T (-a_w) + s (-a_w) (m/s^2), which joins the hydrostatic extrapolation of the wall
    pressure (in the wall's frame the fluid feels g - a_w).
    """

    share: np.ndarray
    grad: np.ndarray
    hydro: np.ndarray
    normals: np.ndarray
    fill: np.ndarray
    active: bool
    flux: np.ndarray = np.zeros(0)
    accel: np.ndarray = np.zeros((0, 3))
    #: (n, dim), moving walls only: the acceleration the completion gave each particle (m/s^2),
    #: whose reaction, summed over a group's particles, is the fluid's load on that group
    react: np.ndarray = np.zeros((0, 3))


# constants of each compiled twin of the pair loop (see the end): the spatial dimension,
# whether wall terms are supplied (WallTerms.active), and how the partners are walked
DIM = None
WALLS = None
THREE_PASS = None  # walk a particle's partners in three passes (sphcore.physics.pairterms): in 3D
COMPLETE = None  # the wall model's completion of a particle's sums (sph_wall_completion), inlined


def sph_rates(n_dest, src, grid, prm, L, wall, acc, drho, work, spos, nth, completion=None):
    """Accelerations acc (n_dest, dim) in m/s^2 and density rates drho (n_dest,) in kg/m^3/s.

    Every interacting pair is evaluated once and applied to both particles (Newton's third
    law: the pair forces are equal and opposite to round-off), walking each occupied cell
    and its forward neighbours (:mod:`sphcore.neighbours.cellgrid`); slabs of the same parity run in
    parallel without touching the same particle, so the result does not depend on the
    number of threads. A pair of two plugin sources (ghosts) is skipped, a pair of a fluid
    particle and a source acts on the fluid particle only. ``work`` (n_sources,
    WORK_COLUMNS) is scratch (the near-wall sums of the wall completion, p/rho^2, 1/rho, and
    for the density diffusion k/2, the volume m/rho and g . x), ``spos``
    (n_sources, dim) scratch for the positions in cell order; ``nth``:
    numba's thread count (only the balance between threads depends on it).

    Terms whose coefficient is zero are skipped, so a case without viscosity or density
    diffusion computes none. ``prm.modified_pressure``: gravity acts as g (1 - rho0/rho_i)
    (Batchelor 1967). ``prm.kernel_gradient``: the kernel gradient is corrected with the
    symmetrised Bonet & Lok matrix (L_i + L_j)/2 (antisymmetric in i, j, so momentum is
    still conserved); sources beyond ``L.shape[0]`` use the identity. ``wall``: see the
    module docstring; with ``wall.active``, ``completion`` is the wall model's compiled
    completion of a particle's sums (the ``sph_wall_completion`` hook), inlined into the
    loop.

    The pair loop is compiled once per dimension and for runs with and without wall terms
    (``_RATES``), each a constant of its build: 0.44 -> 0.35-0.36 ms per call of the seed's
    dam break on one thread (dimension), -> 0.351-0.357 (wall terms), the same bits. The
    terms of a pair are :func:`sphcore.physics.pairterms.pair_terms`; 2D walks a particle's partners
    in one fused loop, 3D in three passes whose middle one is vectorised (the measurements
    are in :mod:`sphcore.physics.pairterms`), the same bits either way.
    """
    dim = src.pos.shape[1]
    if wall.active:
        if completion is None:
            raise ValueError("wall terms are active but no wall completion was given")
        rates = _RATES.get((dim, completion))
        if rates is None:
            rates = _RATES[dim, completion] = _build(dim, completion)
    else:
        rates = _RATES[dim, None]
    rates(n_dest, src, grid, prm, L, wall, acc, drho, work, spos, nth)


def _sph_rates(n_dest, src, grid, prm, L, wall, acc, drho, work, spos, nth):
    """:func:`sph_rates` for one dimension DIM, with or without wall terms (WALLS); compiled
    as twins (see the end)."""
    dim = DIM
    n_src = src.rho.shape[0]
    # element-wise passes: a parallel launch costs more than the work below PARALLEL_MIN
    if n_src >= PARALLEL_MIN:
        for i in prange(n_src):
            _prepare(i, n_dest, dim, src, grid.order, prm, acc, drho, work, spos)
    else:
        for i in range(n_src):
            _prepare(i, n_dest, dim, src, grid.order, prm, acc, drho, work, spos)
    nth = max(nth, 1)
    slab_start = grid.slab_start
    nslab = slab_start.shape[0] - 1
    nbuf = candidates_bound(grid)
    nrow = grid.nbr.shape[1] // 2 + 1  # forward stencil rows, at most
    # scratch per thread, allocated once per call: one particle's partners, the rows of a cell
    nt = nth if n_src >= PAIRS_PARALLEL_MIN else 1
    buf = np.empty((nt, nbuf), np.int64)
    rows = np.empty((nt, nrow, 2), np.int64)
    nrow3 = nbuf if THREE_PASS else 0  # the three-pass walk's rows (sphcore.physics.pairterms)
    gat = np.empty((nt, GATHER_ROWS, nrow3))
    out = np.empty((nt, OUT_ROWS, nrow3))
    # The slabs differ in size (water on a floor: the bottom layers hold most particles),
    # so thread k takes every nth slab of a phase, k, k + nth, ..., rather than a contiguous
    # block; one task per thread, so its scratch is allocated once per call, not per slab
    # (which cost no measurable time: 0.31 ms a call of the seed's dam break on two threads
    # either way). Which thread runs a slab does not change the result. Below
    # PAIRS_PARALLEL_MIN particles the two launches per call cost more than the
    # second thread saves (2D still water, two threads, with the spin of
    # sphcore/__init__.py: 1,024 particles 0.185-0.191 us per particle-step with this loop
    # serial, 0.155-0.208, median 0.165, parallel; 529 particles 0.211 serial and
    # 0.212-0.220 parallel with a longer spin); the serial loop visits the slabs in the
    # same phases, so the additions to each particle come in the same order: the same bits.
    for phase in range(2):
        ntask = (nslab - phase + 1) // 2
        if n_src < PAIRS_PARALLEL_MIN:
            for u in range(ntask):
                s = 2 * u + phase
                _slab_pairs(slab_start[s], slab_start[s + 1], n_dest, src, grid, prm, L, wall, acc, drho, work, spos,
                            buf[0], rows[0], gat[0], out[0])
            continue
        # one task per thread: thread k takes the slabs u = k, k + nth, k + 2 nth, ...
        for k in prange(nth):
            for u in range(k, ntask, nth):
                s = 2 * u + phase
                _slab_pairs(slab_start[s], slab_start[s + 1], n_dest, src, grid, prm, L, wall, acc, drho, work,
                            spos, buf[k], rows[k], gat[k], out[k])
    # the reaction array is taken out of the tuple here, outside the loop: numba 0.68 drops
    # the writes a prange body makes through a tuple's field when the writing function is
    # inlined (measured: a 3D run of 54,528 particles left it all zero)
    react = wall.react
    if n_dest >= PARALLEL_MIN:
        for i in prange(n_dest):
            _finish(i, dim, WALLS, src, prm, wall, react, acc, drho, work)
    else:
        for i in range(n_dest):
            _finish(i, dim, WALLS, src, prm, wall, react, acc, drho, work)


@njit(cache=True, inline="always")
def _prepare(i, n_dest, dim, src, order, prm, acc, drho, work, spos):
    """Zero particle i's rates and sums; its p/rho^2, 1/rho and (with density diffusion) its
    volume m/rho, and (hydrostatic diffusion) k/2 = rho / (2 c^2(rho)) and g . x_i, per
    particle rather than per pair (divisions and powers are slow, and g . x_ij = g . x_i -
    g . x_j: pair separations are plain differences of positions, ghosts' included; a
    periodic domain's minimum-image separation would need g . x_ij per pair again); row i
    of the positions in cell order."""
    for d in range(dim):
        spos[i, d] = src.pos[order[i], d]
    rho_i = src.rho[i]
    if i < n_dest:
        for d in range(dim):
            acc[i, d] = 0.0
        drho[i] = 0.0
    for d in range(4):
        work[i, d] = 0.0
    work[i, W_PR] = src.p[i] / (rho_i * rho_i)
    work[i, W_INV_RHO] = 1.0 / rho_i
    if prm.delta > 0.0:
        work[i, W_VOL] = src.m[i] / rho_i
        if prm.diffusion_hydrostatic:  # k/2 and g . x_i: psi_ij's hydrostatic part (k_i + k_j)/2 g . x_ij
            x = rho_i / prm.rho0  # k = rho / c^2(rho) = (rho0 / c0^2) x^(2 - gamma), no pow for gamma = 7
            work[i, W_KH] = 0.5 * prm.rho0 / (prm.c0 * prm.c0) * (x * x / tait_power(x, prm.gamma))
            gp = 0.0
            for d in range(dim):
                gp += prm.gravity[d] * src.pos[i, d]
            work[i, W_GP] = gp


def _slab_pairs(c_first, c_end, n_dest, src, grid, prm, L, wall, acc, drho, work, spos, buf, rows, gat, out):
    """The pairs of the occupied cells c_first <= c < c_end with themselves and their
    forward neighbours, both ways; ``buf``: scratch for one particle's partners
    (:func:`sphcore.neighbours.cellgrid.forward_pairs`), ``rows`` for a cell's forward stencil rows
    (:func:`sphcore.neighbours.cellgrid.forward_rows`), ``gat`` and ``out`` for the three-pass walk
    of the partners (:mod:`sphcore.physics.pairterms`: in 3D; 2D walks them fused). One call per
    slab, not per cell: a call passes every field of src, grid, prm and wall (0.67 -> 0.63
    ms per evaluation of the seed's dam break, one thread)."""
    dim = DIM
    walls = WALLS
    pos, vel, rho, _, m = src
    kid, h = prm.kernel_id, prm.h
    # gravity in scalars: loads from an array inside the loop are repeated after every
    # store to acc/drho/work, which the compiler cannot prove do not alias it
    gv0, gv1, gv2 = prm.gravity[0], prm.gravity[1], prm.gravity[2]
    share = wall.share
    r2max = prm.support * prm.support
    n_L = L.shape[0] if prm.kernel_gradient else 0
    consts = constants(prm, dim)
    order, cell_start = grid.order, grid.cell_start
    pair_start, pair_cand = grid.pair_start, grid.pair_cand
    use_list = pair_start.shape[0] > 0  # partners from a kept pair list, else from the cells
    Li = np.empty(9)  # L_i row-major, or none (a source beyond L): kernel gradient correction
    no_L = np.empty(0)
    for c in range(c_first, c_end):
        nrows = 0 if use_list else forward_rows(c, grid, dim, rows)
        for k in range(cell_start[c], cell_start[c + 1]):
            i = order[k]
            if use_list:
                npart = listed_pairs(k, spos, order, pair_start, pair_cand, r2max, buf)
            else:
                npart = forward_pairs(k, n_dest, spos, order, rows, nrows, r2max, buf)
            if not THREE_PASS:
                fused_partners(i, npart, buf, n_dest, dim, walls, pos, vel, rho, m, kid, gv0, gv1, gv2, consts, L, n_L,
                               share, acc, drho, work)
                continue
            gather(i, npart, buf, dim, pos, vel, rho, m, work, consts, L, n_L, gat)
            pr_i, vol_i, kh_i, gp_i = work[i, W_PR], work[i, W_VOL], work[i, W_KH], work[i, W_GP]
            # with the correction and without: the compiler vectorises the second loop only
            # when the correction's loads are not in it
            if n_L > 0:
                if i < n_L:
                    for e in range(9):
                        Li[e] = L[i, e // 3, e % 3]
                terms(npart, dim, walls, kid, consts, rho[i], m[i], pr_i, vol_i, kh_i, gp_i, True,
                      Li if i < n_L else no_L, gat, out)
            else:
                terms(npart, dim, walls, kid, consts, rho[i], m[i], pr_i, vol_i, kh_i, gp_i, False, no_L, gat, out)
            scatter(i, npart, buf, n_dest, dim, walls, kid, h, gv0, gv1, gv2, share, m[i], acc, drho, work, gat, out)


@njit(cache=True, inline="always")
def _no_completion(wall, i, dim, vel, rho_i, p_i, rho_ref, lam, gravity, a0, a1, a2, dr, b0, b1, b2, gam):
    """The completion of a run without wall terms (never called: WALLS is false there)."""
    return a0, a1, a2, dr


def _finish(i, dim, walls, src, prm, wall, react, acc, drho, work):
    """Gravity and the wall completion (COMPLETE, a constant of each twin) of particle i,
    after all pairs. ``react`` (``wall.react``; empty unless walls move) receives the
    acceleration the completion gave the particle, whose reaction is the walls' load."""
    rho, gravity = src.rho, prm.gravity
    a0 = acc[i, 0]
    a1 = acc[i, 1]
    a2 = acc[i, 2] if dim == 3 else 0.0
    dr = drho[i]
    if walls and wall.share[i] > 0.0:
        b0, b1, b2 = a0, a1, a2
        a0, a1, a2, dr = COMPLETE(wall, i, dim, src.vel, rho[i], src.p[i], prm.rho_ref, prm.moment_norm,
                                  gravity, a0, a1, a2, dr, work[i, W_B], work[i, W_B + 1], work[i, W_B + 2], work[i, W_GAMMA])
        if react.shape[0] > 0:
            react[i, 0] = a0 - b0
            react[i, 1] = a1 - b1
            if dim == 3:
                react[i, 2] = a2 - b2
    gscale = 1.0 - prm.rho0 / rho[i] if prm.modified_pressure else 1.0
    acc[i, 0] = gscale * gravity[0] + a0
    acc[i, 1] = gscale * gravity[1] + a1
    if dim == 3:
        acc[i, 2] = gscale * gravity[2] + a2
    drho[i] = dr


@njit(cache=True)
def uniform_acceleration(gravity, acc):
    """acc[i] = gravity for every particle (the only force when SPH is off)."""
    dim = acc.shape[1]
    for i in range(acc.shape[0]):
        for d in range(dim):
            acc[i, d] = gravity[d]


# the pair loop compiled per dimension and with or without wall terms: DIM, WALLS,
# THREE_PASS and COMPLETE are constants in each twin (sphcore.jit.parallel.twin); numba
# compiles each on its first call. Runs without wall terms share one twin per dimension;
# a wall model's twin is built when its run first needs it


def completion_tag(completion) -> str:
    """The part of a twin's name that identifies a wall completion: its module and name
    and a digest of its bytecode and constants, so that numba's disk cache (indexed by the
    twin's name) never serves a pair loop compiled with another completion or an older
    version of this one."""
    import hashlib

    py = getattr(completion, "py_func", completion)
    code = py.__code__
    digest = hashlib.sha256(code.co_code + repr(code.co_consts).encode()).hexdigest()[:12]
    return f"{py.__module__}.{py.__qualname__}".replace(".", "_").replace("<", "_").replace(">", "_") + "_" + digest


def finish_twin(name: str, completion=None):
    """The per-particle finish of the rates (gravity and the wall ``completion``, None: no
    wall terms) compiled for inlining into a pair loop's twin named ``name``."""
    complete = _no_completion if completion is None else completion
    return njit(cache=True, inline="always")(twin(_finish, name, COMPLETE=complete))


def _build(dim: int, completion=None, three_pass: bool | None = None):
    """The pair loop's twin for ``dim``, with the wall ``completion`` compiled in (None:
    without wall terms); ``three_pass`` (default: in 3D) walks the partners in three passes,
    else fused (the other walk is built by the tests only, to check that both give the same
    bits)."""
    three = dim == 3 if three_pass is None else three_pass
    walls = completion is not None
    name = f"_{dim}d" + (f"_walls_{completion_tag(completion)}" if walls else "") + (
        "" if three == (dim == 3) else ("_three" if three else "_fused"))
    finish = finish_twin(name, completion)
    # error_model="numpy" in every twin, 2D and 3D, and in the passes before and after the
    # pairs (_prepare, _finish, inlined here): a float division by zero gives inf instead of
    # raising, so that the three-pass loop, which divides, can be vectorised (the checks
    # after the step catch what is not finite)
    pairs = njit(cache=True, error_model="numpy")(twin(_slab_pairs, name, DIM=dim, WALLS=walls, THREE_PASS=three))
    return njit(cache=True, parallel=True, error_model="numpy")(
        twin(_sph_rates, name, DIM=dim, WALLS=walls, THREE_PASS=three, _slab_pairs=pairs, _finish=finish))


_RATES = {(dim, None): _build(dim) for dim in (2, 3)}


def compiled_on_disk(dim: int) -> bool:
    """Whether numba's on-disk cache holds the pair loop of a ``dim``-dimensional run (else
    the first force evaluation compiles it), wherever numba may keep it
    (:func:`sphcore.jit.cache.on_disk`)."""
    from sphcore.jit.cache import on_disk

    return on_disk(__file__, f"equations._sph_rates_{dim}d*.nbi")
