"""The divergence-free scheme's pair list and operator (sphcore.physics.solvepairs) against
what they must give exactly: the pair list against all pairs, the summed density of the
initial lattice, the hydrostatic kernel average, the operator's symmetry, its eigenvalues
and symbol, and the solves' error per particle."""

from __future__ import annotations

import numpy as np
import pytest

from sphcore.physics import pairfill as pf
from sphcore.physics import solvepairs as sp
from sphcore.physics.kernels import KERNEL_IDS, SUPPORT, kernel_f, kernel_w, lattice_nodes

WENDLAND = KERNEL_IDS["wendland_c2"]


def _pairs(pos, h, kid=WENDLAND, cap=4):
    """The pair list of ``pos`` as solvepairs builds it: (start, end, nb, w, g); ``cap`` the
    first rows' capacity (a small one: rows overflow and the walk is repeated with the
    counts as capacities, as the scheme does)."""
    n, dim = pos.shape
    support = SUPPORT * h
    cell, order = np.zeros(n, np.int64), np.zeros(n, np.int64)
    cell_start, nc0, nc1, nc2 = pf.bin_cells(pos, support, cell, order, np.zeros(1, np.int64))
    counts = np.zeros(n, np.int64)
    caps = np.full(n, cap, np.int64)
    start = np.zeros(n, np.int64)
    while True:
        size = pf.row_starts(caps, start)
        nb, w, g = np.zeros(size, np.int32), np.zeros(size), np.zeros((size, dim))
        pf.fill_pairs(pos, np.zeros_like(pos), support, order, cell_start, nc0, nc1, nc2, kid, h, start, caps,
                      nb, w, g, counts, 2)
        if np.all(counts <= caps):
            return start, start + counts, nb, w, g
        caps = counts.copy()


def _lattice(count, dx):
    axes = [(np.arange(c) + 0.5) * dx for c in count]
    return np.ascontiguousarray(np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, len(count)))


@pytest.mark.parametrize("dim", [2, 3])
def test_the_pair_list_holds_every_pair_within_the_support_once(dim):
    rng = np.random.default_rng(7)
    pos = rng.random((400 if dim == 2 else 600, dim)) * 0.3
    h = 0.03
    start, end, nb, w, g = _pairs(pos, h)
    d = pos[:, None, :] - pos[None, :, :]
    r = np.sqrt((d * d).sum(-1))
    for i in range(pos.shape[0]):
        row = nb[start[i]:end[i]]
        want = np.flatnonzero((r[i] < SUPPORT * h) & (np.arange(pos.shape[0]) != i))
        assert sorted(row.tolist()) == want.tolist()
        # each pair's kernel value and gradient grad_i W_ij = F (x_i - x_j), F < 0
        for p in range(start[i], end[i]):
            j = nb[p]
            assert w[p] == pytest.approx(kernel_w(WENDLAND, r[i, j], h, dim), rel=1e-12)
            assert np.dot(g[p], pos[i] - pos[j]) <= 0.0


@pytest.mark.parametrize("dim,h_over_dx", [(2, 1.3), (2, 2.0), (3, 1.0)])
def test_the_initial_lattice_sums_to_rho0_inside(dim, h_over_dx):
    dx, rho0 = 0.01, 1000.0
    count = (24, 24) if dim == 2 else (12, 12, 12)
    pos = _lattice(count, dx)
    h = h_over_dx * dx
    start, end, nb, w, g = _pairs(pos, h)
    n = pos.shape[0]
    m = np.full(n, rho0 * dx ** dim)
    sigma = sp.lattice_sum(WENDLAND, h, dx, dim)
    rho = np.zeros(n)
    sp.summed_density(rho, start, end, nb, w, m, kernel_w(WENDLAND, 0.0, h, dim), 1.0 / sigma, np.zeros(n))
    inner = np.all((pos > SUPPORT * h) & (pos < np.array(count) * dx - SUPPORT * h), axis=1)
    assert inner.sum() > 0
    np.testing.assert_allclose(rho[inner], rho0, rtol=1e-12)
    assert np.all(rho <= rho0 * (1 + 1e-12))  # a truncated support sums less, never more
    edge = np.any((pos < dx) | (pos > np.array(count) * dx - dx), axis=1)
    assert np.all(rho[edge] < 0.9 * rho0)


