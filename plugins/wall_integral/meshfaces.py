"""The wall share s, its gradient G and the moment T g of finite wall faces, exact.

The same boundary integrals as ``share.py`` (module doc there: Kulasegaram et al. 2004,
Feldman & Bonet 2007, Ferrand et al. 2013), over the faces of ``sphcore.geometry.faces.Faces``
instead of the clipped planes. For the region O outside the fluid bounded by closed faces
(an obstacle, a tank) the divergence theorem gives, face by face,

    s = sum_f d_f int_{f} (K(2h) - K(r)) / r^dim dS,   G = -sum_f n_f int_f W dS,
    T g = -sum_f (n_f . g) int_f W y dS,

with n_f the face's normal into the fluid and d_f = n_f . (x - x_f) its SIGNED distance:
a face seen from behind (x on its solid side's plane, beyond its edges) enters with
d_f < 0. The integrand vanishes beyond r = 2h, so only faces within 2h count, and the sum
is exact for any polyhedral O: concave corners, obstacles standing on a plane wall (the
shared face cancels against the plane's; volumes add) and meshes. Each face is a segment
(2D: ``faces.segment2`` over its extent along the line) or a triangle (3D: the signed
triangles (foot point, edge) of ``faces.edge3`` over its three edges, plus the polar
sector when the foot point lies on the triangle, exactly as ``faces.face3`` does for a
clipped plane). The integrals depend on |d_f| and on the face's extent in its plane;
the sign of d_f multiplies s and enters T g.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .faces import EPS, edge3, plane_basis, sector, segment2
from .share import add_face

#: a foot point closer than this (units of h) to a vertex of its triangle is moved this far
#: into the triangle (:func:`triangle_terms`)
VERTEX_FOOT = 1e-9


@njit(cache=True)
def segment_terms(kid, x0, x1, verts, f, h):
    """(s, int W dt, int W t dt, tau0, tau1, n0, n1, d) of segment f for the point x (units
    of h; tau the segment's direction, n its normal (tau1, -tau0), d the signed distance)."""
    p0, p1 = verts[f, 0, 0], verts[f, 0, 1]
    e0, e1 = verts[f, 1, 0] - p0, verts[f, 1, 1] - p1
    ln = math.sqrt(e0 * e0 + e1 * e1)
    t0, t1 = e0 / ln, e1 / ln
    n0, n1 = t1, -t0
    d = (n0 * (x0 - p0) + n1 * (x1 - p1)) / h
    lo = (t0 * (p0 - x0) + t1 * (p1 - x1)) / h
    hi = lo + ln / h
    s, w, wt = segment2(kid, abs(d), lo, hi)
    return (s if d >= 0.0 else -s), w, wt, t0, t1, n0, n1, d


@njit(cache=True)
def triangle_terms(kid, x0, x1, x2, verts, f, h):
    """(s, int W dA, in-plane int W y dA (3), n (3), d) of triangle f for the point x (units
    of h; n its unit normal, d the signed distance)."""
    a = verts[f, 0]
    u0, u1, u2 = verts[f, 1, 0] - a[0], verts[f, 1, 1] - a[1], verts[f, 1, 2] - a[2]
    v0, v1, v2 = verts[f, 2, 0] - a[0], verts[f, 2, 1] - a[1], verts[f, 2, 2] - a[2]
    n0, n1, n2 = u1 * v2 - u2 * v1, u2 * v0 - u0 * v2, u0 * v1 - u1 * v0
    ln = math.sqrt(n0 * n0 + n1 * n1 + n2 * n2)
    n0, n1, n2 = n0 / ln, n1 / ln, n2 / ln
    d = (n0 * (x0 - a[0]) + n1 * (x1 - a[1]) + n2 * (x2 - a[2])) / h
    ad = abs(d)
    if ad >= 2.0:
        return 0.0, 0.0, 0.0, 0.0, 0.0, n0, n1, n2, d
    # orthonormal (e1, e2) with e1 x e2 = n: the vertices, seen from the foot point, run
    # counter-clockwise (the right-hand orientation of the face)
    (e10, e11, e12), (e20, e21, e22) = plane_basis(n0, n1, n2)
    # in-plane coordinates of the vertices from the foot point (units of h)
    w0, w1, w2 = verts[f, 0, 0] - x0, verts[f, 0, 1] - x1, verts[f, 0, 2] - x2
    qa0 = (w0 * e10 + w1 * e11 + w2 * e12) / h
    qa1 = (w0 * e20 + w1 * e21 + w2 * e22) / h
    w0, w1, w2 = verts[f, 1, 0] - x0, verts[f, 1, 1] - x1, verts[f, 1, 2] - x2
    qb0 = (w0 * e10 + w1 * e11 + w2 * e12) / h
    qb1 = (w0 * e20 + w1 * e21 + w2 * e22) / h
    w0, w1, w2 = verts[f, 2, 0] - x0, verts[f, 2, 1] - x1, verts[f, 2, 2] - x2
    qc0 = (w0 * e10 + w1 * e11 + w2 * e12) / h
    qc1 = (w0 * e20 + w1 * e21 + w2 * e22) / h
    if min(qa0 * qa0 + qa1 * qa1, qb0 * qb0 + qb1 * qb1, qc0 * qc0 + qc1 * qc1) < VERTEX_FOOT ** 2:
        # the foot on a vertex: the edges' angles below take a foot on an edge's line as just
        # inside it, which at a vertex makes the corner a half-plane. Move the foot into the
        # triangle (towards its centroid) by VERTEX_FOOT, so that each edge sees it inside.
        c0, c1 = (qa0 + qb0 + qc0) / 3.0, (qa1 + qb1 + qc1) / 3.0
        cl = VERTEX_FOOT / math.sqrt(c0 * c0 + c1 * c1)
        qa0, qa1, qb0, qb1, qc0, qc1 = (qa0 - c0 * cl, qa1 - c1 * cl, qb0 - c0 * cl, qb1 - c1 * cl, qc0 - c0 * cl,
                                        qc1 - c1 * cl)
    inside = 1.0
    s = 0.0
    w = 0.0
    phi = 0.0
    m0 = 0.0
    m1 = 0.0
    m2 = 0.0
    for j in range(3):
        if j == 0:
            pj0, pj1, pk0, pk1 = qa0, qa1, qb0, qb1
        elif j == 1:
            pj0, pj1, pk0, pk1 = qb0, qb1, qc0, qc1
        else:
            pj0, pj1, pk0, pk1 = qc0, qc1, qa0, qa1
        tx, ty = pk0 - pj0, pk1 - pj1
        tl = math.sqrt(tx * tx + ty * ty)
        tx, ty = tx / tl, ty / tl
        ax, ay = -ty, tx  # inward normal of the edge (counter-clockwise polygon)
        b = ax * pj0 + ay * pj1  # inside: a . u >= b
        if b > 0.0:
            inside = 0.0  # the foot point lies beyond this edge
        lo = tx * pj0 + ty * pj1
        hi = tx * pk0 + ty * pk1
        p = -b
        p = max(p, EPS) if p >= 0.0 else min(p, -EPS)  # foot on the line counts as inside
        es, ew, eq, ephi = edge3(kid, ad, p, lo, hi)
        s += es
        w += ew
        phi += ephi
        m0 -= eq * (ax * e10 + ay * e20)
        m1 -= eq * (ax * e11 + ay * e21)
        m2 -= eq * (ax * e12 + ay * e22)
    s, w = sector(kid, ad, inside, phi, s, w)
    return (s if d >= 0.0 else -s), w, m0, m1, m2, n0, n1, n2, d


@njit(cache=True, inline="always")
def face_part(kid, x0, x1, x2, verts, f, h):
    """(fs, fw, m0, m1, m2, n0, n1, n2, d) of face f at x, a segment (2D) or a triangle (3D):
    its share, int W dS, in-plane first moment, unit normal and signed distance (units of
    h), the arguments of ``share.add_face``."""
    if verts.shape[2] == 2:
        fs, fw, fwt, ta, tb, n0, n1, d = segment_terms(kid, x0, x1, verts, f, h)
        return fs, fw, fwt * ta, fwt * tb, 0.0, n0, n1, 0.0, d
    return triangle_terms(kid, x0, x1, x2, verts, f, h)


@njit(cache=True)
def face_point(x0, x1, x2, verts, faces_near, count, kernel_id, h, g0, g1, g2):
    """(s, G0, G1, G2, Tg0, Tg1, Tg2) at x from the faces ``faces_near[:count]`` (each once);
    the units of ``share.wall_point``."""
    s = gr0 = gr1 = gr2 = t0 = t1 = t2 = 0.0
    for c in range(count):
        fs, fw, m0, m1, m2, n0, n1, n2, d = face_part(kernel_id, x0, x1, x2, verts, faces_near[c], h)
        s, gr0, gr1, gr2, t0, t1, t2 = add_face(s, gr0, gr1, gr2, t0, t1, t2, fs, fw, m0, m1, m2,
                                                n0, n1, n2, d, h, g0, g1, g2)
    return s, gr0, gr1, gr2, t0, t1, t2


def face_terms_at(x, verts, kernel_id, h, gravity=(0.0, 0.0, 0.0)):
    """Python convenience for tests: (s, G (dim,), T g (dim,)) at x from every face."""
    x = np.asarray(x, float)
    dim = x.size
    g = np.zeros(3)
    g[: len(gravity)] = gravity
    verts = np.ascontiguousarray(verts, dtype=float)
    ids = np.arange(verts.shape[0], dtype=np.int64)
    r = face_point(x[0], x[1], x[2] if dim == 3 else 0.0, verts, ids, ids.size, int(kernel_id), float(h),
                   g[0], g[1], g[2])
    return r[0], np.array(r[1:1 + dim]), np.array(r[4:4 + dim])
