"""The pair passes of the divergence-free scheme (:mod:`sphcore.physics.incompressible`).

The solves of a step sweep the same pairs a few to a few tens of times, so the pairs are
listed once per step with what every pass reads of them: a full (both-ways) neighbour list
in rows, particle i's partners ``nb[start[i]:end[i]]`` (int32), and each pair's kernel
value ``w`` = W_ij and gradient ``g`` = grad_i W_ij (built by :mod:`sphcore.physics.pairfill`,
held by :class:`sphcore.physics.solvelist.SolveList`). Each pass is a gather over the rows:
particle i sums its own row, in the row's order, and writes only its own entry, so the
passes run in parallel without races and give the same bits for any thread count.

Symbols (module docstring of :mod:`sphcore.physics.incompressible`): m mass (the array, or
one float when all are equal: :func:`one_mass`), rho density,
kappa = p / rho the solves' pressure variable, G the walls' share gradient (1/m), rho0 the
rest density; ``inv_sigma`` = 1 / sigma0 normalises the kernel sum so that the initial
lattice sums to rho0 exactly.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange, types
from numba.extending import overload

from sphcore.jit.parallel import PARALLEL_MIN, on_threads_by_size
from sphcore.physics.kernels import SUPPORT, kernel_f, kernel_w, lattice_nodes

LIST_PARALLEL_MIN = 1000  # particles: the passes run on one thread below (a launch costs more)


def one_mass(m):
    """The mass every particle has (the cases' fluids), or None when they differ. The passes
    take ``m`` as that one float then, else as the array (:func:`mass_of`): with one mass
    they read no partner's mass, and the density rate and the pressure kick took 0.83 and
    0.87 of the time (the 3D dam break's state at 0.12 s, one thread), with the same bits."""
    if m.shape[0] and np.all(m == m[0]):
        return float(m[0])
    return None


def mass_of(m, j):
    """m_j, ``m`` the masses (n,) or the one mass of all (:func:`one_mass`)."""
    return m if isinstance(m, float) else m[j]


@overload(mass_of, inline="always")
def _mass_of(m, j):
    if isinstance(m, types.Float):
        return lambda m, j: m
    return lambda m, j: m[j]


def run_pass(kernel, *args):
    """Call one of this module's passes over the pairs, on one thread below LIST_PARALLEL_MIN
    entries of its first argument (the output: one entry per particle)."""
    on_threads_by_size(args[0].shape[0], LIST_PARALLEL_MIN, kernel, *args)


def particle_pass(kernel, *args):
    """Call one of this module's passes over the particles alone (:func:`residual`,
    :func:`projected_step`), on one thread below ``sphcore.jit.parallel.PARALLEL_MIN``
    particles, where a parallel launch costs more than the work (the 3D dam break's 16,384
    particles on two threads: 57 us a projected step in parallel, 17 us on one)."""
    on_threads_by_size(args[0].shape[0], PARALLEL_MIN, kernel, *args)


def lattice_sum(kernel_id: int, h: float, dx: float, dim: int) -> float:
    """sigma0 = sum_k dx^dim W(|x_k|) over the square (cubic) lattice of spacing dx, self
    included: the kernel sum of an interior particle of the initial lattice (1 in the
    continuum; e.g. 1.0105 for Wendland C2 at h = 1.3 dx in 2D)."""
    _, r = lattice_nodes(h, dx, dim, centre=True)
    return float(sum(kernel_w(kernel_id, ri, h, dim) for ri in r) * dx ** dim)


def lattice_eigenvalue(kernel_id: int, h: float, dx: float, dim: int) -> float:
    """The largest eigenvalue lambda_max of the solves' operator scaled by its diagonal, on
    the initial lattice.

    On the lattice the operator kappa -> D rho has the symbol |T(k)|^2 / rho with
    T(k) = sum_j m_j sin(k . x_ji) grad_i W_ij, and its diagonal m_i sum_j m_j |grad W_ij|^2
    / rho, so lambda(k) = |T|^2 / (m sum_j m_j |grad W|^2), maximised here over a grid of
    wave vectors. A Jacobi step multiplies the mode k by 1 - lambda(k): plain Jacobi
    (Bender & Koschier 2017) diverges where lambda > 2, and on the lattice lambda_max = 2.1
    in 2D at h = dx, 2.6 at h = 1.3 dx and 5.7 at h = 2 dx; 2.6 in 3D at h = dx and 4.2 at
    h = 1.3 dx."""
    x, r = lattice_nodes(h, dx, dim)
    keep = r < SUPPORT * h
    x, r = x[keep], r[keep]
    g = np.array([kernel_f(kernel_id, ri, h, dim) for ri in r])[:, None] * x
    diag = float((g * g).sum())
    waves = np.linspace(0.0, math.pi / dx, 41 if dim == 2 else 21)
    kk = np.stack(np.meshgrid(*([waves] * dim), indexing="ij"), axis=-1).reshape(-1, dim)
    t = np.sin(kk @ x.T) @ g
    return float(((t * t).sum(axis=1)).max()) / diag


@njit(cache=True, parallel=True)
def summed_density(rho, start, end, nb, w, m, w0, inv_sigma, wall_rho):
    """rho_i = (m_i W(0) + sum_j m_j W_ij) / sigma0 + wall_rho_i."""
    for i in prange(rho.shape[0]):
        s = mass_of(m, i) * w0
        for p in range(start[i], end[i]):
            s += mass_of(m, nb[p]) * w[p]
        rho[i] = s * inv_sigma + wall_rho[i]


@njit(cache=True, parallel=True)
def diagonal(alpha, start, end, nb, g, m, rho, grad, rho0, inv_sigma):
    """alpha_i = 1 / D_i, D_i the change of particle i's density rate per unit of its own
    kappa (the Jacobi diagonal; Bender & Koschier 2017, Eq. 9, with the wall terms):
    D_i = [|S_i + 2 rho0 G_i|^2 + sum_j m_i m_j |grad W_ij|^2] / (sigma0 rho_i),
    S_i = sum_j m_j grad_i W_ij; 0 where D_i vanishes (a particle alone).

    Next to a wall the first term is about (rho0 |G_i|)^2 (S_i ~ -rho0 G_i), and the wall's
    push on i changes its neighbours' densities, which the diagonal does not see:
    without more, a mode along the side walls under the free surface grew by 3 % an iteration
    (the still tank at h = 2 dx, before the rate's wall term was made the kick's adjoint).
    2 (rho0 |G_i|)^2 / rho_i is added: the weight stays below the exact diagonal's inverse."""
    dim = g.shape[1]
    for i in prange(alpha.shape[0]):
        s0 = 0.0
        s1 = 0.0
        s2 = 0.0
        sq = 0.0
        for p in range(start[i], end[i]):
            mj = mass_of(m, nb[p])
            g0 = g[p, 0]
            g1 = g[p, 1]
            g2 = g[p, 2] if dim == 3 else 0.0
            s0 += mj * g0
            s1 += mj * g1
            s2 += mj * g2
            sq += mj * (g0 * g0 + g1 * g1 + g2 * g2)
        w0 = rho0 * grad[i, 0]
        w1 = rho0 * grad[i, 1]
        w2 = rho0 * grad[i, 2] if dim == 3 else 0.0
        cross = ((s0 + 2.0 * w0) ** 2 + (s1 + 2.0 * w1) ** 2 + (s2 + 2.0 * w2) ** 2) * inv_sigma
        d = (cross + 2.0 * (w0 * w0 + w1 * w1 + w2 * w2) + mass_of(m, i) * sq * inv_sigma) / rho[i]
        alpha[i] = 1.0 / d if d > 0.0 else 0.0


@njit(cache=True, parallel=True)
def density_rate(rate, start, end, nb, g, m, vel, grad, flux, rho0, inv_sigma):
    """rate_i = D rho_i / Dt = [sum_j m_j (v_i - v_j) . grad_i W_ij + 2 rho0 (v_i - v_w) . G_i] / sigma0
    (the walls' part the mirror image's, :mod:`sphcore.physics.incompressible`),
    the walls' velocity as ``flux`` = sum over the wall groups of v_w . G (empty: walls at rest)."""
    dim = g.shape[1]
    moving = flux.shape[0] > 0
    for i in prange(rate.shape[0]):
        v0 = vel[i, 0]
        v1 = vel[i, 1]
        v2 = vel[i, 2] if dim == 3 else 0.0
        s = 0.0
        for p in range(start[i], end[i]):
            j = nb[p]
            vg = (v0 - vel[j, 0]) * g[p, 0] + (v1 - vel[j, 1]) * g[p, 1]
            if dim == 3:
                vg += (v2 - vel[j, 2]) * g[p, 2]
            s += mass_of(m, j) * vg
        wv = v0 * grad[i, 0] + v1 * grad[i, 1]
        if dim == 3:
            wv += v2 * grad[i, 2]
        if moving:
            wv -= flux[i]
        rate[i] = (s + 2.0 * rho0 * wv) * inv_sigma


@njit(cache=True, parallel=True)
def pressure_kick(vel, start, end, nb, g, m, kr, grad, rho0, dt):
    """v_i -= dt [sum_j m_j (kr_i + kr_j) grad_i W_ij + 2 kr_i rho0 G_i], kr = kappa / rho:
    the pressure acceleration of kappa = p / rho, the wall's part that of the particle's
    mirror image (pressure p_i, density rho0 over the wall's share of the support)."""
    dim = g.shape[1]
    for i in prange(vel.shape[0]):
        ki = kr[i]
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        for p in range(start[i], end[i]):
            j = nb[p]
            c = mass_of(m, j) * (ki + kr[j])
            a0 += c * g[p, 0]
            a1 += c * g[p, 1]
            if dim == 3:
                a2 += c * g[p, 2]
        cw = 2.0 * ki * rho0
        vel[i, 0] -= dt * (a0 + cw * grad[i, 0])
        vel[i, 1] -= dt * (a1 + cw * grad[i, 1])
        if dim == 3:
            vel[i, 2] -= dt * (a2 + cw * grad[i, 2])


@njit(cache=True, parallel=True)
def residual(z, err, base, rate, dt, rho0, kappa, alpha, scale, compression):
    """The error of a solve, e_i = base_i + dt rate_i - rho0 (the density solve, base = rho;
    the divergence solve, base = rho0, e = dt rate), and its Jacobi correction
    z_i = e_i alpha_i * scale; err_i = |e_i| (``compression``: max(e_i, 0)), or 0 for a
    particle at zero pressure that expands (the free surface: the projected step holds its
    kappa at zero), and 0 for a particle alone (alpha = 0: its own pressure cannot change its
    density)."""
    for i in prange(z.shape[0]):
        e = base[i] + dt * rate[i] - rho0
        z[i] = e * alpha[i] * scale
        solved = alpha[i] == 0.0 or (e < 0.0 and kappa[i] + z[i] <= 0.0)
        if solved:
            err[i] = 0.0
        elif compression:
            err[i] = max(e, 0.0)
        else:
            err[i] = abs(e)


@njit(cache=True, parallel=True)
def projected_step(d, z, kappa, c_old, c_new, rho, kr):
    """d_i <- c_old d_i + c_new z_i, the step of a (Chebyshev-accelerated) Jacobi
    iteration, then projected: kappa_i <- max(kappa_i + d_i, 0) and d_i the change made
    (the pressure never pulls); kr_i = d_i / rho_i, the change the next kick applies."""
    for i in prange(d.shape[0]):
        step = c_old * d[i] + c_new * z[i]
        k = kappa[i] + step
        if k < 0.0:
            k = 0.0
        d[i] = k - kappa[i]
        kappa[i] = k
        kr[i] = d[i] / rho[i]


@njit(cache=True, parallel=True)
def kernel_average(out, start, end, nb, w, m, rho, pos, kappa, gravity, w0, vol, q):
    """out_i = kernel average of kappa about its hydrostatic part: with q = kappa - g . x
    (constant in a fluid at rest, kappa = p / rho = |g| depth + const),
    out_i = g . x_i + sum_j V_j q_j W_ij / sum_j V_j W_ij over i's neighbours and itself
    (Shepard, V = m / rho). A Shepard average is exact for a constant, also where the
    support is cut by a wall or the free surface, so a hydrostatic kappa is kept exactly
    there; a linear field would not be. ``vol`` and ``q`` (n,): scratch for V and q, taken
    once per particle rather than once per pair."""
    dim = pos.shape[1]
    for i in prange(out.shape[0]):
        gxi = 0.0
        for d in range(dim):
            gxi += gravity[d] * pos[i, d]
        vol[i] = m[i] / rho[i]
        q[i] = kappa[i] - gxi
    for i in prange(out.shape[0]):
        gxi = 0.0
        for d in range(dim):
            gxi += gravity[d] * pos[i, d]
        vi = vol[i] * w0
        num = vi * q[i]
        den = vi
        for p in range(start[i], end[i]):
            j = nb[p]
            v = vol[j] * w[p]
            num += v * q[j]
            den += v
        out[i] = num / den + gxi
