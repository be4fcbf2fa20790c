"""Lattice error of the truncated SPH sums next to walls, tabulated once per run.

A particle of the square (cubic) lattice the blocks are filled with, at distances
d_a = (k_a + 1/2) dx from m mutually perpendicular walls (m = 1 a plane, 2 an edge or a 2D
corner, 3 a 3D corner), has the truncated neighbour sum D = sum_j V_j grad_i W_ij over the
lattice nodes inside; the continuum says D = -G, G the gradient of the walls' share of its
support. The difference E = D + G is the lattice error of the sum: on the initial lattice a
uniform pressure would push the particle by 2 (p/rho) E. The wall model uses G - E as the
wall gradient: it keeps the exact G's growth as a particle approaches a wall (the wall's
stiffness, which the discrete complement -D alone lacks: it does not depend on the wall
distance at all, and particles then rest on the reflective contact instead of the wall
pressure) while a uniform pressure exerts no force on the initial lattice, corners included.

The same holds for the first moment along the walls (a side wall's vertical): the node's
own sum b_t = -sum_j V_j F_ij (x_ij . t)^2 plus lambda times the exact outside moment
A_t = (T + s) t . t differs from the interior's lambda (Params.moment_norm) by F; the
plugin removes it from the hydrostatic moment, so that a column along a side wall is held
up as the interior is and does not slide.

Tables: nodes (k + 1/2) dx for (k + 1/2) dx < 2h and a last node at 2h (where the wall's
influence ends); multilinear in between, the first node's value closer to a wall than the
first row. Planes that are not mutually perpendicular (a V tank's apex) add their
single-plane errors.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from sphcore.api import kernel_f, kernel_w, particle_distance

from .share import wall_terms_at

PERP_TOL = 1e-9  # |n_a . n_b| below this: perpendicular planes


def _node_error(kernel_id, h, dx, dim, lam, d):
    """(E_1..E_m, F, Gamma) of a lattice node at distances d (m,) from m perpendicular walls
    x_a = 0 (a < m), the fluid at x_a > 0: E = D + G, F = B + lam A_t - lam and
    Gamma = sum_j V_j W_ij over the neighbours (self excluded), with D the truncated
    gradient sum and B its first moment along the walls (lattice volumes dx^dim)."""
    m = len(d)
    support = 2.0 * h
    n = int(math.ceil(support / dx))
    k = np.arange(-n, n + 1, dtype=np.float64) * dx
    off = np.stack(np.meshgrid(*([k] * dim), indexing="ij"), axis=-1).reshape(-1, dim)  # x_j - x_i
    r = np.sqrt((off * off).sum(axis=1))
    keep = (r > 0.0) & (r < support)
    for a in range(m):
        keep &= d[a] + off[:, a] > 0.0
    off, r = off[keep], r[keep]
    f = dx ** dim * np.array([kernel_f(kernel_id, ri, h, dim) for ri in r])
    dsum = -(f[:, None] * off).sum(axis=0)  # grad_i W_ij = F (x_i - x_j)
    x = np.zeros(dim)
    x[:m] = d
    normals = np.eye(dim)[:m]
    out = np.zeros(m + 2)
    g3 = np.zeros(3)
    if m < dim:  # first moment along the first axis parallel to every wall
        g3[m] = 1.0
    s, g, tg = wall_terms_at(x, normals, np.zeros(m), kernel_id, h, g3)
    out[:m] = dsum[:m] + g[:m]  # E = D + G (1/m)
    out[m + 1] = dx ** dim * sum(kernel_w(kernel_id, ri, h, dim) for ri in r)
    if m < dim:
        bsum = -(f * off[:, m] ** 2).sum()
        out[m] = bsum + lam * (tg[m] + s) - lam
    return out


def lattice_error_tables(kernel_id: int, h: float, dx: float, dim: int, lam: float):
    """(nodes (K,), tab1 (K, 3), tab2 (K*K, 4), tab3 (K**3, 5)): the node distances (m) and,
    for 1, 2 and 3 perpendicular walls, (E_1..E_m (1/m), F, Gamma) at every node combination
    (row-major, see :func:`_node_error`); tab3 is empty in 2D."""
    support = 2.0 * h
    nodes = [(k + 0.5) * dx for k in range(int(math.ceil(support / dx)) + 1) if (k + 0.5) * dx < support]
    nodes = np.array(nodes + [support])
    tabs = []
    for m in (1, 2, 3):
        if m > dim:
            tabs.append(np.zeros((0, m + 2)))
            continue
        grid = np.stack(np.meshgrid(*([nodes] * m), indexing="ij"), axis=-1).reshape(-1, m)
        tabs.append(np.array([_node_error(kernel_id, h, dx, dim, lam, d) for d in grid]))
    return (nodes, *tabs)


@njit(cache=True)
def _locate(nodes, d):
    """(index, fraction) of d between nodes, clamped to the first and last node."""
    K = nodes.shape[0]
    if d <= nodes[0]:
        return 0, 0.0
    for k in range(1, K):
        if d < nodes[k]:
            return k - 1, (d - nodes[k - 1]) / (nodes[k] - nodes[k - 1])
    return K - 2, 1.0


@njit(cache=True, inline="always")
def _interp(nodes, tab, m, d0, d1, d2, col):
    """Multilinear value of column ``col`` of the m-wall table at distances (d0, d1, d2)[:m]."""
    K = nodes.shape[0]
    i0, f0 = _locate(nodes, d0)
    i1, f1 = (0, 0.0) if m < 2 else _locate(nodes, d1)
    i2, f2 = (0, 0.0) if m < 3 else _locate(nodes, d2)
    v = 0.0
    for c in range(1 << m):
        w = 1.0
        idx = 0
        for a in range(m):
            bit = (c >> a) & 1
            ia, fa = (i0, f0) if a == 0 else ((i1, f1) if a == 1 else (i2, f2))
            w *= fa if bit else 1.0 - fa
            idx = idx * K + ia + bit
        if w != 0.0:
            v += w * tab[idx, col]
    return v


@njit(cache=True, inline="always")
def _normal_part(normals, k, v, dim):
    """n_k . v, the component of v along plane k's normal."""
    c = normals[k, 0] * v[0] + normals[k, 1] * v[1]
    if dim == 3:
        c += normals[k, 2] * v[2]
    return c


