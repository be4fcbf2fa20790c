"""Wall terms of finite faces for every particle (``WallTerms`` of the core), beside the
planes' (``planes.py``); ``facetable.py`` tabulates the same terms once per run.

Per particle, the faces within the kernel support 2h (found through a face grid, each
face once) add their exact share s, gradient G and moment T g (:mod:`.meshfaces`); the
completion's reference neighbour sum (``fill``) loses s (the missing part of the kernel's
unit integral), and the projector onto the near walls' directions (``normals``) gains the
direction from each face's nearest point to the particle (the face's normal over its
interior, radial at an edge or vertex).

What the planes have and faces do not (yet): the lattice-error tables. For planes, G is
corrected by the error of the truncated sum on the initial lattice, so that a uniform
pressure exerts no force on that lattice; next to a face the exact G is used as it is, and
a particle of the initial lattice there feels the (small) lattice error of its own sum.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from sphcore.api import box_cells, nearest_point

from .meshfaces import face_part
from .normals import add_direction, set_projector
from .share import add_face, add_terms_to


@njit(cache=True, parallel=True)
def face_wall_terms(pos, verts, glo, ginv, gshape, gstart, gitems, stamps, epoch, kernel_id, h, gravity,
                    full, share, grad, hydro, fill, q):
    """Add the faces' terms to share (n,), grad (n, dim), hydro (n, dim), fill (n,) and the
    projector q (n, dim, dim) of every particle within 2h (m) of a face. ``stamps``
    (blocks, nf) int64: scratch marking the faces already taken for a particle (each block
    of particles runs on one thread), with the marks epoch * (n + 1) + i: ``epoch`` must
    differ between calls (a mark left by the same particle index in an earlier call would
    hide the face). ``full``: the interior's lattice neighbour sum."""
    n, dim = pos.shape
    rows = stamps.shape[0]
    first_mark = epoch * (n + 1)
    for b in prange(rows):
        for i in range(b * n // rows, (b + 1) * n // rows):
            x0, x1 = pos[i, 0], pos[i, 1]
            x2 = pos[i, 2] if dim == 3 else 0.0
            near, s, gr0, gr1, gr2, t0, t1, t2, basis, count = point_terms(
                x0, x1, x2, dim, verts, glo, ginv, gshape, gstart, gitems, stamps, np.int64(b), first_mark + i,
                kernel_id, h, gravity, q[i])
            if near == 0:
                continue
            add_terms(i, dim, s, gr0, gr1, gr2, t0, t1, t2, full, share, grad, hydro, fill)
            set_projector(q[i], dim, basis, count)


@njit(cache=True, inline="always")
def add_terms(i, dim, s, gr0, gr1, gr2, t0, t1, t2, full, share, grad, hydro, fill):
    """share, grad, hydro of particle i += the faces' s, G, T g; its fill reference loses s."""
    add_terms_to(i, dim, s, gr0, gr1, gr2, t0, t1, t2, share, grad, hydro)
    ref = fill[i] if fill[i] > 0.0 else full
    fill[i] = max(ref - s, 1e-3 * full)


@njit(cache=True)
def point_terms(x0, x1, x2, dim, verts, glo, ginv, gshape, gstart, gitems, stamps, b, mark, kernel_id, h, gravity,
                q0):
    """The faces' terms at the point x: (number of faces within 2h, s, G (3), T g (3), the
    orthonormal basis (a 9-tuple of rows) of span(q0, directions from the faces' nearest
    points to x), its size). ``stamps[b]`` with ``mark`` takes each face once (see
    :func:`face_wall_terms`); q0 (dim, dim): the projector already there (its columns are
    added first)."""
    g0, g1 = gravity[0], gravity[1]
    g2 = gravity[2] if dim == 3 else 0.0
    support = 2.0 * h
    cx0, cx1, cy0, cy1, cz0, cz1 = box_cells(glo, ginv, gshape, dim, x0, x1, x2, x0, x1, x2, support)
    s = 0.0
    gr0 = 0.0
    gr1 = 0.0
    gr2 = 0.0
    t0 = 0.0
    t1 = 0.0
    t2 = 0.0
    near = 0
    basis = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
    count = 0
    for cx in range(cx0, cx1 + 1):
        for cy in range(cy0, cy1 + 1):
            for cz in range(cz0, cz1 + 1):
                c = (cx * gshape[1] + cy) * gshape[2] + cz
                for e in range(gstart[c], gstart[c + 1]):
                    f = gitems[e]
                    if stamps[b, f] == mark:
                        continue
                    stamps[b, f] = mark
                    qx, qy, qz = nearest_point(verts, f, x0, x1, x2)
                    dist = math.sqrt((x0 - qx) ** 2 + (x1 - qy) ** 2 + (x2 - qz) ** 2)
                    if dist >= support:
                        continue
                    if near == 0:  # what the planes (or another plugin) put in q
                        for a in range(dim):
                            basis, count = add_direction(basis, count, dim, q0[0, a], q0[1, a],
                                                          q0[2, a] if dim == 3 else 0.0)
                    near += 1
                    fs, fw, m0, m1, m2, n0, n1, n2, d = face_part(kernel_id, x0, x1, x2, verts, f, h)
                    s, gr0, gr1, gr2, t0, t1, t2 = add_face(s, gr0, gr1, gr2, t0, t1, t2, fs, fw, m0,
                                                            m1, m2, n0, n1, n2, d, h, g0, g1, g2)
                    if dist > 0.0:
                        basis, count = add_direction(basis, count, dim, (x0 - qx) / dist,
                                                      (x1 - qy) / dist, (x2 - qz) / dist)
    return near, s, gr0, gr1, gr2, t0, t1, t2, basis, count


def stamps_for(nf: int) -> np.ndarray:
    """The scratch of :func:`face_wall_terms` for ``nf`` faces: 64 blocks."""
    return np.full((64, nf), -1, np.int64)
