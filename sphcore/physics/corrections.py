"""Kernel corrections computed from per-particle neighbour sums.

- the Bonet & Lok (1999) gradient correction matrix L_i, applied to a pair symmetrised
  as (L_i + L_j)/2 (:func:`corrected_gradient`, used by :func:`sphcore.physics.equations.sph_rates`);
- the Shepard-filtered density (Chen et al. 1999, CSPH zeroth order).

Both walk the neighbours of each particle (:mod:`sphcore.neighbours.cellgrid`), one particle per
parallel task: a gather, since each sum belongs to one particle.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from sphcore.neighbours.cellgrid import cell_of, cell_range, separation
from sphcore.physics.kernels import kernel_f, kernel_w


@njit(cache=True)
def corrected_gradient(L, n_L, i, j, g0, g1, g2):
    """(L_i + L_j)/2 applied to the gradient; L is the identity for rows >= n_L (ghosts)."""
    a0, a1, a2 = _apply(L, n_L, i, g0, g1, g2)
    b0, b1, b2 = _apply(L, n_L, j, g0, g1, g2)
    return 0.5 * (a0 + b0), 0.5 * (a1 + b1), 0.5 * (a2 + b2)


@njit(cache=True)
def _apply(L, n_L, row, g0, g1, g2):
    if row >= n_L:
        return g0, g1, g2
    return (L[row, 0, 0] * g0 + L[row, 0, 1] * g1 + L[row, 0, 2] * g2,
            L[row, 1, 0] * g0 + L[row, 1, 1] * g1 + L[row, 1, 2] * g2,
            L[row, 2, 0] * g0 + L[row, 2, 1] * g1 + L[row, 2, 2] * g2)


@njit(cache=True, parallel=True)
def neighbour_sums(n_dest, src, grid, prm, want_L, L, want_shepard, shepard):
    """Per-particle kernel sums over the neighbours (self included where it contributes).

    - L (n_dest, 3, 3): the Bonet & Lok (1999) correction matrix
      L_i = [sum_j V_j (x_j - x_i) (x) grad_i W_ij]^-1 (identity where the sum is singular);
    - shepard (n_dest,): the Shepard-filtered density
      rho_i = sum_j m_j W_ij / sum_j V_j W_ij (Chen et al. 1999, CSPH zeroth order).
    """
    pos, rho, m = src.pos, src.rho, src.m
    dim = pos.shape[1]
    h, kernel_id = prm.h, prm.kernel_id
    r2max = prm.support * prm.support
    for i in prange(n_dest):
        c = cell_of(grid, i)
        if want_L:
            for a in range(3):
                for b in range(3):
                    L[i, a, b] = 0.0  # accumulates M_i, inverted in place below
        num = 0.0
        den = 0.0
        for q in range(grid.nbr.shape[1]):
            k0, k1 = cell_range(grid, c, q)
            for k in range(k0, k1):
                j = grid.order[k]
                x0, x1, x2, r2 = separation(pos, i, j, dim)
                if r2 >= r2max:
                    continue
                r = np.sqrt(r2)
                vj = m[j] / rho[j]
                if want_shepard:
                    w = kernel_w(kernel_id, r, h, dim)
                    num += m[j] * w
                    den += vj * w
                if want_L and j != i:
                    # M_ab += V_j (x_j - x_i)_a (grad_i W_ij)_b, grad_i W_ij = f x_ij
                    coef = -vj * kernel_f(kernel_id, r, h, dim)
                    L[i, 0, 0] += coef * x0 * x0
                    L[i, 0, 1] += coef * x0 * x1
                    L[i, 1, 0] += coef * x1 * x0
                    L[i, 1, 1] += coef * x1 * x1
                    if dim == 3:
                        L[i, 0, 2] += coef * x0 * x2
                        L[i, 1, 2] += coef * x1 * x2
                        L[i, 2, 0] += coef * x2 * x0
                        L[i, 2, 1] += coef * x2 * x1
                        L[i, 2, 2] += coef * x2 * x2
        if want_shepard:
            shepard[i] = num / den if den > 0.0 else rho[i]
        if want_L:
            _invert_in_place(L, i, dim)


@njit(cache=True, inline="always")
def _invert_in_place(L, i, dim):
    """L[i] <- inverse of L[i] (2x2 or 3x3 block); identity where it is near singular
    (isolated particles: keep the plain gradient)."""
    m00, m01, m02 = L[i, 0, 0], L[i, 0, 1], L[i, 0, 2]
    m10, m11, m12 = L[i, 1, 0], L[i, 1, 1], L[i, 1, 2]
    m20, m21, m22 = L[i, 2, 0], L[i, 2, 1], L[i, 2, 2]
    for a in range(3):
        for b in range(3):
            L[i, a, b] = 1.0 if a == b else 0.0
    if dim == 2:
        det = m00 * m11 - m01 * m10
        if abs(det) > 1e-3:
            L[i, 0, 0] = m11 / det
            L[i, 0, 1] = -m01 / det
            L[i, 1, 0] = -m10 / det
            L[i, 1, 1] = m00 / det
        return
    c00 = m11 * m22 - m12 * m21
    c01 = m12 * m20 - m10 * m22
    c02 = m10 * m21 - m11 * m20
    det = m00 * c00 + m01 * c01 + m02 * c02
    if abs(det) > 1e-3:
        L[i, 0, 0] = c00 / det
        L[i, 1, 0] = c01 / det
        L[i, 2, 0] = c02 / det
        L[i, 0, 1] = (m02 * m21 - m01 * m22) / det
        L[i, 1, 1] = (m00 * m22 - m02 * m20) / det
        L[i, 2, 1] = (m01 * m20 - m00 * m21) / det
        L[i, 0, 2] = (m01 * m12 - m02 * m11) / det
        L[i, 1, 2] = (m02 * m10 - m00 * m12) / det
        L[i, 2, 2] = (m00 * m11 - m01 * m10) / det
