"""Smoothing kernels W(r, h) in 2D and 3D, support radius 2h.

Each kernel gives W and F = (1/r) dW/dr, so that grad_i W_ij = F * (x_i - x_j) with no
division by r (F stays finite as r -> 0). ``kernel_id`` selects the kernel inside numba
code: one compiled path for every kernel and dimension.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

CUBIC_SPLINE = 0
WENDLAND_C2 = 1
KERNEL_IDS = {"cubic_spline": CUBIC_SPLINE, "wendland_c2": WENDLAND_C2}
SUPPORT = 2.0  # support radius in units of h, both kernels


@njit(cache=True, inline="always")
def _sigma(kernel_id, dim):
    """Normalisation constant (without the 1/h^dim factor)."""
    if kernel_id == CUBIC_SPLINE:  # Monaghan & Lattanzio (1985)
        return 10.0 / (7.0 * math.pi) if dim == 2 else 1.0 / math.pi
    # Wendland C2 (Wendland 1995; Dehnen & Aly 2012 scaling to support 2h)
    return 7.0 / (4.0 * math.pi) if dim == 2 else 21.0 / (16.0 * math.pi)


@njit(cache=True, inline="always")
def kernel_w(kernel_id, r, h, dim):
    """W(r, h) in 1/m^dim."""
    q = r / h
    s = _sigma(kernel_id, dim) / h**dim
    if kernel_id == CUBIC_SPLINE:
        if q < 1.0:
            return s * (1.0 - 1.5 * q * q + 0.75 * q * q * q)
        if q < 2.0:
            return s * 0.25 * (2.0 - q) ** 3
        return 0.0
    if q < 2.0:
        return s * (1.0 - 0.5 * q) ** 4 * (1.0 + 2.0 * q)
    return 0.0


@njit(cache=True, inline="always")
def kernel_f_scale(kernel_id, h, dim):
    """The factor sigma / h^(dim+2) of F, so that F(r) = kernel_f_scale * kernel_f_of_q(q),
    q = r / h: loops over pairs compute it once."""
    return _sigma(kernel_id, dim) / h ** (dim + 2)


@njit(cache=True, inline="always")
def kernel_f_of_q(kernel_id, q):
    """F in units of sigma / h^(dim+2) as a function of q = r / h (no division by h)."""
    if kernel_id == CUBIC_SPLINE:
        if q < 1.0:
            return -3.0 + 2.25 * q
        if q < 2.0:
            return -0.75 * (2.0 - q) ** 2 / q
        return 0.0
    if q < 2.0:
        t = 1.0 - 0.5 * q
        return -5.0 * t * t * t
    return 0.0


@njit(cache=True, inline="always")
def kernel_f(kernel_id, r, h, dim):
    """F = (1/r) dW/dr in 1/m^(dim+2); grad_i W_ij = F * (x_i - x_j)."""
    return kernel_f_scale(kernel_id, h, dim) * kernel_f_of_q(kernel_id, r / h)


def lattice_moment(kernel_id: int, h: float, dx: float, dim: int) -> float:
    """Lattice normalisation lambda of the SPH first moment: -(1/dim) sum_k dx^dim x_k . grad W(x_k).

    The sum runs over the nodes x_k != 0 of the square (cubic) lattice of spacing dx, the
    arrangement particles start in. In the continuum the integral int x (x) grad W dV is
    -I; on the lattice the SPH sum sum_j V_j (x_j - x_i) (x) grad_i W_ij is lambda I (cubic
    symmetry), e.g. 0.974 for Wendland C2 at h = 1.3 dx in 2D and 0.999 at h = 2 dx. An
    interior particle in a hydrostatic field is held up by lambda rho g, so a wall that
    completes the missing support should supply lambda of the continuum moment too
    (the wall_integral plugin's completion, :func:`sphcore_plugins.wall_integral.completion.complete_at_wall`).
    """
    _, r = lattice_nodes(h, dx, dim)
    f = np.array([kernel_f(kernel_id, ri, h, dim) for ri in r])
    return float(-(f * r * r).sum() * dx ** dim / dim)


def lattice_nodes(h: float, dx: float, dim: int, centre: bool = False) -> tuple[np.ndarray, np.ndarray]:
    """(x, r): the nodes x_k of the square (cubic) lattice of spacing dx about a particle,
    out to the first whole dx at or beyond the support 2h, in grid order, and their
    distances; the particle's own node x = 0 only with ``centre``."""
    n = int(math.ceil(SUPPORT * h / dx))
    k = np.arange(-n, n + 1, dtype=np.float64) * dx
    x = np.stack(np.meshgrid(*([k] * dim), indexing="ij"), axis=-1).reshape(-1, dim)
    r = np.sqrt((x * x).sum(axis=1))
    keep = r > 0.0
    if centre:
        return x, r
    return x[keep], r[keep]
