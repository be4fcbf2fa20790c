"""Closed-form integrals over the wall faces of a convex domain (2D segments, 3D polygons).

Used by ``share.py``. For a point x at distance d (units of h) from plane k, face_k is the
part of plane k on the fluid side of every other plane within 2h; y = x' - x, r = |y|,
f_s(r) = (K(2h) - K(r)) / r^dim with K(r) = int_0^r W u^(dim-1) du (``tables.py``).
Each function returns, over face_k inside the support (h = 1):

    d int f_s dS    (wall-share part; the divergence theorem with V = y (K(r) - K(2h)) / r^dim)
    int W dS        (so that G = -sum_k n_k int W dS / h; Feldman & Bonet 2007)
    int W y dS      (its in-plane part; T g = -sum_k (n_k . g) int W y dS)

2D: along the segment t in [lo, hi], r^2 = d^2 + t^2; int r^k dt by the recurrence
A_k = (t r^k + k d^2 A_(k-2)) / (k + 1), A_0 = t, A_-1 = asinh(t/d), and
d int r^-2 dt = atan(t/d); int W t dt = Psi_W(r) with Psi_W(r) = int_0^r W u du.
3D: the polygon is a sum of signed triangles (foot point, edge); for an edge at in-plane
distance p, r^2 = d^2 + p^2 + t^2, a triangle's polar integral int dphi Phi(r_edge(phi)),
Phi(r) = int_d^r f u du, is int Phi(r(t)) p dt / (p^2 + t^2), i.e. a sum of
pB_k = p int r^k / (p^2 + t^2) dt: pB_k = p A_(k-2) + d^2 pB_(k-2), pB_0 = atan(t/p),
d pB_-1 = atan(d t / (p r)) (the solid angle of the face, K(2h) / r^3 term). The parts of
the face beyond r = 2h are a polar sector, weight Phi(2h). The in-plane first moment is
the edge integral sum_e nu_e int Q dt, Q(r) = -int_r^2h W u du (in-plane divergence theorem).
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from .tables import OFF, PS, PS2, PW, PW2, SC, WC

EPS = 1e-12
PS2_ = np.ascontiguousarray(PS2[:, 1])  # Psi_s(2h) in 3D, per kernel


@njit(cache=True)
def lval(tab, kid, di, q, shift):
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
    am1 = math.asinh(t / d) if d > EPS else 0.0
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
def segment2(kid, d, lo, hi):
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
    wt = (lval(PW, kid, 0, math.sqrt(d * d + hi * hi), 0)
          - lval(PW, kid, 0, math.sqrt(d * d + lo * lo), 0))
    return s, w, wt


@njit(cache=True)
def face2(kid, x0, x1, normals, offsets, h, k, d):
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
        if cj > EPS:
            lo = max(lo, -c / cj)
        elif cj < -EPS:
            hi = min(hi, -c / cj)
        elif c < -EPS or (c <= EPS and nn > 0.0 and j < k):
            return 0.0, 0.0, 0.0, tx, ty  # hidden by a parallel (or duplicate) plane
    s, w, wt = segment2(kid, d, lo, hi)
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
def edge3(kid, d, p, lo, hi):
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
        if c < -EPS or (c <= EPS and nn > 0.0 and j < k):
            return 0.0, 0.0, 0.0, 2
        return 0.0, 0.0, 0.0, 1
    return ax / na, ay / na, -c / na, 0


@njit(cache=True, inline="always")
def plane_basis(n0, n1, n2):
    """Orthonormal (e1, e2) in the plane of unit normal n, with e1 x e2 = n (so that a
    polygon whose normal is n runs counter-clockwise in (e1, e2))."""
    if abs(n0) < 0.9:
        c0, c1, c2 = 0.0, n2, -n1
    else:
        c0, c1, c2 = -n2, 0.0, n0
    cn = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
    e1 = (c0 / cn, c1 / cn, c2 / cn)
    e2 = (n1 * e1[2] - n2 * e1[1], n2 * e1[0] - n0 * e1[2], n0 * e1[1] - n1 * e1[0])
    return e1, e2


@njit(cache=True)
def face3(kid, x0, x1, x2, normals, offsets, h, k, d):
    """(d int f_s dA, int W dA, in-plane int W y dA (3 components)) of face k, h = 1 units.

    The face polygon P (possibly unbounded) is cut by the other planes within 2h. Sum over
    its edges of the signed triangles (foot, edge) clipped to the disc of radius
    R = sqrt(4 - d^2); the rest of P inside the disc is a polar sector of radius R with
    angle 2 pi [foot in P] - sum of the edges' in-disc angles (winding number), whose
    integrand is the constant Phi(2h) = Psi(2) - Psi(d).
    """
    nk = normals.shape[0]
    e1, e2 = plane_basis(normals[k, 0], normals[k, 1], normals[k, 2])
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
            if cj > EPS:
                lo = max(lo, rhs / cj)
            elif cj < -EPS:
                hi = min(hi, rhs / cj)
            elif rhs > EPS or (rhs >= -EPS and aa > 0.0 and j < i):
                lo = np.inf  # parallel line in front, or duplicate edge
        if hi <= lo:
            continue
        p = -b
        p = max(p, EPS) if p >= 0.0 else min(p, -EPS)  # foot on the line counts as inside
        es, ew, eq, ephi = edge3(kid, d, p, lo, hi)
        s += es
        w += ew
        phi += ephi
        # in-plane moment: outward edge normal -a times int Q dt (Q = 0 beyond the support)
        m0 -= eq * (ax * e1[0] + ay * e2[0])
        m1 -= eq * (ax * e1[1] + ay * e2[1])
        m2 -= eq * (ax * e1[2] + ay * e2[2])
    s, w = sector(kid, d, inside, phi, s, w)
    return s, w, m0, m1, m2


@njit(cache=True, inline="always")
def sector(kid, d, inside, phi, s, w):
    """(s, w) plus the polar sector of a face polygon inside the support disc: angle
    2 pi [foot in the polygon] - phi (phi the edges' in-disc angles), integrand the
    constant Phi(2h) = Psi(2) - Psi(d), and the -Psi(d) phi terms of its edges."""
    arc = 2.0 * math.pi * inside - phi
    dps_d = lval(PS, kid, 1, d, 1)
    psw_d = lval(PW, kid, 1, d, 0)
    s += (d * PS2_[kid] - dps_d) * arc - dps_d * phi
    w += (PW2[kid, 1] - psw_d) * arc - psw_d * phi
    return s, w
