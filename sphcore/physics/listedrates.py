"""The rates of the current state from a full pair list that a scheme keeps (the
incompressible scheme's, :mod:`sphcore.physics.solvepairs`), instead of a neighbour search.

The divergence-free scheme lists every particle's partners, with W_ij and grad_i W_ij, at
the positions a step starts from, for its solves; its non-pressure accelerations (viscosity,
the walls' completion, gravity) are wanted at the same positions. Walking the cells again
for them cost as much as the list itself (the 3D dam break at h = dx: the weakly
compressible pair loop and its neighbour search, 14 ms a step against 15 ms for the list).
Here particle i sums its own row instead, in the row's order, and writes only its own
entries: no races, the same bits for any thread count, each pair evaluated from both ends
(equal and opposite to round-off, where the cell walk evaluates it once).

The terms are those of the pair loop (:func:`sphcore.physics.pairterms.pair_terms`: the
force pressure's p / rho^2, artificial and laminar viscosity), the near-wall sums and the
completion of :func:`sphcore.physics.equations.sph_rates` (its finish, compiled in),
so that the two paths differ only in the order of the additions. What this path does not
compute, the caller sends to the cell walk (:meth:`sphcore.physics.forces.Forces.evaluate`):
density diffusion (its drho only; a scheme that sums its density does not read it), the
kernel gradient correction, and plugin source particles (ghosts), which are in no list.
"""

from __future__ import annotations

from numba import njit, prange

from sphcore.jit.parallel import twin
from sphcore.physics import equations
from sphcore.physics.pairterms import W_B, W_GAMMA, W_INV_RHO, W_PR, constants, pair_terms

# constants of each compiled twin (see the end): the dimension, whether wall terms are
# supplied, and the rates' finish with the wall model's completion (equations.finish_twin)
DIM = None
WALLS = None
FINISH = None


def _listed_rates(n, src, prm, wall, start, end, nb, w, g, acc, drho, work):
    """acc (n, dim) and drho (n,) of the fluid ``src`` (:class:`sphcore.physics.particles.Fields`,
    with the pressure the momentum equation uses) from particle i's partners
    ``nb[start[i]:end[i]]``, their W_ij (``w``) and grad_i W_ij (``g``); ``work`` (n,
    WORK_COLUMNS) scratch, as the pair loop's."""
    dim = DIM
    walls = WALLS
    pos, vel, rho, p, m = src
    react = wall.react
    share = wall.share
    k = constants(prm, dim)
    gv0, gv1, gv2 = prm.gravity[0], prm.gravity[1], prm.gravity[2]
    for i in prange(n):
        inv = 1.0 / rho[i]
        work[i, W_PR] = p[i] * inv * inv
        work[i, W_INV_RHO] = inv
    for i in prange(n):
        near = walls and share[i] > 0.0
        rho_i, m_i, pr_i = rho[i], m[i], work[i, W_PR]
        px0, px1 = pos[i, 0], pos[i, 1]
        px2 = pos[i, 2] if dim == 3 else 0.0
        vi0, vi1 = vel[i, 0], vel[i, 1]
        vi2 = vel[i, 2] if dim == 3 else 0.0
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        dr = 0.0
        gam = 0.0
        b0 = 0.0
        b1 = 0.0
        b2 = 0.0
        for q in range(start[i], end[i]):
            j = nb[q]
            x0 = px0 - pos[j, 0]
            x1 = px1 - pos[j, 1]
            x2 = px2 - pos[j, 2] if dim == 3 else 0.0
            g0 = g[q, 0]
            g1 = g[q, 1]
            g2 = g[q, 2] if dim == 3 else 0.0
            v0 = vi0 - vel[j, 0]
            v1 = vi1 - vel[j, 1]
            v2 = vi2 - vel[j, 2] if dim == 3 else 0.0
            m_j = m[j]
            e0, e1, e2, dr_i, _ = pair_terms(k, x0, x1, x2, x0 * x0 + x1 * x1 + x2 * x2, g0, g1, g2, v0, v1, v2, m_i,
                                             m_j, rho_i, rho[j], pr_i, work[j, W_PR], 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
            a0 -= m_j * e0
            a1 -= m_j * e1
            a2 -= m_j * e2
            dr += dr_i
            if near:  # the completion's sums: sum_j V_j W_ij and sum_j V_j grad_i W_ij (x_j - x_i) . g
                vj = m_j * work[j, W_INV_RHO]
                gx = -(x0 * gv0 + x1 * gv1 + x2 * gv2)
                gam += vj * w[q]
                b0 += vj * gx * g0
                b1 += vj * gx * g1
                b2 += vj * gx * g2
        acc[i, 0] = a0
        acc[i, 1] = a1
        if dim == 3:
            acc[i, 2] = a2
        drho[i] = dr
        work[i, W_GAMMA] = gam
        work[i, W_B] = b0
        work[i, W_B + 1] = b1
        work[i, W_B + 2] = b2
        FINISH(i, dim, walls, src, prm, wall, react, acc, drho, work)


def _build(dim: int, completion=None):
    """The twin of ``_listed_rates`` for ``dim``, with the wall ``completion`` (None: without
    wall terms), named as :func:`sphcore.physics.equations.sph_rates`' twins so that numba's
    disk cache keeps one per completion."""
    walls = completion is not None
    name = f"_{dim}d" + (f"_walls_{equations.completion_tag(completion)}" if walls else "")
    finish = equations.finish_twin(name, completion)
    return njit(cache=True, parallel=True, error_model="numpy")(
        twin(_listed_rates, name, DIM=dim, WALLS=walls, FINISH=finish))


_BUILT = {}


def listed_rates(n, src, prm, wall, start, end, nb, w, g, acc, drho, work, completion=None):
    """Fill ``acc`` and ``drho`` of the n fluid particles from the kept pair list (module
    docstring); ``wall``: the wall terms (:class:`sphcore.physics.equations.WallTerms`), with
    ``completion`` the wall model's compiled completion when they are active."""
    dim = src.pos.shape[1]
    key = (dim, completion if wall.active else None)
    if wall.active and completion is None:
        raise ValueError("wall terms are active but no wall completion was given")
    fn = _BUILT.get(key)
    if fn is None:
        fn = _BUILT[key] = _build(dim, key[1])
    fn(n, src, prm, wall, start, end, nb, w, g, acc, drho, work)


def compiled_on_disk(dim: int) -> bool:
    """Whether numba's on-disk cache holds the rates over the pair list of a
    ``dim``-dimensional run and the pair list's fill (else a divergence-free run's first
    step compiles them)."""
    from sphcore.jit.cache import on_disk
    from sphcore.physics import pairfill

    return (on_disk(__file__, f"listedrates._listed_rates_{dim}d*.nbi")
            and on_disk(pairfill.__file__, "pairfill.fill_pairs-*.nbi"))
