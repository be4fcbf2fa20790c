"""Distance and swept-sphere contact for finite wall faces (numba kernels).

A face is a segment (2D) or a triangle (3D), stored as ``verts[f]`` of shape (dim, dim):
row j is vertex j. Points are passed as scalars (x0, x1, x2), x2 ignored in 2D, so the
kernels allocate nothing.

The set of centres closer than r to a face is convex (a capsule in 2D; a triangle
thickened by r, with rounded edges and vertices, in 3D). A sphere of radius r whose
centre moves along A + t (B - A), t in [0, 1], first touches the face at the smallest t
where the centre enters that set. Its boundary is made of pieces: the two lines (planes)
parallel to the face at distance r, over the face; the cylinders of radius r around the
edges (3D), over their length; the circles (spheres) of radius r around the vertices.
The entry point lies on one of them, and every point where the path meets a piece within
its extent lies in the set, so the first entry is the smallest such t (the classic
decomposition of continuous collision detection, e.g. Ericson, *Real-Time Collision
Detection*, 2005, sections 5.3.7 and 5.5). The nearest point of a triangle is found by
its Voronoi regions (vertex, edge, interior; same reference, section 5.1.5).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def _vert(verts, f, j, c):
    """Coordinate c of vertex j of face f (0 for c = 2 in 2D)."""
    return verts[f, j, c] if c < verts.shape[2] else 0.0


#: which part of a face holds its nearest point (:func:`nearest_feature`): the interior, a
#: vertex (1 + j: vertex j) or, of a triangle, an edge (4: vertices 0-1, 5: 0-2, 6: 1-2)
INTERIOR, EDGE_01, EDGE_02, EDGE_12 = 0, 4, 5, 6


@njit(cache=True)
def nearest_feature(verts, f, x0, x1, x2):
    """(q0, q1, q2, part): the point of face f nearest to (x0, x1, x2) and the part of the
    face it lies on (:data:`INTERIOR`, 1 + j for vertex j, or an edge code)."""
    if verts.shape[2] == 2:
        p0, p1 = verts[f, 0, 0], verts[f, 0, 1]
        e0, e1 = verts[f, 1, 0] - p0, verts[f, 1, 1] - p1
        t = ((x0 - p0) * e0 + (x1 - p1) * e1) / (e0 * e0 + e1 * e1)
        part = 1 if t <= 0.0 else (2 if t >= 1.0 else INTERIOR)
        t = min(max(t, 0.0), 1.0)
        return p0 + t * e0, p1 + t * e1, 0.0, part
    a0, a1, a2 = verts[f, 0, 0], verts[f, 0, 1], verts[f, 0, 2]
    b0, b1, b2 = verts[f, 1, 0], verts[f, 1, 1], verts[f, 1, 2]
    c0, c1, c2 = verts[f, 2, 0], verts[f, 2, 1], verts[f, 2, 2]
    ab0, ab1, ab2 = b0 - a0, b1 - a1, b2 - a2
    ac0, ac1, ac2 = c0 - a0, c1 - a1, c2 - a2
    ap0, ap1, ap2 = x0 - a0, x1 - a1, x2 - a2
    d1 = ab0 * ap0 + ab1 * ap1 + ab2 * ap2
    d2 = ac0 * ap0 + ac1 * ap1 + ac2 * ap2
    if d1 <= 0.0 and d2 <= 0.0:
        return a0, a1, a2, 1
    bp0, bp1, bp2 = x0 - b0, x1 - b1, x2 - b2
    d3 = ab0 * bp0 + ab1 * bp1 + ab2 * bp2
    d4 = ac0 * bp0 + ac1 * bp1 + ac2 * bp2
    if d3 >= 0.0 and d4 <= d3:
        return b0, b1, b2, 2
    vc = d1 * d4 - d3 * d2
    if vc <= 0.0 and d1 >= 0.0 and d3 <= 0.0:
        v = d1 / (d1 - d3)
        return a0 + v * ab0, a1 + v * ab1, a2 + v * ab2, EDGE_01
    cp0, cp1, cp2 = x0 - c0, x1 - c1, x2 - c2
    d5 = ab0 * cp0 + ab1 * cp1 + ab2 * cp2
    d6 = ac0 * cp0 + ac1 * cp1 + ac2 * cp2
    if d6 >= 0.0 and d5 <= d6:
        return c0, c1, c2, 3
    vb = d5 * d2 - d1 * d6
    if vb <= 0.0 and d2 >= 0.0 and d6 <= 0.0:
        w = d2 / (d2 - d6)
        return a0 + w * ac0, a1 + w * ac1, a2 + w * ac2, EDGE_02
    va = d3 * d6 - d5 * d4
    if va <= 0.0 and (d4 - d3) >= 0.0 and (d5 - d6) >= 0.0:
        w = (d4 - d3) / ((d4 - d3) + (d5 - d6))
        return b0 + w * (c0 - b0), b1 + w * (c1 - b1), b2 + w * (c2 - b2), EDGE_12
    den = 1.0 / (va + vb + vc)
    v = vb * den
    w = vc * den
    return a0 + ab0 * v + ac0 * w, a1 + ab1 * v + ac1 * w, a2 + ab2 * v + ac2 * w, INTERIOR


@njit(cache=True)
def nearest_point(verts, f, x0, x1, x2):
    """The point (q0, q1, q2) of face f nearest to (x0, x1, x2)."""
    q0, q1, q2, _ = nearest_feature(verts, f, x0, x1, x2)
    return q0, q1, q2


@njit(cache=True)
def face_distance(verts, f, x0, x1, x2):
    """Distance (m) of (x0, x1, x2) to face f."""
    q0, q1, q2 = nearest_point(verts, f, x0, x1, x2)
    return math.sqrt((x0 - q0) ** 2 + (x1 - q1) ** 2 + (x2 - q2) ** 2)


@njit(cache=True, inline="always")
def _sphere_entry(c0, c1, c2, a0, a1, a2, d0, d1, d2, r):
    """Smallest t in [0, 1] where A + t D enters the ball |X - C| <= r (inf if none).
    A outside the ball is assumed (the caller handles a start inside the set)."""
    m0, m1, m2 = a0 - c0, a1 - c1, a2 - c2
    qa = d0 * d0 + d1 * d1 + d2 * d2
    qb = m0 * d0 + m1 * d1 + m2 * d2
    qc = m0 * m0 + m1 * m1 + m2 * m2 - r * r
    if qb >= 0.0 or qa == 0.0:
        return np.inf  # moving away (or not at all)
    disc = qb * qb - qa * qc
    if disc < 0.0:
        return np.inf
    t = (-qb - math.sqrt(disc)) / qa  # qc > 0 and qb < 0: the entering root is >= 0
    return max(t, 0.0) if t <= 1.0 else np.inf


@njit(cache=True, inline="always")
def _cylinder_entry(p0, p1, p2, e0, e1, e2, a0, a1, a2, d0, d1, d2, r):
    """Smallest t in [0, 1] where A + t D enters the cylinder of radius r around the
    segment P + s E, s in [0, 1], through its side (the end caps lie inside the vertex
    balls, handled separately); inf if none."""
    ee = e0 * e0 + e1 * e1 + e2 * e2
    m0, m1, m2 = a0 - p0, a1 - p1, a2 - p2
    md = m0 * e0 + m1 * e1 + m2 * e2
    dd = d0 * e0 + d1 * e1 + d2 * e2
    # components perpendicular to the axis
    u0, u1, u2 = m0 - md / ee * e0, m1 - md / ee * e1, m2 - md / ee * e2
    w0, w1, w2 = d0 - dd / ee * e0, d1 - dd / ee * e1, d2 - dd / ee * e2
    qa = w0 * w0 + w1 * w1 + w2 * w2
    qb = u0 * w0 + u1 * w1 + u2 * w2
    qc = u0 * u0 + u1 * u1 + u2 * u2 - r * r
    if qb >= 0.0 or qa == 0.0 or qc < 0.0:
        return np.inf  # moving away from the axis, parallel to it, or starting within it
    disc = qb * qb - qa * qc
    if disc < 0.0:
        return np.inf
    t = (-qb - math.sqrt(disc)) / qa
    if t > 1.0:
        return np.inf
    s = (md + t * dd) / ee
    return t if 0.0 <= s <= 1.0 else np.inf


@njit(cache=True)
def first_contact(verts, f, a0, a1, a2, b0, b1, b2, r):
    """Smallest t in [0, 1] at which a sphere of radius r (m) whose centre moves from A to B
    touches face f; 0 when A is already within r; inf when it never does."""
    dim = verts.shape[2]
    if face_distance(verts, f, a0, a1, a2) <= r:
        return 0.0
    d0, d1, d2 = b0 - a0, b1 - a1, b2 - a2
    best = np.inf
    nv = dim  # vertices per face: 2 (segment) or 3 (triangle)
    for j in range(nv):
        t = _sphere_entry(_vert(verts, f, j, 0), _vert(verts, f, j, 1), _vert(verts, f, j, 2),
                          a0, a1, a2, d0, d1, d2, r)
        best = min(best, t)
    p0, p1, p2 = _vert(verts, f, 0, 0), _vert(verts, f, 0, 1), _vert(verts, f, 0, 2)
    if dim == 2:
        e0, e1 = verts[f, 1, 0] - p0, verts[f, 1, 1] - p1
        ln = math.sqrt(e0 * e0 + e1 * e1)
        n0, n1, n2 = -e1 / ln, e0 / ln, 0.0
    else:
        for j in range(3):
            k = (j + 1) % 3
            q0, q1, q2 = verts[f, j, 0], verts[f, j, 1], verts[f, j, 2]
            t = _cylinder_entry(q0, q1, q2, verts[f, k, 0] - q0, verts[f, k, 1] - q1,
                                verts[f, k, 2] - q2, a0, a1, a2, d0, d1, d2, r)
            best = min(best, t)
        u0, u1, u2 = verts[f, 1, 0] - p0, verts[f, 1, 1] - p1, verts[f, 1, 2] - p2
        v0, v1, v2 = verts[f, 2, 0] - p0, verts[f, 2, 1] - p1, verts[f, 2, 2] - p2
        n0, n1, n2 = u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0
        ln = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
        n0, n1, n2 = n0 / ln, n1 / ln, n2 / ln
    # the face's own extent: the path reaches |n . (X - P)| = r from the side A is on
    sa = n0 * (a0 - p0) + n1 * (a1 - p1) + n2 * (a2 - p2)
    sd = n0 * d0 + n1 * d1 + n2 * d2
    sgn = 1.0 if sa >= 0.0 else -1.0
    if sgn * sd < 0.0 and sgn * sa > r:
        t = (sgn * sa - r) / (-sgn * sd)
        if t <= 1.0 and _over_face(verts, f, a0 + t * d0 - p0, a1 + t * d1 - p1, a2 + t * d2 - p2):
            best = min(best, t)
    return best


@njit(cache=True, inline="always")
def _over_face(verts, f, x0, x1, x2):
    """Whether the point P + x (P the face's vertex 0) projects onto the face."""
    if verts.shape[2] == 2:
        e0, e1 = verts[f, 1, 0] - verts[f, 0, 0], verts[f, 1, 1] - verts[f, 0, 1]
        s = x0 * e0 + x1 * e1
        return 0.0 <= s <= e0 * e0 + e1 * e1
    u0, u1, u2 = (verts[f, 1, 0] - verts[f, 0, 0], verts[f, 1, 1] - verts[f, 0, 1],
                  verts[f, 1, 2] - verts[f, 0, 2])
    v0, v1, v2 = (verts[f, 2, 0] - verts[f, 0, 0], verts[f, 2, 1] - verts[f, 0, 1],
                  verts[f, 2, 2] - verts[f, 0, 2])
    uu = u0 * u0 + u1 * u1 + u2 * u2
    vv = v0 * v0 + v1 * v1 + v2 * v2
    uv = u0 * v0 + u1 * v1 + u2 * v2
    xu = x0 * u0 + x1 * u1 + x2 * u2
    xv = x0 * v0 + x1 * v1 + x2 * v2
    den = uu * vv - uv * uv
    s = (xu * vv - xv * uv) / den
    w = (xv * uu - xu * uv) / den
    return s >= 0.0 and w >= 0.0 and s + w <= 1.0
