"""Density diffusion with the hydrostatic correction leaves water at rest alone.

A column at rest whose density follows the hydrostatic stratification of the Tait
equation exactly must see no density diffusion: psi_ij = rho_i - rho_j - k_ij g . x_ij vanishes for every pair
when k_ij g . x_ij is the hydrostatic density difference across the pair. The
linearisation about rho0 (k = rho0/c0^2 for every pair) leaves the curvature of the
stratification, which this test detects (the second assertion), so the test fails for it.

Exact hydrostatics: dp/dz = -rho(p) g with p = B ((rho/rho0)^gamma - 1) integrates to
rho(z) = rho0 [1 + ((gamma - 1)/gamma) rho0 g (H - z) / B]^(1/(gamma - 1)). (A case starts
from rho(p = rho0 g (H - z)), which differs from it by 0.25% of the stratification at
mid-depth of a 1 m tank: the run settles to this one.)
"""

from __future__ import annotations

import numpy as np
from conftest import make_sim, write_case
from core_cases import blob

from sphcore.neighbours.cellgrid import CellGrid
from sphcore.physics.equations import WallTerms, sph_rates
from sphcore.physics.pairterms import WORK_COLUMNS
from sphcore.physics.particles import Fields


def _column_rates(tmp_path, dim, k_of_rho=None):
    """drho/dt of the interior particles of a column of water at rest, exactly hydrostatic;
    only density diffusion is on. ``k_of_rho``: replaces the pair loop's k by a reference
    gather with that k (to show what the test detects)."""
    prm0 = make_sim(write_case(tmp_path / "blob", blob())).params
    dx, H = 0.02, 1.0
    h = 2.0 * dx
    c0 = 10.0 * np.sqrt(2.0 * 9.81 * H)  # the cases' rule: 44 m/s, rho 0.5% above rho0 at the floor
    width = 14 if dim == 2 else 12
    axes = [np.arange(width) * dx] * (dim - 1) + [(np.arange(round(H / dx)) + 0.5) * dx]
    pos = np.stack(np.meshgrid(*axes, indexing="ij"), -1).reshape(-1, dim)
    n = pos.shape[0]
    gravity = np.zeros(3)
    gravity[dim - 1] = -9.81
    b = 1000.0 * c0 ** 2 / 7.0
    rho = 1000.0 * (1.0 + (6.0 / 7.0) * 1000.0 * 9.81 * (H - pos[:, -1]) / b) ** (1.0 / 6.0)
    m = 1000.0 * dx ** dim * np.ones(n)
    src = Fields(np.ascontiguousarray(pos), np.zeros((n, dim)), rho, np.zeros(n), m)
    prm = prm0._replace(dim=dim, h=h, support=2.0 * h, alpha=0.0, beta=0.0, nu=0.0, delta=0.1,
                        diffusion_hydrostatic=True, eta2=0.01 * h * h, c0=c0, rho0=1000.0, gamma=7.0,
                        gravity=gravity, kernel_gradient=False, modified_pressure=False)
    interior = np.all((pos[:, :-1] > 2 * h) & (pos[:, :-1] < (width - 1) * dx - 2 * h), axis=1) \
        & (pos[:, -1] > 2 * h) & (pos[:, -1] < H - 2 * h)
    if k_of_rho is None:
        cells = CellGrid(src.pos, prm.support)
        wall = WallTerms(np.zeros(n), np.zeros((n, dim)), np.zeros((n, dim)), np.zeros((n, dim, dim)),
                         np.zeros(n), False)
        acc, drho = np.zeros((n, dim)), np.zeros(n)
        sph_rates(n, src, cells.view, prm, np.zeros((1, 3, 3)), wall, acc, drho, np.zeros((n, WORK_COLUMNS)),
                  np.zeros((n, dim)), 1)
        return drho[interior], rho, c0
    from sphcore.physics.kernels import kernel_f
    drho = []
    for i in np.flatnonzero(interior):
        x = pos[i] - pos
        r = np.sqrt((x * x).sum(1))
        near = (r < prm.support) & (r > 0)
        gr = np.array([kernel_f(prm.kernel_id, rr, h, dim) for rr in r[near]])[:, None] * x[near]
        xg = (x[near] * gr).sum(1)
        psi = rho[i] - rho[near] - k_of_rho(rho[i], rho[near], c0) * (x[near] @ gravity[:dim])
        drho.append((2 * prm.delta * h * c0 * psi * m[near] / rho[near] * xg / (r[near] ** 2 + prm.eta2)).sum())
    return np.array(drho), rho, c0


def test_hydrostatic_diffusion_leaves_a_tait_column_at_rest(tmp_path):
    for dim in (2, 3):
        drho, rho, c0 = _column_rates(tmp_path, dim)
        # the time sound takes to cross the column: over it the density may not move by
        # more than 1e-7 of its stratification (rho_floor - rho_surface = 5 kg/m^3)
        strat = rho.max() - rho.min()
        assert strat > 4.0
        assert np.abs(drho).max() * (1.0 / c0) < 1e-7 * strat, (dim, np.abs(drho).max())


def test_linearisation_about_rho0_would_diffuse_the_column(tmp_path):
    """The same column with k = rho0/c0^2 for every pair (the linearisation the pair loop no
    longer uses): the deep particles' density then drifts, 1e3 times the bound above."""
    drho, rho, c0 = _column_rates(tmp_path, 2, k_of_rho=lambda ri, rj, c0: 1000.0 / c0 ** 2)
    strat = rho.max() - rho.min()
    assert np.abs(drho).max() * (1.0 / c0) > 3e-5 * strat  # measured 1.0e-4; the pair loop: 6e-11
    # and the trapezoidal k of the pair loop, by the same gather, meets the bound
    k = lambda r_, c0: 1000.0 / c0 ** 2 * (r_ / 1000.0) ** -5.0  # noqa: E731
    drho, rho, c0 = _column_rates(tmp_path, 2, k_of_rho=lambda ri, rj, c0: 0.5 * (k(ri, c0) + k(rj, c0)))
    assert np.abs(drho).max() * (1.0 / c0) < 1e-7 * strat
