"""One contact with several walls at once: corners, edges and wedges.

The paper treats one wall per contact (section 2.2, Fig. 7). In a wedge the particle then
bounces between the two walls, ever closer to the apex: with CR = 0 each reflection
projects it onto one wall and the projections converge like cos(angle)^(2k) (about 800
reflections per step in a 7-degree wedge). When the sequence meets a wall a second time in
one step at a contact point that touches two or more walls, the particle is caught in the
corner and that contact is resolved as one: with the walls' tangent half-spaces
n_k . X >= c_k (k touching at the contact), the end point B goes to its projection P onto
their intersection (the nearest admissible point: the polyhedral generalisation of Eq. 1's
r - d), then to P + CR (P - B) when that is admissible too, else P; the velocity likewise
goes to the projection w of v onto the cone n_k . v >= 0 and then w + CR (w - v) (Eq. 2's
-CR u for one wall); when that leaves the cone (an acute corner) and CR > 0, Eq. 2 is
applied across the wall the velocity enters most until it enters none (at most MAX_BOUNCES
times, velocity only: an isometry for CR = 1), else w. For a single wall both reduce to
Eq. 1 and to Eq. 2 in its end-point form; the contact form (the work of the step's
acceleration between contact and end point, ``velocity = "contact"``) is not applied to a
joint contact. A corner passed with one reflection per wall (a box corner: x, y, z once
each) never comes here: the paper's sequence is kept, bit for bit; nor does CR = 1, whose
sequence is the exact billiard and ends in any corner
(:func:`sphcore_plugins.reflective.collision._reflect_one`).

The projections are small quadratic programmes (at most MAX_ACTIVE constraints, dim <= 3),
solved exactly by enumerating the active sets of at most dim constraints: the nearest
feasible candidate whose multipliers are non-negative is the projection (KKT).
"""

from __future__ import annotations

from typing import NamedTuple

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


#: scratch sizes: float64 and int64 words one corner contact uses (:func:`scratch`)
NFLOAT = 96
NINT = 24


#: rows of scratch: the kernel splits the particles into this many blocks, one row each
#: (a block runs on one thread at a time; numba.get_thread_id() would be simpler but its
#: compiled code does not survive numba's disk cache: a cached kernel crashed)
ROWS = 64


class Scratch(NamedTuple):
    """Work arrays of corner contacts (no units: the functions here lay out their words).

    As :func:`scratch` allocates them: ``floats`` (ROWS, NFLOAT) float64 and ``ints``
    (ROWS, NINT) int64, one row per block of particles; as one contact uses them: one row
    of each, ``floats`` (NFLOAT,) and ``ints`` (NINT,).
    """

    floats: np.ndarray
    ints: np.ndarray


def scratch():
    """The :class:`Scratch` of the reflective kernel, (ROWS, NFLOAT) and (ROWS, NINT) rows,
    allocated once by the caller so that the kernel allocates nothing."""
    return Scratch(np.zeros((ROWS, NFLOAT)), np.zeros((ROWS, NINT), np.int64))


