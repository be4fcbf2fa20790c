"""Wall share s, its gradient G and the hydrostatic moment T g of a convex domain, exact.

For a point x of the fluid Omega (intersection of the half-spaces d_k = n_k.x - o_k >= 0,
n_k pointing into the fluid) and the outside O = R^dim minus Omega, with y = x' - x, r = |y|:

    s(x) = int_O W(r) dx'                      wall share (1 - gamma, Ferrand et al. 2013 Eq. 14)
    G(x) = grad s = int_O F(r) (x - x') dx'    1/m, points towards the walls
    T(x) = int_O (-F) y y^T dx' - s I          moment tensor; ``share`` returns T g (units of g)

Method (exact, no quadrature): the divergence theorem moves each volume integral onto the
wall faces, which is the boundary-integral form of Kulasegaram et al. (2004) and Feldman &
Bonet (2007). With K(r) = int_0^r W u^(dim-1) du and face_k = plane_k minus the other
half-spaces (a segment in 2D, a convex polygon in 3D), d_k the distance of x to plane k:

    s   =  sum_k d_k int_{face_k} (K(2h) - K(r)) / r^dim dS      (V = y (K - K(2h)) / r^dim)
    G   = -sum_k n_k int_{face_k} W dS                            (Ferrand et al. 2013 Eq. 16)
    T g = -sum_k (n_k . g) m_k,  m_k = int_{face_k} W y dS        (from d_j(W y_i) = F y_i y_j + W d_ij)

The ball boundary r = 2h contributes nothing because the fields vanish there. The face
integrals of piecewise-polynomial radial functions have closed forms (``tables.py``):
in 2D along the segment, int r^k dt by the recurrence A_k = (t r^k + k delta^2 A_(k-2))/(k+1)
and int d/r^2 dt = atan(t/d); in 3D the polygon is split into signed triangles (foot point,
edge), whose polar integrals reduce to p int r^k / (p^2 + t^2) dt (recurrence
B_k = A_(k-2) + d^2 B_(k-2), B_0 = atan(t/p)/p, d B_(-1) = atan(d t / (p r))/p; the s term
K(2h)/r^3 is the solid angle). The in-plane first moment is an edge integral of
Q(r) = -int_r^2h W u du. A single plane has S(z), Wbar(z) in closed form and is the cheap
path; corners, edges, wedges and vertices (any angles, up to ~12 planes) are exact too.
Points with d_k < 0 (outside) are treated as lying on plane k.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from .tables import OFF, PS, PS2, PW, PW2, SC, WC

_EPS = 1e-12
PS2_ = np.ascontiguousarray(PS2[:, 1])  # Psi_s(2h) in 3D, per kernel


@njit(cache=True, inline="always")
def _lval(tab, kid, di, q, shift):
    """Sum_k tab[k] q^(k + shift) for the kernel piece holding q (Laurent row, powers -3..9)."""
    pc = 0 if q < 1.0 else 1
    acc = 0.0
    for k in range(-3, 10):
        c = tab[kid, di, pc, k + OFF]
        if c != 0.0:
            acc += c * q ** (k + shift)
    return acc


# ---------------------------------------------------------------- 2D: segments

@njit(cache=True)
def _seg_prim2(kid, pc, d, t):
    """(d int_0^t f_s dt, int_0^t W dt) on kernel piece pc, line at distance d (h = 1)."""
    r = math.sqrt(d * d + t * t)
    d2 = d * d
    am1 = math.asinh(t / d) if d > _EPS else 0.0
    a0 = t
    a1 = 0.5 * (t * r + d2 * am1)
    s = SC[kid, 0, pc, OFF] * a0 + SC[kid, 0, pc, OFF + 1] * a1
    w = WC[kid, 0, pc, OFF] * a0 + WC[kid, 0, pc, OFF + 1] * a1
    akm2, akm1, rk = a0, a1, r
    for k in range(2, 8):
        rk *= r
        ak = (t * rk + k * d2 * akm2) / (k + 1)
        s += SC[kid, 0, pc, OFF + k] * ak
        w += WC[kid, 0, pc, OFF + k] * ak
        akm2, akm1 = akm1, ak
    return SC[kid, 0, pc, OFF - 2] * math.atan2(t, d) + d * s, w


@njit(cache=True)
def _segment2(kid, d, lo, hi):
    """(d int f_s dt, int W dt, int W t dt) over t in [lo, hi] at distance d, h = 1."""
    if d >= 2.0:
        return 0.0, 0.0, 0.0
    t2 = math.sqrt(4.0 - d * d)
    lo = max(lo, -t2)
    hi = min(hi, t2)
    if lo >= hi:
        return 0.0, 0.0, 0.0
    t1 = math.sqrt(1.0 - d * d) if d < 1.0 else 0.0
    s = 0.0
    w = 0.0
    for j in range(3):
        a, b, pc = (-t2, -t1, 1) if j == 0 else ((-t1, t1, 0) if j == 1 else (t1, t2, 1))
        a = max(a, lo)
        b = min(b, hi)
        if b > a:
            sb, wb = _seg_prim2(kid, pc, d, b)
            sa, wa = _seg_prim2(kid, pc, d, a)
            s += sb - sa
            w += wb - wa
    wt = (_lval(PW, kid, 0, math.sqrt(d * d + hi * hi), 0)
          - _lval(PW, kid, 0, math.sqrt(d * d + lo * lo), 0))
    return s, w, wt


@njit(cache=True)
def _face2(kid, x0, x1, normals, offsets, h, k, d):
    """(s, int W dt, int W t dt, tau) of face k (a segment) for a point at distance d (units of h)."""
    nx, ny = normals[k, 0], normals[k, 1]
    tx, ty = -ny, nx
    lo, hi = -np.inf, np.inf
    for j in range(normals.shape[0]):
        if j == k:
            continue
        dj = (normals[j, 0] * x0 + normals[j, 1] * x1 - offsets[j]) / h
        if dj >= 2.0:
            continue  # its trace on plane k lies outside the support
        cj = normals[j, 0] * tx + normals[j, 1] * ty
        nn = normals[j, 0] * nx + normals[j, 1] * ny
        c = max(dj, 0.0) - d * nn  # d_j at the foot point
        if cj > _EPS:
            lo = max(lo, -c / cj)
        elif cj < -_EPS:
            hi = min(hi, -c / cj)
        elif c < -_EPS or (c <= _EPS and nn > 0.0 and j < k):
            return 0.0, 0.0, 0.0, tx, ty  # hidden by a parallel (or duplicate) plane
    s, w, wt = _segment2(kid, d, lo, hi)
    return s, w, wt, tx, ty


# ---------------------------------------------------------------- 3D: polygons

@njit(cache=True)
def _edge_prim3(kid, pc, d, p, t):
    """Primitives at t for an edge line at in-plane distance p of a face at distance d (h = 1).

    Returns (d sum PS_k pB_k + PS_-1 d pB_-1, sum PW_k pB_k, sum PW_k A_k, pB_0) with
    pB_k = p int_0^t r^k/(p^2+t^2) dt and A_k = int_0^t r^k dt, r^2 = d^2 + p^2 + t^2.
    """
    dl2 = d * d + p * p
    r = math.sqrt(dl2 + t * t)
    am1 = math.asinh(t / math.sqrt(dl2))
    b0 = math.atan(t / p)
    bm1d = math.atan(d * t / (p * r))  # d pB_-1
    a0 = t
    a1 = 0.5 * (t * r + dl2 * am1)
    b1 = p * am1 + d * bm1d
    ps = PS[kid, 1, pc, OFF - 1] * bm1d + d * (PS[kid, 1, pc, OFF] * b0 + PS[kid, 1, pc, OFF + 1] * b1)
    pw = PW[kid, 1, pc, OFF] * b0 + PW[kid, 1, pc, OFF + 1] * b1
    qa = PW[kid, 1, pc, OFF] * a0 + PW[kid, 1, pc, OFF + 1] * a1
    am2, am1_, bm2, bm1_, rk = a0, a1, b0, b1, r
    for k in range(2, 8):
        rk *= r
        ak = (t * rk + k * dl2 * am2) / (k + 1)
        bk = p * am2 + d * d * bm2
        ps += d * PS[kid, 1, pc, OFF + k] * bk
        pw += PW[kid, 1, pc, OFF + k] * bk
        qa += PW[kid, 1, pc, OFF + k] * ak
        am2, am1_, bm2, bm1_ = am1_, ak, bm1_, bk
    return ps, pw, qa, b0


@njit(cache=True)
def _edge3(kid, d, p, lo, hi):
    """Part inside the support disc of the signed triangle (foot, edge t in [lo, hi]).

    Face at distance d, edge line at signed in-plane distance p (> 0: foot on the inner
    side), h = 1. Returns (d int f_s dA + d Psi_s(d) dphi, int W dA + Psi_W(d) dphi,
    int_edge Q dt, dphi) over the in-disc part, Q = Psi_W(r) - Psi_W(2), dphi its polar
    angle seen from the foot (the -Psi(d) dphi terms are added once per face).
    """
    rr = 4.0 - d * d - p * p
    if rr <= 0.0 or hi <= lo:
        return 0.0, 0.0, 0.0, 0.0
    t2 = math.sqrt(rr)
    dl2 = d * d + p * p
    t1 = math.sqrt(1.0 - dl2) if dl2 < 1.0 else 0.0
    s = 0.0
    w = 0.0
    q = 0.0
    phi = 0.0
    for j in range(3):
        a, b, pc = (-t2, -t1, 1) if j == 0 else ((-t1, t1, 0) if j == 1 else (t1, t2, 1))
        a = max(a, lo)
        b = min(b, hi)
        if b > a:
            sb, wb, qb, b0b = _edge_prim3(kid, pc, d, p, b)
            sa, wa, qa, b0a = _edge_prim3(kid, pc, d, p, a)
            s += sb - sa
            w += wb - wa
            q += qb - qa - PW2[kid, 1] * (b - a)
            phi += b0b - b0a
    return s, w, q, phi


@njit(cache=True, inline="always")
def _constraint3(j, k, x0, x1, x2, normals, offsets, h, e1, e2, d):
    """Half-plane a.u >= b that plane j cuts from face k (u on (e1, e2) from the foot point).

    kind 0: a line; 1: no constraint within the support (j = k, plane j farther than 2h,
    or parallel behind); 2: face k is hidden (parallel plane in front, or a duplicate of
    lower index).
    """
    if j == k:
        return 0.0, 0.0, 0.0, 1
    dj = (normals[j, 0] * x0 + normals[j, 1] * x1 + normals[j, 2] * x2 - offsets[j]) / h
    if dj >= 2.0:
        return 0.0, 0.0, 0.0, 1  # all of plane j lies outside the support ball
    ax = normals[j, 0] * e1[0] + normals[j, 1] * e1[1] + normals[j, 2] * e1[2]
    ay = normals[j, 0] * e2[0] + normals[j, 1] * e2[1] + normals[j, 2] * e2[2]
    nn = normals[j, 0] * normals[k, 0] + normals[j, 1] * normals[k, 1] + normals[j, 2] * normals[k, 2]
    c = max(dj, 0.0) - d * nn  # d_j at the foot point
    na = math.sqrt(ax * ax + ay * ay)
    if na < 1e-10:
        if c < -_EPS or (c <= _EPS and nn > 0.0 and j < k):
            return 0.0, 0.0, 0.0, 2
        return 0.0, 0.0, 0.0, 1
    return ax / na, ay / na, -c / na, 0


@njit(cache=True)
def _face3(kid, x0, x1, x2, normals, offsets, h, k, d):
    """(d int f_s dA, int W dA, in-plane int W y dA (3 components)) of face k, h = 1 units.

    The face polygon P (possibly unbounded) is cut by the other planes within 2h. Sum over
    its edges of the signed triangles (foot, edge) clipped to the disc of radius
    R = sqrt(4 - d^2); the rest of P inside the disc is a polar sector of radius R with
    angle 2 pi [foot in P] - sum of the edges' in-disc angles (winding number), whose
    integrand is the constant Phi(2h) = Psi(2) - Psi(d).
    """
    nk = normals.shape[0]
    n0, n1, n2 = normals[k, 0], normals[k, 1], normals[k, 2]
    if abs(n0) < 0.9:  # orthonormal (e1, e2) with e1 x e2 = n_k
        c0, c1, c2 = 0.0, n2, -n1
    else:
        c0, c1, c2 = -n2, 0.0, n0
    cn = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    e1 = (c0 / cn, c1 / cn, c2 / cn)
    e2 = (n1 * e1[2] - n2 * e1[1], n2 * e1[0] - n0 * e1[2], n0 * e1[1] - n1 * e1[0])
    inside = 1.0
    for j in range(nk):
        kind = _constraint3(j, k, x0, x1, x2, normals, offsets, h, e1, e2, d)
        if kind[3] == 2:
            return 0.0, 0.0, 0.0, 0.0, 0.0
        if kind[3] == 0 and kind[2] > 0.0:  # foot on the outer side of an edge line
            inside = 0.0
    s = 0.0
    w = 0.0
    phi = 0.0
    m0 = 0.0
    m1 = 0.0
    m2 = 0.0
    for i in range(nk):
        ax, ay, b, kind = _constraint3(i, k, x0, x1, x2, normals, offsets, h, e1, e2, d)
        if kind != 0:
            continue
        tx, ty = ay, -ax  # edge direction: polygon counter-clockwise in (e1, e2)
        lo, hi = -np.inf, np.inf
        for j in range(nk):
            if j == i:
                continue
            bx, by, bb, kj = _constraint3(j, k, x0, x1, x2, normals, offsets, h, e1, e2, d)
            if kj != 0:
                continue
            cj = bx * tx + by * ty
            aa = bx * ax + by * ay
            rhs = bb - b * aa
            if cj > _EPS:
                lo = max(lo, rhs / cj)
            elif cj < -_EPS:
                hi = min(hi, rhs / cj)
            elif rhs > _EPS or (rhs >= -_EPS and aa > 0.0 and j < i):
                lo = np.inf  # parallel line in front, or duplicate edge
        if hi <= lo:
            continue
        p = -b
        p = max(p, _EPS) if p >= 0.0 else min(p, -_EPS)  # foot on the line counts as inside
        es, ew, eq, ephi = _edge3(kid, d, p, lo, hi)
        s += es
        w += ew
        phi += ephi
        # in-plane moment: outward edge normal -a times int Q dt (Q = 0 beyond the support)
        m0 -= eq * (ax * e1[0] + ay * e2[0])
        m1 -= eq * (ax * e1[1] + ay * e2[1])
        m2 -= eq * (ax * e1[2] + ay * e2[2])
    arc = 2.0 * math.pi * inside - phi
    dps_d = _lval(PS, kid, 1, d, 1)
    psw_d = _lval(PW, kid, 1, d, 0)
    s += (d * PS2_[kid] - dps_d) * arc - dps_d * phi
    w += (PW2[kid, 1] - psw_d) * arc - psw_d * phi
    return s, w, m0, m1, m2


# ---------------------------------------------------------------- single plane

NTAB = 2048  # intervals of the single-plane tables on z in [0, 2h]


@njit(cache=True)
def plane_exact(kid, dim, z):
    """(S(z), h Wbar(z)) of one plane at distance z (units of h), closed form (Ferrand 2013 Eq. 14).

    S = wall share (1), Wbar = int_plane W dS (1/m), the marginal kernel; S' = -Wbar.
    """
    if z >= 2.0:
        return 0.0, 0.0
    if dim == 2:
        sz, wz, _ = _segment2(kid, z, -np.inf, np.inf)
        return sz, wz
    return (2.0 * math.pi * (z * PS2_[kid] - _lval(PS, kid, 1, z, 1)),
            2.0 * math.pi * (PW2[kid, 1] - _lval(PW, kid, 1, z, 0)))


@njit(cache=True)
def _fill_plane_tables(tab):
    for kid in range(2):
        for di in range(2):
            for i in range(NTAB + 1):
                tab[kid, di, 0, i], tab[kid, di, 1, i] = plane_exact(kid, di + 2, 2.0 * i / NTAB)


PLANE = np.zeros((2, 2, 2, NTAB + 1))
_fill_plane_tables(PLANE)


@njit(cache=True, inline="always")
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
def wall_point(x0, x1, x2, normals, offsets, kernel_id, h, g0, g1, g2):
    """(s, G0, G1, G2, Tg0, Tg1, Tg2) at one point; s dimensionless, G in 1/m, T g in units of g.

    ``normals`` (k, dim) unit, into the fluid; ``offsets`` (k,) in m; h in m; unused
    components (dim = 2: x2, g2, G2, Tg2) are ignored / zero.
    """
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
            fs, fw, fwt, tx, ty = _face2(kernel_id, x0, x1, normals, offsets, h, k, d)
            m0 = fwt * tx
            m1 = fwt * ty
        else:
            fs, fw, m0, m1, m2 = _face3(kernel_id, x0, x1, x2, normals, offsets, h, k, d)
        s += fs
        gr0 -= n0 * fw / h
        gr1 -= n1 * fw / h
        gr2 -= n2 * fw / h
        # m_k = int W y dS = -d n_k int W dS + in-plane moment; T g = -sum (n_k . g) m_k
        ng = n0 * g0 + n1 * g1 + n2 * g2
        t0 -= ng * (m0 - d * n0 * fw)
        t1 -= ng * (m1 - d * n1 * fw)
        t2 -= ng * (m2 - d * n2 * fw)
    return s, gr0, gr1, gr2, t0, t1, t2


@njit(parallel=True, cache=True)
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
            dk = normals[k, 0] * pos[i, 0] + normals[k, 1] * pos[i, 1] - offsets[k]
            if dim == 3:
                dk += normals[k, 2] * x2
            dmin = min(dmin, dk)
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
