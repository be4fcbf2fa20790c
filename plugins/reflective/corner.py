"""One contact with several walls at once: corners, edges and wedges.

The paper treats one wall per contact (section 2.2, Fig. 7). In a wedge the particle then
bounces between the two walls, ever closer to the apex: with CR = 0 each reflection
projects it onto one wall and the projections converge like cos(angle)^(2k) (about 800
reflections per step in a 7-degree wedge). When the sequence comes back to a contact
point that touches two or more walls, the particle is in the corner and that contact is
resolved as one: with the walls' tangent half-spaces n_k . X >= c_k (k touching at the
contact), the end point B goes to its projection P onto their intersection (the nearest
admissible point: the polyhedral generalisation of Eq. 1's r - d), then to
P + CR (P - B) when that is admissible too, else P; the velocity likewise goes to the
projection w of v onto the cone n_k . v >= 0 and then w + CR (w - v) (Eq. 2's
-CR u for one wall), else w. For a single wall both reduce to the paper's rules.

The projections are small quadratic programmes (at most MAX_ACTIVE constraints, dim <= 3),
solved exactly by enumerating the active sets of at most dim constraints: the nearest
feasible candidate whose multipliers are non-negative is the projection (KKT).
"""

from __future__ import annotations

import numpy as np
from numba import njit

#: constraints kept for one corner contact (more faces meeting at a mesh vertex are rare;
#: the first MAX_ACTIVE found are used and the loop treats the rest as later contacts)
MAX_ACTIVE = 8


@njit(cache=True, inline="always")
def _dot(a, b):
    """a . b for vectors of length dim (numba's @ needs SciPy's BLAS)."""
    s = 0.0
    for j in range(a.shape[0]):
        s += a[j] * b[j]
    return s


@njit(cache=True)
def project(nrm, c, m, x, tol):
    """Nearest point to x (dim,) with nrm[k] . y >= c[k] for k < m (in place into x);
    False when the constraints admit no such point (x is left unchanged)."""
    dim = x.shape[0]
    ok = True
    for k in range(m):
        if _dot(nrm[k], x) < c[k] - tol:
            ok = False
    if ok:
        return True
    best = np.inf
    out = x.copy()
    g = np.zeros((3, 3))
    rhs = np.zeros(3)
    idx = np.zeros(3, np.int64)
    y = np.zeros(dim)
    for size in range(1, min(dim, m) + 1):
        # every subset of `size` constraints, in lexicographic order
        for j in range(size):
            idx[j] = j
        while True:
            for a in range(size):
                rhs[a] = c[idx[a]] - _dot(nrm[idx[a]], x)
                for b in range(size):
                    g[a, b] = _dot(nrm[idx[a]], nrm[idx[b]])
            lam = _solve(g, rhs, size)
            if lam.shape[0] == size and lam.min() >= -1e-12:
                for j in range(dim):
                    y[j] = x[j]
                    for a in range(size):
                        y[j] += lam[a] * nrm[idx[a], j]
                feasible = True
                for k in range(m):
                    if _dot(nrm[k], y) < c[k] - tol:
                        feasible = False
                d = 0.0
                for j in range(dim):
                    d += (y[j] - x[j]) ** 2
                if feasible and d < best:
                    best = d
                    out[:] = y
            # next subset
            j = size - 1
            while j >= 0 and idx[j] == m - size + j:
                j -= 1
            if j < 0:
                break
            idx[j] += 1
            for k in range(j + 1, size):
                idx[k] = idx[k - 1] + 1
    if best == np.inf:
        return False
    x[:] = out
    return True


@njit(cache=True)
def _solve(g, rhs, size):
    """Solution of the size x size system g lam = rhs (Gaussian elimination with partial
    pivoting); an empty array when it is singular (linearly dependent normals)."""
    a = g[:size, :size].copy()
    b = rhs[:size].copy()
    for col in range(size):
        p = col
        for rr in range(col + 1, size):
            if abs(a[rr, col]) > abs(a[p, col]):
                p = rr
        if abs(a[p, col]) < 1e-10:
            return np.zeros(0)
        if p != col:
            for k in range(size):
                a[col, k], a[p, k] = a[p, k], a[col, k]
            b[col], b[p] = b[p], b[col]
        for rr in range(col + 1, size):
            f = a[rr, col] / a[col, col]
            for k in range(col, size):
                a[rr, k] -= f * a[col, k]
            b[rr] -= f * b[col]
    lam = np.zeros(size)
    for rr in range(size - 1, -1, -1):
        s = b[rr]
        for k in range(rr + 1, size):
            s -= a[rr, k] * lam[k]
        lam[rr] = s / a[rr, rr]
    return lam


@njit(cache=True)
def respond(nrm, c, m, pos, vel, i, cr, tol):
    """The joint response for particle i (pos, vel in place) to the m walls nrm . X >= c;
    False when the half-spaces have no common point (then nothing is changed)."""
    dim = pos.shape[1]
    b = pos[i, :dim].copy()
    p = b.copy()
    if not project(nrm, c, m, p, tol):
        return False
    q = p + cr * (p - b)
    ok = True
    for k in range(m):
        if _dot(nrm[k], q) < c[k] - tol:
            ok = False
    pos[i, :dim] = q if ok else p
    v = vel[i, :dim].copy()
    w = v.copy()
    zero = np.zeros(m)
    vtol = 1e-12 * np.sqrt(_dot(v, v))
    if project(nrm, zero, m, w, vtol):
        u = w + cr * (w - v)
        ok = True
        for k in range(m):
            if _dot(nrm[k], u) < -vtol:
                ok = False
        vel[i, :dim] = u if ok else w
    return True