@njit(cache=True, inline="always")
def subtract_one(i, pos, normals, offsets, nodes, tab1, tab2, tab3, support, lam, gravity, grad, hydro, fill):
    """For particle i, over the walls within ``support`` (inward normals n_a): grad (n, dim,
    1/m) -= sum_a E_a n_a, hydro (n, dim, m/s^2) -= (F / lam) g_t (g_t the part of g along
    every one of those walls) and fill (n,) += Gamma, the neighbour sum sum_j V_j W_ij a
    particle of the initial lattice has there (the core compares the particle's own sum
    with it: a particle with fewer neighbours than the lattice, a splash or a film, gets a
    proportionally smaller wall completion). Up to ``dim`` mutually perpendicular walls take
    one orthant table; other combinations (a V tank's apex) add their single-wall errors
    and deficits of Gamma. Nothing is written for a particle farther than ``support`` from
    every wall.
    """
    dim = pos.shape[1]
    nk = normals.shape[0]
    full = tab1[tab1.shape[0] - 1, 2]  # Gamma of an interior particle (last node: 2h from the wall)
    cnt = 0
    k0 = k1 = k2 = -1
    for k in range(nk):
        if particle_distance(normals, offsets, k, pos, i) < support:
            if cnt == 0:
                k0 = k
            elif cnt == 1:
                k1 = k
            elif cnt == 2:
                k2 = k
            cnt += 1
    if cnt == 0:
        return
    perp = cnt <= dim
    if perp and cnt >= 2:
        c01 = 0.0
        c02 = 0.0
        c12 = 0.0
        for a in range(dim):
            c01 += normals[k0, a] * normals[k1, a]
            if cnt == 3:
                c02 += normals[k0, a] * normals[k2, a]
                c12 += normals[k1, a] * normals[k2, a]
        perp = abs(c01) <= PERP_TOL and abs(c02) <= PERP_TOL and abs(c12) <= PERP_TOL
    if perp:
        tab = tab1 if cnt == 1 else (tab2 if cnt == 2 else tab3)
        d0 = particle_distance(normals, offsets, k0, pos, i)
        d1 = particle_distance(normals, offsets, k1, pos, i) if cnt > 1 else 0.0
        d2 = particle_distance(normals, offsets, k2, pos, i) if cnt > 2 else 0.0
        f = _interp(nodes, tab, cnt, d0, d1, d2, cnt) / lam
        fill[i] += _interp(nodes, tab, cnt, d0, d1, d2, cnt + 1)
        # the first moment's error lies along the walls: g minus its parts along every normal
        g0, g1, g2 = gravity[0], gravity[1], gravity[2]
        for a in range(cnt):
            k = k0 if a == 0 else (k1 if a == 1 else k2)
            gn = _normal_part(normals, k, gravity, dim)
            g0 -= gn * normals[k, 0]
            g1 -= gn * normals[k, 1]
            if dim == 3:
                g2 -= gn * normals[k, 2]
            e = _interp(nodes, tab, cnt, d0, d1, d2, a)
            for x in range(dim):
                grad[i, x] -= e * normals[k, x]
        hydro[i, 0] -= f * g0
        hydro[i, 1] -= f * g1
        if dim == 3:
            hydro[i, 2] -= f * g2
    else:
        gam = full
        for k in range(nk):
            d = particle_distance(normals, offsets, k, pos, i)
            if d < support:
                e = _interp(nodes, tab1, 1, d, 0.0, 0.0, 0)
                f = _interp(nodes, tab1, 1, d, 0.0, 0.0, 1) / lam
                gam -= full - _interp(nodes, tab1, 1, d, 0.0, 0.0, 2)
                gn = _normal_part(normals, k, gravity, dim)
                for a in range(dim):
                    grad[i, a] -= e * normals[k, a]
                    hydro[i, a] -= f * (gravity[a] - gn * normals[k, a])
        fill[i] += max(gam, 0.0)
