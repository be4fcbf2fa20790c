"""Wall share s, its gradient G and the hydrostatic moment T g of a convex domain, exact.

For a point x of the fluid Omega (intersection of the half-spaces d_k = n_k.x - o_k >= 0,
n_k pointing into the fluid) and the outside O = R^dim minus Omega, with y = x' - x, r = |y|:

    s(x) = int_O W(r) dx'                      wall share (1 - gamma_a of Ferrand et al. 2013)
    G(x) = grad s = int_O F(r) (x - x') dx'    1/m, points towards the walls
    T(x) = int_O (-F) y y^T dx' - s I          moment tensor (1); ``wall_terms`` returns T g

By the divergence theorem (boundary-integral walls: Kulasegaram et al. 2004, Feldman &
Bonet 2007, Ferrand et al. 2013, Mayrhofer et al. 2015) these are integrals over the
wall faces (``faces.py``, closed forms, any corner angle, k up to ~12 planes):

    s = sum_k d_k int_{face_k} (K(2h) - K(r)) / r^dim dS,   G = -sum_k n_k int_{face_k} W dS,
    T g = -sum_k (n_k . g) int_{face_k} W y dS.

One plane at distance z: s = S(z), G = -Wbar(z) n, T g = z (g.n) Wbar(z) n, Wbar = int_plane W
(the marginal kernel, S' = -Wbar); these are tabulated from the closed forms (cubic
interpolation, error < 1e-11) and used for particles within 2h of a single plane.
Points with d_k < 0 (outside) are treated as lying on plane k.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from sphcore.api import particle_distance, plane_distance

from .faces import PS2_, face2, face3, lval, segment2
from .tables import PS, PW, PW2

# ---------------------------------------------------------------- single plane

NTAB = 2048  # intervals of the single-plane tables on z in [0, 2h]


@njit(cache=True)
def plane_exact(kid, dim, z):
    """(S(z), h Wbar(z)) of one plane at distance z (units of h), closed form.

    S = wall share (1), Wbar = int_plane W dS (1/m), the marginal kernel; S' = -Wbar.
    """
    if z >= 2.0:
        return 0.0, 0.0
    if dim == 2:
        sz, wz, _ = segment2(kid, z, -np.inf, np.inf)
        return sz, wz
    return (2.0 * math.pi * (z * PS2_[kid] - lval(PS, kid, 1, z, 1)),
            2.0 * math.pi * (PW2[kid, 1] - lval(PW, kid, 1, z, 0)))


@njit(cache=True)
def _fill_plane_tables(tab):
    for kid in range(2):
        for di in range(2):
            for i in range(NTAB + 1):
                tab[kid, di, 0, i], tab[kid, di, 1, i] = plane_exact(kid, di + 2, 2.0 * i / NTAB)


PLANE = np.zeros((2, 2, 2, NTAB + 1))
_fill_plane_tables(PLANE)


@njit(cache=True)
def _plane_lookup(kid, di, z):
    """(S(z), h Wbar(z)) by 4-point (cubic) Lagrange interpolation in PLANE; error < 1e-10."""
    u = z * (NTAB / 2.0)
    i = min(max(int(u) - 1, 0), NTAB - 3)
    t = u - i  # nodes at t = 0, 1, 2, 3
    l0 = -(t - 1.0) * (t - 2.0) * (t - 3.0) / 6.0
    l1 = t * (t - 2.0) * (t - 3.0) / 2.0
    l2 = -t * (t - 1.0) * (t - 3.0) / 2.0
    l3 = t * (t - 1.0) * (t - 2.0) / 6.0
    sz = (l0 * PLANE[kid, di, 0, i] + l1 * PLANE[kid, di, 0, i + 1]
          + l2 * PLANE[kid, di, 0, i + 2] + l3 * PLANE[kid, di, 0, i + 3])
    wz = (l0 * PLANE[kid, di, 1, i] + l1 * PLANE[kid, di, 1, i + 1]
          + l2 * PLANE[kid, di, 1, i + 2] + l3 * PLANE[kid, di, 1, i + 3])
    return sz, wz


# ---------------------------------------------------------------- drivers



@njit(cache=True)
def _degenerate(x0, x1, x2, normals, offsets, h):
    """True where the face formulas are 0/0: the foot point of x on plane k lies on the
    trace of another plane j within 2h (3D; a vertex of face k may sit there), or x is on
    two walls at once (2D corner)."""
    nk, dim = normals.shape
    for k in range(nk):
        dk = max(plane_distance(normals, offsets, k, x0, x1, x2), 0.0) / h
        if dk >= 2.0:
            continue
        for j in range(nk):
            dj = max(plane_distance(normals, offsets, j, x0, x1, x2), 0.0) / h
            if j == k or dj >= 2.0:
                continue
            nn = normals[j, 0] * normals[k, 0] + normals[j, 1] * normals[k, 1]
            if dim == 3:
                nn += normals[j, 2] * normals[k, 2]
            c = dj - dk * nn
            if dim == 2:
                if dk < 1e-11 and abs(c) < 1e-11:
                    return True
            elif 1.0 - nn * nn > 1e-20 and abs(c) < 1e-11 * math.sqrt(1.0 - nn * nn):
                return True
    return False


@njit(cache=True)
def wall_point(x0, x1, x2, normals, offsets, kernel_id, h, g0, g1, g2):
    """(s, G0, G1, G2, Tg0, Tg1, Tg2) at one point; s dimensionless, G in 1/m, T g in units of g.

    ``normals`` (k, dim) unit, into the fluid; ``offsets`` (k,) in m; h in m; unused
    components (dim = 2: x2, g2, G2, Tg2) are ignored / zero. At the rare degenerate points
    (see ``_degenerate``: on an edge, at a corner, or projecting exactly onto an edge line)
    x is moved 1e-8 h into the fluid along a generic direction (s, G, T g change by ~1e-8).
    """
    nact = 0
    for k in range(normals.shape[0]):
        if plane_distance(normals, offsets, k, x0, x1, x2) < 2.0 * h:
            nact += 1
    if nact >= 2 and _degenerate(x0, x1, x2, normals, offsets, h):
        v0, v1, v2 = 0.31, 0.57, 0.27 * (normals.shape[1] == 3)
        for k in range(normals.shape[0]):
            if plane_distance(normals, offsets, k, x0, x1, x2) < 1e-9 * h:
                v0 += normals[k, 0]
                v1 += normals[k, 1]
                if normals.shape[1] == 3:
                    v2 += normals[k, 2]
        x0 += 1e-8 * h * v0
        x1 += 1e-8 * h * v1
        x2 += 1e-8 * h * v2
    return _point_core(x0, x1, x2, normals, offsets, kernel_id, h, g0, g1, g2)


@njit(cache=True)
def _point_core(x0, x1, x2, normals, offsets, kernel_id, h, g0, g1, g2):
    nk, dim = normals.shape
    s = 0.0
    gr0 = 0.0
    gr1 = 0.0
    gr2 = 0.0
    t0 = 0.0
    t1 = 0.0
    t2 = 0.0
    nact = 0
    for k in range(nk):
        dk = normals[k, 0] * x0 + normals[k, 1] * x1 - offsets[k]
        if dim == 3:
            dk += normals[k, 2] * x2
        if dk < 2.0 * h:
            nact += 1
    if nact == 0:
        return s, gr0, gr1, gr2, t0, t1, t2
    for k in range(nk):
        n0 = normals[k, 0]
        n1 = normals[k, 1]
        n2 = normals[k, 2] if dim == 3 else 0.0
        d = (n0 * x0 + n1 * x1 + n2 * x2 - offsets[k]) / h if dim == 3 else (n0 * x0 + n1 * x1 - offsets[k]) / h
        if d >= 2.0:
            continue
        d = max(d, 0.0)
        m0 = 0.0
        m1 = 0.0
        m2 = 0.0
        if nact == 1:  # one plane: tabulated S(z), Wbar(z); no in-plane moment by symmetry
            fs, fw = _plane_lookup(kernel_id, dim - 2, d)
        elif dim == 2:
            fs, fw, fwt, tx, ty = face2(kernel_id, x0, x1, normals, offsets, h, k, d)
            m0 = fwt * tx
            m1 = fwt * ty
        else:
            fs, fw, m0, m1, m2 = face3(kernel_id, x0, x1, x2, normals, offsets, h, k, d)
        s, gr0, gr1, gr2, t0, t1, t2 = add_face(s, gr0, gr1, gr2, t0, t1, t2, fs, fw, m0, m1, m2,
                                                n0, n1, n2, d, h, g0, g1, g2)
    return s, gr0, gr1, gr2, t0, t1, t2


@njit(cache=True, inline="always")
def add_face(s, gr0, gr1, gr2, t0, t1, t2, fs, fw, m0, m1, m2, n0, n1, n2, d, h, g0, g1, g2):
    """One face's part of (s, G, T g): its share fs, G -= n int W dS / h, and with the
    face's first moment m = int W y dS = -d n int W dS + the in-plane moment (m0, m1, m2),
    T g -= (n . g) m (d, fs, fw, m in units of h; n the face's normal into the fluid)."""
    s += fs
    gr0 -= n0 * fw / h
    gr1 -= n1 * fw / h
    gr2 -= n2 * fw / h
    ng = n0 * g0 + n1 * g1 + n2 * g2
    t0 -= ng * (m0 - d * n0 * fw)
    t1 -= ng * (m1 - d * n1 * fw)
    t2 -= ng * (m2 - d * n2 * fw)
    return s, gr0, gr1, gr2, t0, t1, t2


@njit(cache=True, inline="always")
def add_terms_to(i, dim, s, g0, g1, g2, t0, t1, t2, share, grad, hydro):
    """share[i] += s, grad[i] += G, hydro[i] += T g (their first ``dim`` components): how
    each source of wall terms (planes, faces, their table) adds into the core's arrays."""
    share[i] += s
    grad[i, 0] += g0
    grad[i, 1] += g1
    hydro[i, 0] += t0
    hydro[i, 1] += t1
    if dim == 3:
        grad[i, 2] += g2
        hydro[i, 2] += t2


@njit(cache=True, parallel=True)
def wall_terms(pos, normals, offsets, kernel_id, h, gravity, share, grad, hydro):
    """Fill share (n,), grad (n, >=dim) and hydro (n, >=dim) for every particle; see module doc.

    pos (n, dim) m; normals (k, dim); offsets (k,) m; gravity (3,) m/s^2 (first dim used).
    share = s (1), grad = G = grad s (1/m), hydro = T g (m/s^2). Particles farther than 2h
    from every plane get zeros after k dot products. Deterministic (no reductions).
    """
    n, dim = pos.shape
    g0, g1 = gravity[0], gravity[1]
    g2 = gravity[2] if dim == 3 else 0.0
    nk = normals.shape[0]
    for i in prange(n):
        x2 = pos[i, 2] if dim == 3 else 0.0
        dmin = np.inf
        for k in range(nk):
            dmin = min(dmin, particle_distance(normals, offsets, k, pos, i))
        if dmin >= 2.0 * h:  # far from every wall: the common case, kept cheap
            share[i] = 0.0
            for c in range(dim):
                grad[i, c] = 0.0
                hydro[i, c] = 0.0
            continue
        s, a0, a1, a2, t0, t1, t2 = wall_point(pos[i, 0], pos[i, 1], x2, normals, offsets,
                                               kernel_id, h, g0, g1, g2)
        share[i] = s
        grad[i, 0] = a0
        grad[i, 1] = a1
        hydro[i, 0] = t0
        hydro[i, 1] = t1
        if dim == 3:
            grad[i, 2] = a2
            hydro[i, 2] = t2


def wall_terms_at(x, normals, offsets, kernel_id, h, gravity=(0.0, 0.0, 0.0)):
    """Python convenience for probes and tests: (s, G (dim,), T g (dim,)) at one point x."""
    x = np.asarray(x, float)
    dim = x.size
    g = np.zeros(3)
    g[: len(gravity)] = gravity
    nrm = np.ascontiguousarray(normals, dtype=float)
    off = np.ascontiguousarray(offsets, dtype=float)
    x2 = x[2] if dim == 3 else 0.0
    r = wall_point(x[0], x[1], x2, nrm, off, int(kernel_id), float(h), g[0], g[1], g[2])
    return r[0], np.array(r[1:1 + dim]), np.array(r[4:4 + dim])


def moment_tensor_at(x, normals, offsets, kernel_id, h):
    """T (dim, dim) at x, column j = T e_j (dimensionless); symmetric up to round-off."""
    dim = np.asarray(x).size
    return np.stack([wall_terms_at(x, normals, offsets, kernel_id, h, np.eye(3)[j])[2]
                     for j in range(dim)], axis=1)
