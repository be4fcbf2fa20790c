"""The earliest contact of a moving sphere with the finite wall faces near it.

The faces (segments in 2D, triangles in 3D) come with a uniform grid
(:mod:`sphcore.geometry.facegrid`); a sub-segment A -> B of a particle's step tests only the faces
listed in the cells its box, inflated by the radius, covers. A face collides when the
path comes closer than r - tol to it anywhere (not only at B: a thin wall may be crossed
within one step); the contact is where the distance first reaches r (paper section 2.2
with the plane replaced by the face, :func:`sphcore.geometry.facegeom.first_contact`). The
response then uses the plane tangent to the face's r-neighbourhood at the contact point:
normal n = (C - q) / |C - q|, q the face's point nearest to the contact C. That set is
convex, so the tangent plane separates it from everything on its fluid side: a centre
mirrored to at least r from the plane (Eq. 1) is clear of the face.

The faces and their grid travel as one :class:`FaceSet` (:func:`.entry.face_arrays`);
the functions here, called per particle, take its arrays one by one (see
:func:`.collision.reflect_step`).
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit

from sphcore.api import box_cells, face_distance, first_contact, nearest_point


class FaceSet(NamedTuple):
    """Finite wall faces with the grid that lists them by cell (an empty set: no faces).

    ``verts`` (nf, dim, dim) float64: the faces' vertices (m), segments in 2D, triangles
    in 3D, oriented as in :mod:`sphcore.geometry.faces`. The grid
    (:class:`sphcore.api.FaceGrid`, its ``arrays()``): ``lo`` (3,) float64 lower corner
    (m), ``inv_cell`` 1 / cell side (1/m), ``shape`` (3,) int64 cells per axis (1 for an
    absent z), ``start`` (ncells + 1,) int64 and ``items`` (int32): the faces of cell c
    are items[start[c]:start[c + 1]].
    """

    verts: np.ndarray
    lo: np.ndarray
    inv_cell: float
    shape: np.ndarray
    start: np.ndarray
    items: np.ndarray


@njit(cache=True)
def near_any_face(verts, lo, inv_cell, shape, start, items, a0, a1, a2, b0, b1, b2, lim):
    """Whether some face may come closer than ``lim`` (m) to the path A -> B (a cheap
    test: the distance at B minus the path's length)."""
    if verts.shape[0] == 0:
        return False
    dim = verts.shape[2]
    ln = math.sqrt((b0 - a0) ** 2 + (b1 - a1) ** 2 + (b2 - a2) ** 2)
    x0, x1, y0, y1, z0, z1 = box_cells(lo, inv_cell, shape, dim, a0, a1, a2, b0, b1, b2, lim)
    for x in range(x0, x1 + 1):
        for y in range(y0, y1 + 1):
            for z in range(z0, z1 + 1):
                c = (x * shape[1] + y) * shape[2] + z
                for s in range(start[c], start[c + 1]):
                    if face_distance(verts, items[s], b0, b1, b2) - ln < lim:
                        return True
    return False


@njit(cache=True)
def earliest_face(verts, lo, inv_cell, shape, start, items, a0, a1, a2, b0, b1, b2, r, lim, fbest):
    """(face, t): the face with the earliest contact t < ``fbest`` along A -> B for a sphere
    of radius r (m) among those the path comes closer to than ``lim``; (-1, fbest) if none."""
    best = -1
    if verts.shape[0] == 0:
        return best, fbest
    dim = verts.shape[2]
    ln = math.sqrt((b0 - a0) ** 2 + (b1 - a1) ** 2 + (b2 - a2) ** 2)
    x0, x1, y0, y1, z0, z1 = box_cells(lo, inv_cell, shape, dim, a0, a1, a2, b0, b1, b2, r)
    for x in range(x0, x1 + 1):
        for y in range(y0, y1 + 1):
            for z in range(z0, z1 + 1):
                c = (x * shape[1] + y) * shape[2] + z
                for s in range(start[c], start[c + 1]):
                    f = items[s]
                    if f == best or face_distance(verts, f, b0, b1, b2) - ln >= lim:
                        continue
                    tl = first_contact(verts, f, a0, a1, a2, b0, b1, b2, lim)
                    if tl > 1.0:
                        continue  # never closer than lim: a graze within the tolerance
                    # the contact at r comes no later than at lim; a start within an ulp of
                    # r (a touching start, a corner's contact point) may round to "never"
                    t = min(first_contact(verts, f, a0, a1, a2, b0, b1, b2, r), tl)
                    if t == 0.0:
                        # touching (or overlapping) at the start: a contact only when the path
                        # heads towards the face (the distance along a line to a convex set is
                        # convex: a path leaving it never comes closer)
                        q0, q1, q2 = nearest_point(verts, f, a0, a1, a2)
                        away = (a0 - q0) * (b0 - a0) + (a1 - q1) * (b1 - a1) + (a2 - q2) * (b2 - a2)
                        if away >= 0.0 and (a0 - q0) ** 2 + (a1 - q1) ** 2 + (a2 - q2) ** 2 > 0.0:
                            continue
                    if t < fbest:
                        fbest = t
                        best = f
    return best, fbest


@njit(cache=True)
def contact_normal(verts, f, c0, c1, c2, p0, p1, p2):
    """(n0, n1, n2, offset): the plane tangent at contact C to face f's neighbourhood,
    n . X = offset + |C - q| on it (q nearest to C); n points from the face to C. When C
    lies on the face itself (a start already overlapping it), the face's normal is turned
    towards the start-of-step position P."""
    q0, q1, q2 = nearest_point(verts, f, c0, c1, c2)
    n0, n1, n2 = c0 - q0, c1 - q1, c2 - q2
    ln = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    if ln > 0.0:
        n0, n1, n2 = n0 / ln, n1 / ln, n2 / ln
    else:
        n0, n1, n2 = face_normal(verts, f)
        if n0 * (p0 - q0) + n1 * (p1 - q1) + n2 * (p2 - q2) < 0.0:
            n0, n1, n2 = -n0, -n1, -n2
    return n0, n1, n2, n0 * q0 + n1 * q1 + n2 * q2


@njit(cache=True)
def face_normal(verts, f):
    """Unit normal of face f (the orientation of :mod:`sphcore.geometry.faces`)."""
    if verts.shape[2] == 2:
        e0, e1 = verts[f, 1, 0] - verts[f, 0, 0], verts[f, 1, 1] - verts[f, 0, 1]
        ln = math.sqrt(e0 * e0 + e1 * e1)
        return e1 / ln, -e0 / ln, 0.0
    u = verts[f, 1] - verts[f, 0]
    v = verts[f, 2] - verts[f, 0]
    n0, n1, n2 = u[1] * v[2] - u[2] * v[1], u[2] * v[0] - u[0] * v[2], u[0] * v[1] - u[1] * v[0]
    ln = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    return n0 / ln, n1 / ln, n2 / ln


def empty_grid(dim):
    """The :class:`FaceSet` of a case without faces."""
    return FaceSet(np.zeros((0, dim, dim)), np.zeros(3), 1.0, np.ones(3, np.int64),
                   np.zeros(2, np.int64), np.zeros(0, np.int32))
