"""Closed-form radial primitives of the SPH kernels for the wall integrals.

Both kernels of :mod:`sphcore.physics.kernels` are piecewise polynomials in q = r/h (pieces
[0, 1] and [1, 2]), so every radial integral the boundary-integral walls need is a
piecewise Laurent polynomial in q. They are built here once, at import, as coefficient
arrays that numba reads as constants (no interpolation error: exact to round-off).

All quantities use h = 1 (lengths in units of h); ``share.py`` restores the units.
Arrays are indexed ``[kernel_id, dim - 2, piece, power + OFF]`` with powers -3..9:

* ``WC``   W(q) = sigma w(q)                                    (kernel, 1/h^dim)
* ``SC``   f_s(q) = (K(2) - K(q)) / q^dim,  K(q) = int_0^q W u^(dim-1) du
           (the radial factor of the wall share; its q^-dim term is K(2) on piece 0)
* ``PW``   Psi_W(q) = int_0^q W u du                             (continuous, Psi_W(0) = 0)
* ``PS``   Psi_s(q) = an antiderivative of f_s(q) q (3D only; q^-1 term on piece 0)

and ``KTOT[k, d] = K(2)`` (= 1/(2 pi) in 2D, 1/(4 pi) in 3D), ``PW2 = Psi_W(2)``,
``PS2 = Psi_s(2)``. See Ferrand et al. (2013) for why these integrals
appear (the wall renormalisation factor gamma and its gradient), and Feldman & Bonet (2007) for the
boundary form of the gradient.
"""

from __future__ import annotations

import numpy as np
from numpy.polynomial import polynomial as P

from sphcore.api import CUBIC_SPLINE, WENDLAND_C2

OFF = 3      # column of power q^0
NPOW = 13    # powers -3 .. 9
_KERNELS = (CUBIC_SPLINE, WENDLAND_C2)


def _sigma(kernel_id: int, dim: int) -> float:
    if kernel_id == CUBIC_SPLINE:
        return 10.0 / (7.0 * np.pi) if dim == 2 else 1.0 / np.pi
    return 7.0 / (4.0 * np.pi) if dim == 2 else 21.0 / (16.0 * np.pi)


def w_pieces(kernel_id: int, dim: int) -> list[np.ndarray]:
    """Ascending polynomial coefficients of W(q) (h = 1) on [0, 1] and [1, 2]."""
    s = _sigma(kernel_id, dim)
    if kernel_id == CUBIC_SPLINE:
        p0 = np.array([1.0, 0.0, -1.5, 0.75])
        p1 = 0.25 * P.polypow([2.0, -1.0], 3)
    else:
        p0 = P.polymul(P.polypow([1.0, -0.5], 4), [1.0, 2.0])
        p1 = p0
    return [s * p0, s * p1]


def _cumulative(pieces: list[np.ndarray]) -> list[np.ndarray]:
    """Continuous antiderivative, zero at q = 0, of a two-piece polynomial (ascending)."""
    a0 = P.polyint(pieces[0])
    a1 = P.polyint(pieces[1])
    a1[0] += P.polyval(1.0, a0) - P.polyval(1.0, a1)
    return [a0, a1]


def _laurent_row(poly: np.ndarray, shift: int) -> np.ndarray:
    """Row of powers -3..9 holding ``poly(q) * q**shift``."""
    row = np.zeros(NPOW)
    for j, c in enumerate(poly):
        if c != 0.0:
            k = j + shift
            if not -3 <= k <= 9:
                raise ValueError("power out of table range")
            row[k + OFF] += c
    return row


def _build():
    wc = np.zeros((2, 2, 2, NPOW))
    sc = np.zeros_like(wc)
    pw = np.zeros_like(wc)
    ps = np.zeros_like(wc)
    ktot = np.zeros((2, 2))
    pw2 = np.zeros((2, 2))
    ps2 = np.zeros((2, 2))
    for kid in _KERNELS:
        for dim in (2, 3):
            di = dim - 2
            w = w_pieces(kid, dim)
            kc = _cumulative([P.polymul(p, P.polypow([0.0, 1.0], dim - 1)) for p in w])
            k2 = P.polyval(2.0, kc[1])
            psw = _cumulative([P.polymul(p, [0.0, 1.0]) for p in w])
            ktot[kid, di] = k2
            pw2[kid, di] = P.polyval(2.0, psw[1])
            for pc in range(2):
                wc[kid, di, pc] = _laurent_row(w[pc], 0)
                num = -kc[pc].copy()
                num[0] += k2            # K(2) - K(q), powers 0 and >= dim only
                if np.any(np.abs(num[1:dim]) > 1e-14):
                    raise AssertionError("unexpected low powers in K(2) - K(q)")
                num[1:dim] = 0.0
                sc[kid, di, pc] = _laurent_row(num, -dim)
                pw[kid, di, pc] = _laurent_row(psw[pc], 0)
            if dim == 3:
                # Psi_s = int f_s q dq: the q^-3 term integrates to -c q^-1, the rest to powers >= 2
                rows = []
                for pc in range(2):
                    f = sc[kid, di, pc]
                    row = np.zeros(NPOW)
                    for k in range(-3, 10):
                        c = f[k + OFF]
                        if c != 0.0:
                            e = k + 2
                            if e == 0:
                                raise AssertionError("log term in Psi_s")
                            row[e + OFF] += c / e
                    rows.append(row)
                # continuity at q = 1 (value of a Laurent row at q = 1 is its sum)
                rows[1][OFF] += rows[0].sum() - rows[1].sum()
                ps[kid, di] = rows
                ps2[kid, di] = sum(rows[1][k + OFF] * 2.0**k for k in range(-3, 10))
    return wc, sc, pw, ps, ktot, pw2, ps2


# numba freezes these global arrays into the machine code it caches for faces.py/share.py,
# and only the *using* module's timestamp invalidates that cache: after editing this file,
# delete plugins/wall_integral/__pycache__/*.nbi and *.nbc.
WC, SC, PW, PS, KTOT, PW2, PS2 = _build()


def laurent_eval(row: np.ndarray, q) -> np.ndarray:
    """Evaluate a Laurent row (powers -3..9) at q (numpy, for tests and set-up)."""
    q = np.asarray(q, float)
    return sum(row[k + OFF] * q**k for k in range(-3, 10) if row[k + OFF] != 0.0)
