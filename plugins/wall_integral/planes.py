"""The wall terms of the case's planes, for the particles near them only.

Each force evaluation first lists the particles within the kernel support 2h of some plane
(:func:`near_planes`: one pass over the positions, k dot products per particle), then
computes for those alone, in one pass (:func:`add_plane_terms`), the exact share, gradient
and hydrostatic moment (``share.py``), the lattice-error correction and the fill reference
(``lattice.py``) and the near-wall projector (``normals.py``), adding them into the core's
:class:`sphcore.physics.equations.WallTerms` arrays. In a tank only a few per cent of the particles
are that close to a wall: the three full passes this replaces took 2.3 ms of a 45 ms step
at 10^5 particles (one thread), each computing every particle's plane distances again, and
the plugin's own arrays were added into the core's by three more full passes.

The results are the bits of the full passes: each term is computed as before and added to
the core's zeroed arrays in the same order.
"""

from __future__ import annotations

from numba import njit, prange

from sphcore.api import particle_distance

from .lattice import subtract_one
from .normals import project_one
from .share import add_terms_to, wall_point

PARALLEL_NEAR = 4096  # listed particles: below this a parallel launch costs more than the work


@njit(cache=True)
def near_planes(pos, normals, offsets, reach, idx):
    """Write into ``idx`` the indices (ascending) of the particles closer than ``reach`` (m)
    to some plane (normals (k, dim) into the fluid, offsets (k,)); returns their count.
    ``idx`` must hold pos.shape[0] entries."""
    count = 0
    nk = normals.shape[0]
    for i in range(pos.shape[0]):
        near = False
        for k in range(nk):
            near = near or particle_distance(normals, offsets, k, pos, i) < reach
        if near:
            idx[count] = i
            count += 1
    return count


@njit(cache=True, parallel=True)
def add_plane_terms(idx, count, pos, normals, offsets, kernel_id, h, gravity, nodes, tab1, tab2, tab3, support,
                    lam, share, grad, hydro, fill, q):
    """For the particles idx[:count]: share += s, grad += G - E, hydro += T g - (F / lam) g_t,
    fill += Gamma, q <- projector onto span(q, near normals) (the module docstring).

    One loop, called through :func:`sphcore.api.on_threads_by_size` (one thread below
    PARALLEL_NEAR particles): a serial copy of the loop beside the parallel one doubled the
    inlined per-particle code, and the kernel took 107 s to compile."""
    for t in prange(count):
        _one(idx[t], pos, normals, offsets, kernel_id, h, gravity, nodes, tab1, tab2, tab3, support, lam,
             share, grad, hydro, fill, q)


@njit(cache=True, inline="always")
def _one(i, pos, normals, offsets, kernel_id, h, gravity, nodes, tab1, tab2, tab3, support, lam, share, grad,
         hydro, fill, q):
    dim = pos.shape[1]
    x2 = pos[i, 2] if dim == 3 else 0.0
    g2 = gravity[2] if dim == 3 else 0.0
    s, a0, a1, a2, t0, t1, t2 = wall_point(pos[i, 0], pos[i, 1], x2, normals, offsets, kernel_id, h,
                                           gravity[0], gravity[1], g2)
    add_terms_to(i, dim, s, a0, a1, a2, t0, t1, t2, share, grad, hydro)
    subtract_one(i, pos, normals, offsets, nodes, tab1, tab2, tab3, support, lam, gravity, grad, hydro, fill)
    project_one(i, pos, normals, offsets, support, q)