@njit(cache=True)
def project(nrm, c, m, x, tol, ws, wi):
    """Nearest point to x (dim,) with nrm[k] . y >= c[k] for k < m (in place into x);
    False when the constraints admit no such point (x is left unchanged). ws, wi: scratch
    (``ws[55:]``, ``wi[0:3]`` are used)."""
    dim = x.shape[0]
    ok = True
    for k in range(m):
        if _dot(nrm[k], x) < c[k] - tol:
            ok = False
    if ok:
        return True
    best = np.inf
    out = ws[55:55 + dim]
    g = ws[58:67].reshape((3, 3))
    rhs = ws[67:70]
    y = ws[70:70 + dim]
    idx = wi[0:3]
    for size in range(1, min(dim, m) + 1):
        # every subset of `size` constraints, in lexicographic order
        for j in range(size):
            idx[j] = j
        while True:
            for a in range(size):
                rhs[a] = c[idx[a]] - _dot(nrm[idx[a]], x)
                for b in range(size):
                    g[a, b] = _dot(nrm[idx[a]], nrm[idx[b]])
            lam = ws[85:85 + size]
            if _solve(g, rhs, size, ws[73:82].reshape((3, 3)), ws[82:85], lam):
                nonneg = True
                for a in range(size):
                    if lam[a] < -1e-12:
                        nonneg = False
                if nonneg:
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
def _solve(g, rhs, size, a, b, lam):
    """Solve the size x size system g lam = rhs into ``lam`` (Gaussian elimination with
    partial pivoting; a, b scratch); False when it is singular (dependent normals)."""
    for r_ in range(size):
        b[r_] = rhs[r_]
        for k in range(size):
            a[r_, k] = g[r_, k]
    for col in range(size):
        p = col
        for rr in range(col + 1, size):
            if abs(a[rr, col]) > abs(a[p, col]):
                p = rr
        if abs(a[p, col]) < 1e-10:
            return False
        if p != col:
            for k in range(size):
                a[col, k], a[p, k] = a[p, k], a[col, k]
            b[col], b[p] = b[p], b[col]
        for rr in range(col + 1, size):
            f = a[rr, col] / a[col, col]
            for k in range(col, size):
                a[rr, k] -= f * a[col, k]
            b[rr] -= f * b[col]
    for rr in range(size - 1, -1, -1):
        s = b[rr]
        for k in range(rr + 1, size):
            s -= a[rr, k] * lam[k]
        lam[rr] = s / a[rr, rr]
    return True


@njit(cache=True)
def respond(nrm, c, m, pos, vel, i, cr, tol, ws, wi):
    """The joint response for particle i (pos, vel in place) to the m walls nrm . X >= c;
    False when the half-spaces have no common point (then nothing is changed).
    ws, wi: scratch (``ws[32:]`` and ``wi[0:3]`` are used)."""
    dim = pos.shape[1]
    b = ws[32:32 + dim]
    p = ws[35:35 + dim]
    q = ws[38:38 + dim]
    for j in range(dim):
        b[j] = pos[i, j]
        p[j] = pos[i, j]
    if not project(nrm, c, m, p, tol, ws, wi):
        return False
    ok = True
    for j in range(dim):
        q[j] = p[j] + cr * (p[j] - b[j])
    for k in range(m):
        if _dot(nrm[k], q) < c[k] - tol:
            ok = False
    for j in range(dim):
        pos[i, j] = q[j] if ok else p[j]
    v = ws[41:41 + dim]
    w = ws[44:44 + dim]
    zero = ws[47:55]
    for j in range(dim):
        v[j] = vel[i, j]
        w[j] = vel[i, j]
    zero[:] = 0.0
    vtol = 1e-12 * np.sqrt(_dot(v, v))
    if project(nrm, zero, m, w, vtol, ws, wi):
        for j in range(dim):
            q[j] = w[j] + cr * (w[j] - v[j])
        ok = True
        for k in range(m):
            if _dot(nrm[k], q) < -vtol:
                ok = False
        if not ok and cr > 0.0:
            # w + CR (w - v) leaves the cone (an acute corner): the walls' own sequence,
            # Eq. 2 across the wall the velocity enters most, until none is entered; an
            # isometry for CR = 1, where w alone would stop the normal motion (energy lost)
            for j in range(dim):
                q[j] = v[j]
            ok = _bounce_into_cone(nrm, m, q, cr, vtol)
        for j in range(dim):
            vel[i, j] = q[j] if ok else w[j]
    return True


#: velocity reflections of one joint contact, at most: a wedge of angle a needs about pi / a
#: (36 at 5 degrees)
MAX_BOUNCES = 64


@njit(cache=True)
def _bounce_into_cone(nrm, m, q, cr, vtol):
    """q <- q - (1 + CR) (n_k . q) n_k for the wall k that q enters most (n_k . q < -vtol),
    repeated until it enters none (True) or MAX_BOUNCES times (False)."""
    for _ in range(MAX_BOUNCES):
        worst = -vtol
        kk = -1
        for k in range(m):
            d = _dot(nrm[k], q)
            if d < worst:
                worst = d
                kk = k
        if kk < 0:
            return True
        for j in range(q.shape[0]):
            q[j] -= (1.0 + cr) * worst * nrm[kk, j]
    return False
