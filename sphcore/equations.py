"""Weakly compressible SPH equations, as numba kernels over struct-of-arrays.

Destination particles are the first ``n_dest`` entries of the source arrays (the fluid);
further source entries (ghosts) act only as neighbours. With x_ij = x_i - x_j,
v_ij = v_i - v_j, grad_i W_ij = F_ij x_ij (see :mod:`sphcore.kernels`):

- continuity (Monaghan 1992, Eq. 2.9 form): drho_i/dt = sum_j m_j v_ij . grad_i W_ij
- density diffusion (Molteni & Colagrossi 2009):
  + delta h c0 sum_j 2 psi_ij (m_j / rho_j) (x_ij . grad_i W_ij) / (|x_ij|^2 + eta^2),
  psi_ij = rho_i - rho_j, or with ``diffusion_hydrostatic`` its departure from the
  hydrostatic stratification (Fourtakas et al. 2019): psi_ij = rho_i - rho_j - (rho0/c0^2) g . x_ij
  (the linearised hydrostatic density difference rho^H_i - rho^H_j), so water at rest is not diffused
- momentum (Monaghan 1994): dv_i/dt = g - sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) grad_i W_ij
- artificial viscosity (Monaghan 1992): for v_ij . x_ij < 0,
  mu_ij = h v_ij . x_ij / (|x_ij|^2 + eta^2), Pi_ij = (-alpha c0 mu_ij + beta mu_ij^2) / rho_bar
- laminar viscosity (Morris et al. 1997, Lo & Shao 2002 form):
  + sum_j m_j 4 nu / (rho_i + rho_j) (x_ij . grad_i W_ij) / (|x_ij|^2 + eta^2) v_ij
- boundary-integral walls (:class:`WallTerms`; Kulasegaram et al. 2004, Ferrand et al. 2013):
  where a plugin supplies the wall share s_i of the kernel support, its gradient G_i, the
  hydrostatic moment H_i = T_i g and the near walls' normals, the missing support is filled
  with the mirror image of the fluid, its pressure extrapolated hydrostatically:
      drho_i/dt = sum_j ... + 2 rho_i v_i . G_w
      dv_i/dt   = g - sum_j ... - 2 (p_i/rho_i) G_w - ((rho_i - rho_ref)/rho_i) A_w g
  with G_w the wall gradient the plugin supplies (the exact G corrected for the lattice
  error of the truncated sum) and A_w g the discrete complement of the particle's own first
  moment along the walls' normals, lambda (T g + s g) along them; see :func:`_complete_at_wall`.
- Tait equation of state: :mod:`sphcore.eos`.

eta^2 = 0.01 h^2 keeps the denominators finite. Arguments are structured: ``src``
(:class:`Fields`), ``grid`` (:class:`sphcore.neighbours.Grid`), ``prm``
(:class:`sphcore.params.Params`), ``wall`` (:class:`WallTerms`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit, prange

from .kernels import kernel_f, kernel_w
from .neighbours import cell_of, cell_range


class Fields(NamedTuple):
    """Source particles of one force evaluation: the fluid first, then plugin sources.
    pos, vel (n, dim) m and m/s; rho (kg/m^3), p (Pa, the pressure the momentum equation
    uses), m (kg): (n,)."""

    pos: np.ndarray
    vel: np.ndarray
    rho: np.ndarray
    p: np.ndarray
    m: np.ndarray


class WallTerms(NamedTuple):
    """Per-particle boundary-integral terms of the walls (zero far from walls).

    ``share`` (n,): the wall's share s of the particle's kernel support, int_outside W;
    ``grad`` (n, dim): G = grad s (1/m), pointing towards the wall;
    ``hydro`` (n, dim): H = oint_wall W n_out g . (x_s - x) dS (m/s^2), the hydrostatic
    moment of the wall pressure; ``normals`` (n, dim, dim): the orthogonal projector onto
    the normals of the walls within the particle's support (n n^T near one plane, the
    identity in a corner), the directions in which its missing support is wall rather than
    free surface; ``fill`` (n,): the neighbour sum sum_j V_j W_ij (self excluded) that a
    particle of the initial lattice has at that place, against which the core measures how
    full the particle's own neighbourhood is (0: not supplied, no scaling); ``active``:
    false when no plugin supplies them (skipped). Plugins fill them in the
    ``sph_wall_terms`` hook; share, grad, hydro and fill of several plugins add up,
    ``normals`` is replaced by the projector onto the span of both.
    """

    share: np.ndarray
    grad: np.ndarray
    hydro: np.ndarray
    normals: np.ndarray
    fill: np.ndarray
    active: bool


@njit(cache=True, parallel=True)
def sph_rates(n_dest, src, grid, prm, L, wall, acc, drho):
    """Accelerations acc (n_dest, dim) in m/s^2 and density rates drho (n_dest,) in kg/m^3/s.

    Terms whose coefficient is zero are skipped, so a case without viscosity or density
    diffusion computes none. ``prm.modified_pressure``: gravity acts as g (1 - rho0/rho_i)
    (Batchelor 1967). ``prm.kernel_gradient``: the kernel gradient is corrected with the
    symmetrised Bonet & Lok matrix (L_i + L_j)/2 (antisymmetric in i, j, so momentum is
    still conserved); sources beyond ``L.shape[0]`` use the identity. ``wall``: see the
    module docstring.
    """
    pos, vel, rho, p, m = src
    dim = pos.shape[1]
    h, c0 = prm.h, prm.c0
    alpha, beta, nu, delta, eta2 = prm.alpha, prm.beta, prm.nu, prm.delta, prm.eta2
    gravity = prm.gravity
    r2max = prm.support * prm.support
    do_av = alpha > 0.0 or beta > 0.0
    do_lam = nu > 0.0
    do_diff = delta > 0.0
    # linearised hydrostatic density gradient rho0 / c0^2 (s^2/m^2 * kg/m^3)
    diff_h = prm.rho0 / (c0 * c0) if (do_diff and prm.diffusion_hydrostatic) else 0.0
    dcoef = 2.0 * delta * h * c0  # one division per pair in the diffusion term
    use_L = prm.kernel_gradient
    n_L = L.shape[0] if use_L else 0
    walls = wall.active
    for i in prange(n_dest):
        cx, cy, cz = cell_of(grid, pos, i)
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        dr = 0.0
        b0 = 0.0  # b = sum_j V_j grad_i W_ij (x_j - x_i) . g, for the wall completion
        gam = 0.0  # sum_j V_j W_ij, the particle's own neighbour sum (wall completion)
        b1 = 0.0
        b2 = 0.0
        pi_r = p[i] / (rho[i] * rho[i])
        near = walls and wall.share[i] > 0.0  # within the support of a wall: complete the sums
        for q in range(3 ** dim):
            k0, k1 = cell_range(grid, cx, cy, cz, q, dim)
            for k in range(k0, k1):
                j = grid.order[k]
                if j == i:
                    continue
                x0 = pos[i, 0] - pos[j, 0]
                x1 = pos[i, 1] - pos[j, 1]
                x2 = pos[i, 2] - pos[j, 2] if dim == 3 else 0.0
                r2 = x0 * x0 + x1 * x1 + x2 * x2
                if r2 >= r2max:
                    continue
                f = kernel_f(prm.kernel_id, np.sqrt(r2), h, dim)
                g0 = f * x0
                g1 = f * x1
                g2 = f * x2
                if use_L:
                    g0, g1, g2 = _corrected(L, n_L, i, j, g0, g1, g2)
                v0 = vel[i, 0] - vel[j, 0]
                v1 = vel[i, 1] - vel[j, 1]
                v2 = vel[i, 2] - vel[j, 2] if dim == 3 else 0.0
                vx = v0 * x0 + v1 * x1 + v2 * x2
                xg = x0 * g0 + x1 * g1 + x2 * g2  # x_ij . grad_i W_ij (< 0)
                mj = m[j]
                dr += mj * (v0 * g0 + v1 * g1 + v2 * g2)
                if near:
                    gam += mj / rho[j] * kernel_w(prm.kernel_id, np.sqrt(r2), h, dim)
                    vr = -mj / rho[j] * (x0 * gravity[0] + x1 * gravity[1] + x2 * gravity[2])
                    b0 += vr * g0
                    b1 += vr * g1
                    b2 += vr * g2
                if do_diff:
                    psi = rho[i] - rho[j]
                    if diff_h != 0.0:
                        psi -= diff_h * (gravity[0] * x0 + gravity[1] * x1 + gravity[2] * x2)
                    dr += dcoef * psi * mj * xg / (rho[j] * (r2 + eta2))
                s = pi_r + p[j] / (rho[j] * rho[j])
                if do_av and vx < 0.0:
                    mu = h * vx / (r2 + eta2)
                    s += (-alpha * c0 * mu + beta * mu * mu) / (0.5 * (rho[i] + rho[j]))
                a0 -= mj * s * g0
                a1 -= mj * s * g1
                a2 -= mj * s * g2
                if do_lam:
                    lam = mj * 4.0 * nu / (rho[i] + rho[j]) * xg / (r2 + eta2)
                    a0 += lam * v0
                    a1 += lam * v1
                    a2 += lam * v2
        if near:
            a0, a1, a2, dr = _complete_at_wall(wall, i, dim, vel, rho[i], p[i], prm.rho_ref, prm.moment_norm, gravity,
                                               a0, a1, a2, dr, b0, b1, b2, gam)
        gscale = 1.0 - prm.rho0 / rho[i] if prm.modified_pressure else 1.0
        acc[i, 0] = gscale * gravity[0] + a0
        acc[i, 1] = gscale * gravity[1] + a1
        if dim == 3:
            acc[i, 2] = gscale * gravity[2] + a2
        drho[i] = dr


@njit(cache=True, inline="always")
def _complete_at_wall(wall, i, dim, vel, rho_i, p_i, rho_ref, lam, gravity, a0, a1, a2, dr, b0, b1, b2, gam):
    """Add the wall's boundary integrals to particle i's sums (module docstring).

    The wall stands for the missing part of the support, filled with the mirror image of
    the fluid (velocity mirrored, pressure extrapolated hydrostatically): continuity gains
    2 rho_i v_i . G_w, momentum 2 (p_i/rho_i) G_w + ((rho_i - rho_ref)/rho_i) A_w g, with
    A_w g = T g + s g the first moment of the outside region. The same G_w in both terms
    makes the wall do no net work (the power of the wall force equals minus the rate of
    the Tait internal energy it stores), like mirror ghosts, with no ghost particle.

    G_w is ``wall.grad`` as the plugins supply it: a function of the particle's position
    alone, so that the wall pushes harder the closer a particle comes (the wall's
    stiffness). The ``wall_integral`` plugin gives the exact G minus the lattice error of
    the truncated sum on the initial lattice (:mod:`sphcore_plugins.wall_integral.lattice`),
    which makes a uniform pressure exert no force on that lattice, corners included.
    (The discrete complement -Q D of the particle's own sum, used before, balances any
    arrangement but does not depend on the wall distance at all: particles then rested on
    the reflective contact, not on the wall pressure.)

    The whole completion is scaled by phi = min(1, gam / wall.fill), the particle's own
    neighbour sum against the initial lattice's at that place: the mirror image of a full
    neighbourhood is the lattice the wall terms stand for, the mirror image of a splash
    particle or of a thin film is (nearly) nothing. Without it a lone particle near a wall
    would be pushed and decompressed as if the fluid surrounded it (measured: a splash
    particle of the Lobovsky impact fell below 0.5 rho0). phi = 1 on the initial lattice.
    """
    ref = wall.fill[i]
    phi = min(1.0, gam / ref) if ref > 0.0 else 1.0
    w0 = phi * wall.grad[i, 0]
    w1 = phi * wall.grad[i, 1]
    w2 = phi * wall.grad[i, 2] if dim == 3 else 0.0
    q = wall.normals
    # first moment: along the wall normals the discrete complement (lam I - B) g of the
    # particle's own sum b = B g, so that the hydrostatic pressure of the particles is in
    # balance there whatever their arrangement; along the walls (a side wall's vertical,
    # where the particle's missing support may be free surface) lam times the exact
    # A_w g = T g + s g. lam (Params.moment_norm) is what the interior's discrete sum gives
    # on the initial lattice (B = lam I): a particle next to a wall is then held up as an
    # interior one is (lam rho g), and no column along a wall slides against its neighbours
    s = wall.share[i]
    en0, en1, en2 = _project(q, i, dim, lam * gravity[0] - b0, lam * gravity[1] - b1, lam * gravity[2] - b2)
    t0 = lam * (wall.hydro[i, 0] + s * gravity[0])
    t1 = lam * (wall.hydro[i, 1] + s * gravity[1])
    t2 = lam * (wall.hydro[i, 2] + s * gravity[2]) if dim == 3 else 0.0
    tn0, tn1, tn2 = _project(q, i, dim, t0, t1, t2)
    h0 = phi * en0 + t0 - tn0
    h1 = phi * en1 + t1 - tn1
    h2 = phi * en2 + t2 - tn2
    cp = 2.0 * p_i / rho_i
    ch = (rho_i - rho_ref) / rho_i
    a0 -= cp * w0 + ch * h0
    a1 -= cp * w1 + ch * h1
    a2 -= cp * w2 + ch * h2
    vw = vel[i, 0] * w0 + vel[i, 1] * w1
    if dim == 3:
        vw += vel[i, 2] * w2
    dr += 2.0 * rho_i * vw
    return a0, a1, a2, dr


@njit(cache=True, inline="always")
def _project(q, i, dim, v0, v1, v2):
    """q[i] applied to (v0, v1, v2)."""
    if dim == 2:
        return q[i, 0, 0] * v0 + q[i, 0, 1] * v1, q[i, 1, 0] * v0 + q[i, 1, 1] * v1, 0.0
    return (q[i, 0, 0] * v0 + q[i, 0, 1] * v1 + q[i, 0, 2] * v2,
            q[i, 1, 0] * v0 + q[i, 1, 1] * v1 + q[i, 1, 2] * v2,
            q[i, 2, 0] * v0 + q[i, 2, 1] * v1 + q[i, 2, 2] * v2)


@njit(cache=True)
def _corrected(L, n_L, i, j, g0, g1, g2):
    """(L_i + L_j)/2 applied to the gradient; L is the identity for rows >= n_L (ghosts)."""
    a0, a1, a2 = _apply(L, n_L, i, g0, g1, g2)
    b0, b1, b2 = _apply(L, n_L, j, g0, g1, g2)
    return 0.5 * (a0 + b0), 0.5 * (a1 + b1), 0.5 * (a2 + b2)


@njit(cache=True)
def _apply(L, n_L, row, g0, g1, g2):
    # separate calls for i and j: the parfor index and j have different integer types,
    # and a conditional expression over both would unify them to float64
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
        cx, cy, cz = cell_of(grid, pos, i)
        if want_L:
            for a in range(3):
                for b in range(3):
                    L[i, a, b] = 0.0  # accumulates M_i, inverted in place below
        num = 0.0
        den = 0.0
        for q in range(3 ** dim):
            k0, k1 = cell_range(grid, cx, cy, cz, q, dim)
            for k in range(k0, k1):
                j = grid.order[k]
                x0 = pos[i, 0] - pos[j, 0]
                x1 = pos[i, 1] - pos[j, 1]
                x2 = pos[i, 2] - pos[j, 2] if dim == 3 else 0.0
                r2 = x0 * x0 + x1 * x1 + x2 * x2
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


@njit(cache=True)
def uniform_acceleration(gravity, acc):
    """acc[i] = gravity for every particle (the only force when SPH is off)."""
    dim = acc.shape[1]
    for i in range(acc.shape[0]):
        for d in range(dim):
            acc[i, d] = gravity[d]
