"""Wall terms of finite faces for every particle (``WallTerms`` of the core), beside the
planes' (``planes.py``); ``facetable.py`` tabulates the same terms once per run.

Per particle, the faces within the kernel support 2h (found through a face grid, each
face once) add their exact share s, gradient G and moment T g (:mod:`.meshfaces`); the
completion's reference neighbour sum (``fill``) loses s (the missing part of the kernel's
unit integral), and the projector onto the near walls' directions (``normals``) gains the
direction from each face's nearest point to the particle: the face's normal over its
interior, radial at an edge or vertex where the wall turns. Where the nearest point is on an
edge or vertex that the face shares only with faces in its own plane (the diagonal of a
box's side split into two triangles), the wall does not turn there and the face adds its
normal instead (:func:`flat_parts`): a radial direction from such an edge lies partly
along the wall, and the completion would read the wall's tangent as wall, pressing on the
face along it; the terms of a flat face then do not depend on how it is triangulated.

What the planes have and faces do not (yet): the lattice-error tables. For planes, G is
corrected by the error of the truncated sum on the initial lattice, so that a uniform
pressure exerts no force on that lattice; next to a face the exact G is used as it is, and
a particle of the initial lattice there feels the (small) lattice error of its own sum.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from sphcore.api import box_cells, nearest_feature

from .meshfaces import face_part
from .normals import add_direction, set_projector
from .share import add_face, add_terms_to


@njit(cache=True, parallel=True)
def face_wall_terms(pos, verts, flat, glo, ginv, gshape, gstart, gitems, stamps, epoch, kernel_id, h, gravity,
                    full, share, grad, hydro, fill, q):
    """Add the faces' terms to share (n,), grad (n, dim), hydro (n, dim), fill (n,) and the
    projector q (n, dim, dim) of every particle within 2h (m) of a face. ``stamps``
    (blocks, nf) int64: scratch marking the faces already taken for a particle (each block
    of particles runs on one thread), with the marks epoch * (n + 1) + i: ``epoch`` must
    differ between calls (a mark left by the same particle index in an earlier call would
    hide the face). ``flat``: :func:`flat_parts` of verts. ``full``: the interior's lattice
    neighbour sum."""
    n, dim = pos.shape
    rows = stamps.shape[0]
    first_mark = epoch * (n + 1)
    for b in prange(rows):
        for i in range(b * n // rows, (b + 1) * n // rows):
            x0, x1 = pos[i, 0], pos[i, 1]
            x2 = pos[i, 2] if dim == 3 else 0.0
            near, s, gr0, gr1, gr2, t0, t1, t2, basis, count = point_terms(
                x0, x1, x2, dim, verts, flat, glo, ginv, gshape, gstart, gitems, stamps, np.int64(b),
                first_mark + i, kernel_id, h, gravity, q[i])
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
def point_terms(x0, x1, x2, dim, verts, flat, glo, ginv, gshape, gstart, gitems, stamps, b, mark, kernel_id, h,
                gravity, q0):
    """The faces' terms at the point x: (number of faces within 2h, s, G (3), T g (3), the
    orthonormal basis (a 9-tuple of rows) of span(q0, directions from the faces' nearest
    points to x: radial, or the face's normal where ``flat`` says the nearest point's part
    of the face is flat), its size). ``stamps[b]`` with ``mark`` takes each face once (see
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
                    qx, qy, qz, part = nearest_feature(verts, f, x0, x1, x2)
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
                    if part != 0 and flat[f, part]:  # an edge or vertex inside a plane wall
                        basis, count = add_direction(basis, count, dim, n0, n1, n2)
                    elif dist > 0.0:
                        basis, count = add_direction(basis, count, dim, (x0 - qx) / dist,
                                                      (x1 - qy) / dist, (x2 - qz) / dist)
    return near, s, gr0, gr1, gr2, t0, t1, t2, basis, count


#: normals closer than this (1 - cosine) are in one plane for :func:`flat_parts`
FLAT_TOL = 1e-9


def flat_parts(verts: np.ndarray) -> np.ndarray:
    """(nf, 7) bool: for each face, whether each part of it (indexed as
    :func:`sphcore.api.nearest_feature` numbers them: 1 + j vertex j, 4-6 a triangle's
    edges) lies inside a plane wall: an edge shared by exactly two faces of the same
    orientation and plane, a vertex all of whose edges are such edges (in 2D: a vertex shared
    by exactly two segments in one line). The faces are compared where ``verts`` draws
    them: a group that moves rigidly keeps its flat parts."""
    verts = np.asarray(verts, float)
    nf, nv, dim = verts.shape
    flat = np.zeros((nf, 7), np.bool_)
    if nf == 0:
        return flat
    scale = max(float(np.abs(verts).max()), 1e-300)
    keys = [tuple(np.round(v / scale, 9)) for v in verts.reshape(-1, dim)]
    ids = {}
    vid = np.array([ids.setdefault(k, len(ids)) for k in keys], np.int64).reshape(nf, nv)
    if dim == 2:
        e = verts[:, 1] - verts[:, 0]
        normals = np.stack([-e[:, 1], e[:, 0]], axis=1)
    else:
        normals = np.cross(verts[:, 1] - verts[:, 0], verts[:, 2] - verts[:, 0])
    normals /= np.maximum(np.linalg.norm(normals, axis=1), 1e-300)[:, None]
    if dim == 2:
        at = {}
        for f in range(nf):
            for j in range(2):
                at.setdefault(vid[f, j], []).append(f)
        for f in range(nf):
            for j in range(2):
                faces = at[vid[f, j]]
                flat[f, 1 + j] = len(faces) == 2 and all(normals[f] @ normals[g] > 1.0 - FLAT_TOL for g in faces)
        return flat
    pairs = ((0, 1, 4), (0, 2, 5), (1, 2, 6))
    edges = {}
    for f in range(nf):
        for a, c, _ in pairs:
            edges.setdefault(tuple(sorted((vid[f, a], vid[f, c]))), []).append(f)
    flat_edge = {e: len(fs) == 2 and normals[fs[0]] @ normals[fs[1]] > 1.0 - FLAT_TOL for e, fs in edges.items()}
    vertex_flat = {}
    for e, ok in flat_edge.items():
        for v in e:
            vertex_flat[v] = vertex_flat.get(v, True) and ok
    for f in range(nf):
        for a, c, part in pairs:
            flat[f, part] = flat_edge[tuple(sorted((vid[f, a], vid[f, c])))]
        for j in range(3):
            flat[f, 1 + j] = vertex_flat[vid[f, j]]
    return flat


def stamps_for(nf: int) -> np.ndarray:
    """The scratch of :func:`face_wall_terms` for ``nf`` faces: 64 blocks."""
    return np.full((64, nf), -1, np.int64)