def test_the_kernel_average_keeps_a_hydrostatic_pressure_exactly_next_to_walls_and_surface():
    dx, h = 0.01, 0.013
    pos = _lattice((20, 30), dx)
    rng = np.random.default_rng(3)
    pos += rng.uniform(-0.2, 0.2, pos.shape) * dx  # off the lattice too
    start, end, nb, w, g = _pairs(pos, h)
    n = pos.shape[0]
    gravity = np.array([0.0, -9.81, 0.0])
    kappa = 9.81 * (0.3 - pos[:, 1])  # p / rho of water at rest under a surface at 0.3 m
    rho = np.full(n, 1000.0) * rng.uniform(0.98, 1.02, n)
    m = np.full(n, 1000.0 * dx * dx)
    out = np.zeros(n)
    sp.kernel_average(out, start, end, nb, w, m, rho, pos, kappa, gravity, kernel_w(WENDLAND, 0.0, h, 2),
                      np.zeros(n), np.zeros(n))
    np.testing.assert_allclose(out, kappa, rtol=0, atol=1e-12)
    # and it removes a pressure alternating between particle layers (the solves' blind mode)
    layered = kappa + np.where(np.round(pos[:, 1] / dx - 0.5).astype(int) % 2 == 0, 1.0, -1.0)
    sp.kernel_average(out, start, end, nb, w, m, rho, pos, layered, gravity, kernel_w(WENDLAND, 0.0, h, 2),
                      np.zeros(n), np.zeros(n))
    inner = np.all((pos > 3 * h) & (pos < np.array([0.2, 0.3]) - 3 * h), axis=1)
    assert np.abs(out - kappa)[inner].max() < 0.5 * np.abs(layered - kappa)[inner].min()


@pytest.mark.parametrize("dim,h_over_dx,lam", [(2, 1.0, 2.11), (2, 1.3, 2.60), (2, 2.0, 5.67), (3, 1.0, 2.60)])
def test_the_operator_s_largest_eigenvalue_exceeds_two_so_plain_jacobi_diverges(dim, h_over_dx, lam):
    # from the symbol, and recomputed by an independent script over the same wave grid
    assert sp.lattice_eigenvalue(WENDLAND, h_over_dx, 1.0, dim) == pytest.approx(lam, abs=0.01)
    assert lam > 2.0


@pytest.mark.parametrize("dim", [2, 3])
def test_the_solves_operator_is_symmetric_next_to_a_wall(dim):
    # kappa / rho -> the density rate after its pressure kick (dt = 1, from rest), particles
    # off a lattice next to the wall x = 0 with the walls' gradient G: the matrix is symmetric
    # (the kick is the rate's adjoint, so that the Chebyshev-accelerated Jacobi iterates on
    # a real spectrum), and its diagonal is the Jacobi weight's (less the added 2 (rho0 G)^2)
    dx, h, rho0 = 1.0, 1.3, 1000.0
    rng = np.random.default_rng(11)
    pos = _lattice((6, 7) if dim == 2 else (4, 4, 4), dx) + rng.uniform(-0.2, 0.2, (42 if dim == 2 else 64, dim))
    start, end, nb, w, g = _pairs(pos, h)
    n = pos.shape[0]
    m = np.full(n, rho0 * dx ** dim)
    rho = rho0 * (1.0 + rng.uniform(-0.01, 0.01, n))
    inv_sigma = 1.0 / sp.lattice_sum(WENDLAND, h, dx, dim)
    grad = np.zeros((n, dim))
    grad[:, 0] = -np.clip(SUPPORT * h - pos[:, 0], 0.0, None) ** 2 / (SUPPORT * h) ** 3  # the wall's share rises to x = 0
    a = np.zeros((n, n))
    for k in range(n):
        vel = np.zeros((n, dim))
        sp.pressure_kick(vel, start, end, nb, g, m, np.eye(n)[k], grad, rho0, 1.0)
        sp.density_rate(a[:, k], start, end, nb, g, m, vel, grad, np.zeros(0), rho0, inv_sigma)
    assert np.abs(grad[:, 0]).max() > 0.1 and np.abs(a).max() > 0.0
    np.testing.assert_allclose(a, a.T, rtol=0, atol=1e-12 * np.abs(a).max())
    alpha = np.zeros(n)
    sp.diagonal(alpha, start, end, nb, g, m, rho, grad, rho0, inv_sigma)
    wall = 2.0 * rho0 ** 2 * (grad * grad).sum(axis=1)
    np.testing.assert_allclose(1.0 / alpha, (-np.diag(a) + wall) / rho, rtol=1e-12)


