"""Free-surface detection by the divergence of position (Lee et al. 2008):

    div r_i = - sum_j V_j (x_i - x_j) . grad_i W_ij,    V_j = m_j / rho_j,

which equals the dimension (2 or 3) inside the fluid and drops towards half of it at a free
surface, where the kernel support is half empty. A wall truncates the support too; to
tell a wall from a free surface, the sum also runs over the mirror images of the
neighbours across every wall plane the particle is near (the image of a neighbour is never
closer than the neighbour itself, so the same cell scan finds them).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from sphcore.api import cell_of, cell_range, kernel_f, particle_distance


@njit(cache=True, parallel=True)
def position_divergence(n, pos, rho, m, grid, prm, normals, offsets, mirror, out):
    """div r (dimensionless) for the first n particles; wall images included when ``mirror``."""
    dim = pos.shape[1]
    h, kernel_id, support = prm.h, prm.kernel_id, prm.support
    r2max = support * support
    nplanes = normals.shape[0]
    for i in prange(n):
        c = cell_of(grid, i)
        s = 0.0
        for q in range(grid.nbr.shape[1]):
            k0, k1 = cell_range(grid, c, q)
            for k in range(k0, k1):
                j = grid.order[k]
                vj = m[j] / rho[j]
                r2 = 0.0
                for d in range(dim):
                    e = pos[i, d] - pos[j, d]
                    r2 += e * e
                if j != i and r2 < r2max:
                    s -= vj * kernel_f(kernel_id, np.sqrt(r2), h, dim) * r2
                if not mirror:
                    continue
                for p in range(nplanes):
                    dj = particle_distance(normals, offsets, p, pos, j)
                    if dj >= support:
                        continue
                    r2 = 0.0
                    for d in range(dim):
                        e = pos[i, d] - (pos[j, d] - 2.0 * dj * normals[p, d])
                        r2 += e * e
                    if r2 < r2max and r2 > 0.0:
                        s -= vj * kernel_f(kernel_id, np.sqrt(r2), h, dim) * r2
        out[i] = s
