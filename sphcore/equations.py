"""Weakly compressible SPH equations, as numba kernels over struct-of-arrays.

Destination particles are the first ``n_dest`` entries of the source arrays (the fluid);
further source entries (ghosts) act only as neighbours. With x_ij = x_i - x_j,
v_ij = v_i - v_j, grad_i W_ij = F_ij x_ij (see :mod:`sphcore.kernels`):

- continuity (Monaghan 1992, Eq. 2.9 form): drho_i/dt = sum_j m_j v_ij . grad_i W_ij
- density diffusion (Molteni & Colagrossi 2009):
  + delta h c0 sum_j 2 (rho_i - rho_j) (m_j / rho_j) (x_ij . grad_i W_ij) / (|x_ij|^2 + eta^2)
- momentum (Monaghan 1994): dv_i/dt = g - sum_j m_j (p_i/rho_i^2 + p_j/rho_j^2 + Pi_ij) grad_i W_ij
- artificial viscosity (Monaghan 1992): for v_ij . x_ij < 0,
  mu_ij = h v_ij . x_ij / (|x_ij|^2 + eta^2), Pi_ij = (-alpha c0 mu_ij + beta mu_ij^2) / rho_bar
- laminar viscosity (Morris et al. 1997, Lo & Shao 2002 form):
  + sum_j m_j 4 nu / (rho_i + rho_j) (x_ij . grad_i W_ij) / (|x_ij|^2 + eta^2) v_ij
- Tait equation of state (Monaghan 1994; Batchelor 1967): p = B ((rho/rho0)^gamma - 1) + p_b,
  B = c0^2 rho0 / gamma

eta^2 = 0.01 h^2 keeps the denominators finite.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from .kernels import kernel_f
from .neighbours import cell_coords


@njit(cache=True)
def tait_pressure(rho, rho0, c0, gamma, p_background, p):
    """Fill p (Pa) from rho (kg/m^3) with the Tait equation of state."""
    b = c0 * c0 * rho0 / gamma
    for i in range(rho.shape[0]):  # element-wise: serial (see integrators._drift)
        p[i] = b * ((rho[i] / rho0) ** gamma - 1.0) + p_background


@njit(cache=True, parallel=True)
def sph_rates(n_dest, pos, vel, rho, p, m, order, cell_start, lo, cell_size, ncell,
              kernel_id, h, c0, alpha, beta, nu, delta, gravity, acc, drho):
    """Accelerations acc (n_dest, dim) in m/s^2 and density rates drho (n_dest,) in kg/m^3/s.

    Terms whose coefficient is zero are skipped, so a case without viscosity or density
    diffusion computes none.
    """
    dim = pos.shape[1]
    eta2 = 0.01 * h * h
    r2max = (2.0 * h) ** 2
    do_av = alpha > 0.0 or beta > 0.0
    do_lam = nu > 0.0
    do_diff = delta > 0.0
    zr = 1 if dim == 3 else 0
    for i in prange(n_dest):
        cx, cy, cz = cell_coords(pos, i, lo, cell_size, ncell)
        a0 = 0.0
        a1 = 0.0
        a2 = 0.0
        dr = 0.0
        pi_r = p[i] / (rho[i] * rho[i])
        for dz in range(-zr, zr + 1):
            z = cz + dz
            if z < 0 or z >= ncell[2]:
                continue
            for dy in range(-1, 2):
                y = cy + dy
                if y < 0 or y >= ncell[1]:
                    continue
                for dx in range(-1, 2):
                    x = cx + dx
                    if x < 0 or x >= ncell[0]:
                        continue
                    c = x + ncell[0] * (y + ncell[1] * z)
                    for k in range(cell_start[c], cell_start[c + 1]):
                        j = order[k]
                        if j == i:
                            continue
                        x0 = pos[i, 0] - pos[j, 0]
                        x1 = pos[i, 1] - pos[j, 1]
                        x2 = pos[i, 2] - pos[j, 2] if dim == 3 else 0.0
                        r2 = x0 * x0 + x1 * x1 + x2 * x2
                        if r2 >= r2max:
                            continue
                        f = kernel_f(kernel_id, np.sqrt(r2), h, dim)
                        v0 = vel[i, 0] - vel[j, 0]
                        v1 = vel[i, 1] - vel[j, 1]
                        v2 = vel[i, 2] - vel[j, 2] if dim == 3 else 0.0
                        vx = v0 * x0 + v1 * x1 + v2 * x2
                        mj = m[j]
                        dr += mj * vx * f
                        if do_diff:
                            dr += delta * h * c0 * 2.0 * (rho[i] - rho[j]) * mj / rho[j] * f * r2 / (r2 + eta2)
                        s = pi_r + p[j] / (rho[j] * rho[j])
                        if do_av and vx < 0.0:
                            mu = h * vx / (r2 + eta2)
                            s += (-alpha * c0 * mu + beta * mu * mu) / (0.5 * (rho[i] + rho[j]))
                        g = -mj * s * f
                        a0 += g * x0
                        a1 += g * x1
                        a2 += g * x2
                        if do_lam:
                            lam = mj * 4.0 * nu / (rho[i] + rho[j]) * f * r2 / (r2 + eta2)
                            a0 += lam * v0
                            a1 += lam * v1
                            a2 += lam * v2
        acc[i, 0] = gravity[0] + a0
        acc[i, 1] = gravity[1] + a1
        if dim == 3:
            acc[i, 2] = gravity[2] + a2
        drho[i] = dr


@njit(cache=True)
def uniform_acceleration(gravity, acc):
    """acc[i] = gravity for every particle (the only force when SPH is off)."""
    dim = acc.shape[1]
    for i in range(acc.shape[0]):
        for d in range(dim):
            acc[i, d] = gravity[d]