@pytest.mark.parametrize("wave", [(0.3, 0.35), (0.18, 0.23), (0.5, 0.0)])
def test_the_operator_applied_to_a_wave_gives_the_symbol_s_eigenvalue(wave):
    # kappa = cos(k . x) on a lattice: the pressure kick of kappa (dt = 1, from rest) then the
    # density rate give -lambda(k) kappa_i / alpha_i inside, the eigenvalue the Chebyshev
    # interval is built from
    dx, h, rho0 = 1.0, 1.3, 1000.0
    pos = _lattice((40, 40), dx)
    start, end, nb, w, g = _pairs(pos, h)
    n = pos.shape[0]
    m = np.full(n, rho0 * dx * dx)
    rho = np.full(n, rho0)
    inv_sigma = 1.0 / sp.lattice_sum(WENDLAND, h, dx, 2)
    grad = np.zeros((n, 2))
    k = np.pi * np.array(wave) / dx
    kappa = np.cos(pos @ k)
    vel = np.zeros((n, 2))
    sp.pressure_kick(vel, start, end, nb, g, m, kappa / rho, grad, rho0, 1.0)
    rate, alpha = np.zeros(n), np.zeros(n)
    sp.density_rate(rate, start, end, nb, g, m, vel, grad, np.zeros(0), rho0, inv_sigma)
    sp.diagonal(alpha, start, end, nb, g, m, rho, grad, rho0, inv_sigma)
    x, r = lattice_nodes(h, dx, 2)
    x = x[r < SUPPORT * h]
    gl = np.array([kernel_f(WENDLAND, ri, h, 2) for ri in r[r < SUPPORT * h]])[:, None] * x
    t = np.sin(x @ k) @ gl
    symbol = float(t @ t) / float((gl * gl).sum())
    inner = np.all((pos > 3 * SUPPORT * h) & (pos < 40 * dx - 3 * SUPPORT * h), axis=1) & (np.abs(kappa) > 0.3)
    np.testing.assert_allclose(-rate[inner] * alpha[inner] / kappa[inner], symbol, rtol=1e-9)


def test_the_compression_error_counts_compression_only():
    """The solves' error per particle: |e| by default, max(e, 0) with ``error =
    "compression"``; 0 for a particle at zero pressure that expands (a free surface) and for
    a particle alone, either way."""
    e = np.array([2.0, -3.0, -1.0, 4.0, -2.0])
    kappa = np.array([1.0, 10.0, 0.0, 1.0, 5.0])
    alpha = np.array([1.0, 1.0, 1.0, 0.0, 1.0])
    rho0, dt = 1000.0, 0.5
    rate = e / dt  # base = rho0: e = dt rate
    base = np.full(5, rho0)
    for compression, want in ((False, [2.0, 3.0, 0.0, 0.0, 2.0]), (True, [2.0, 0.0, 0.0, 0.0, 0.0])):
        z, err = np.zeros(5), np.zeros(5)
        sp.residual(z, err, base, rate, dt, rho0, kappa, alpha, 1.0, compression)
        assert err.tolist() == want
        assert z.tolist() == (e * alpha).tolist()  # the correction is the same either way


@pytest.mark.parametrize("dim", [2, 3])
def test_one_mass_gives_the_passes_of_the_mass_array_to_the_bit(dim):
    """The passes take the particles' one mass as a float (no partner's mass read) and
    otherwise the array: with all masses equal, the two give the same bits."""
    rng = np.random.default_rng(11)
    pos = rng.random((300 if dim == 2 else 500, dim)) * 0.2
    h = 0.02
    start, end, nb, w, g = _pairs(pos, h)
    n = pos.shape[0]
    m = np.full(n, 0.37)
    assert sp.one_mass(m) == 0.37 and sp.one_mass(np.r_[m[:-1], 0.38]) is None
    rho = rng.uniform(990.0, 1010.0, n)
    vel = rng.normal(size=(n, dim))
    grad = rng.normal(size=(n, dim)) * 10.0
    kr = rng.random(n)
    w0, inv_sigma = kernel_w(WENDLAND, 0.0, h, dim), 0.99
    outs = []
    for mass in (m, 0.37):
        dens, alpha, rate, v = np.zeros(n), np.zeros(n), np.zeros(n), vel.copy()
        sp.summed_density(dens, start, end, nb, w, mass, w0, inv_sigma, np.zeros(n))
        sp.diagonal(alpha, start, end, nb, g, mass, rho, grad, 1000.0, inv_sigma)
        sp.density_rate(rate, start, end, nb, g, mass, vel, grad, np.zeros(0), 1000.0, inv_sigma)
        sp.pressure_kick(v, start, end, nb, g, mass, kr, grad, 1000.0, 1e-3)
        outs.append((dens, alpha, rate, v))
    for a, b in zip(*outs):
        assert np.array_equal(a, b)
    assert np.all(outs[0][0] > 0.0) and np.any(outs[0][2] != 0.0)
