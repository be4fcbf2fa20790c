"""The pair loop (each pair once, applied to both particles) against a brute-force gather
of the same equations, written independently here from the module docstring of
:mod:`sphcore.physics.equations`; and its result independent of the number of threads.

Every term is on: artificial viscosity, laminar viscosity, density diffusion with the
hydrostatic correction, the Bonet & Lok gradient correction, ghost sources (which act
on fluid particles only), and wall terms on some particles (their neighbour sums gam and
b are accumulated from both sides of each pair).
"""

from __future__ import annotations

import numba
import numpy as np
import pytest
from conftest import make_sim, write_case
from core_cases import blob

from sphcore.neighbours.cellgrid import CellGrid
from sphcore.physics.corrections import neighbour_sums
from sphcore.physics.equations import PAIRS_PARALLEL_MIN, WallTerms, sph_rates
from sphcore.physics.kernels import kernel_f, kernel_w
from sphcore.physics.pairterms import WORK_COLUMNS
from sphcore.physics.particles import Fields
from sphcore_plugins.wall_integral.completion import complete_at_wall


def _setup(tmp_path, dim, seed, kernel_gradient, walls, side=None):
    sim = make_sim(write_case(tmp_path / "blob", blob()))
    prm0 = sim.params
    rng = np.random.default_rng(seed)
    dx = 0.02
    h = 1.3 * dx
    side = side or (6 if dim == 2 else 4)
    grid = np.stack(np.meshgrid(*[np.arange(side) * dx] * dim, indexing="ij"), -1).reshape(-1, dim)
    n_dest = grid.shape[0]
    n_ghost = 12
    pos = np.concatenate([grid + rng.uniform(-0.3, 0.3, grid.shape) * dx,
                          rng.uniform(-dx, side * dx, (n_ghost, dim))])
    n = pos.shape[0]
    vel = rng.normal(0.0, 0.5, (n, dim))
    rho = 1000.0 * (1.0 + rng.uniform(-0.02, 0.02, n))
    p = rng.uniform(-50.0, 400.0, n)
    m = np.full(n, 1000.0 * dx ** dim) * (1.0 + rng.uniform(-0.1, 0.1, n))
    gravity = np.zeros(3)
    gravity[dim - 1] = -9.81
    prm = prm0._replace(dim=dim, h=h, support=2.0 * h, alpha=0.3, beta=0.2, nu=1e-3, delta=0.1,
                        diffusion_hydrostatic=True, eta2=0.01 * h * h, c0=20.0, gravity=gravity,
                        kernel_gradient=kernel_gradient, modified_pressure=False, moment_norm=0.97,
                        rho_ref=1000.0)
    src = Fields(*(np.ascontiguousarray(a) for a in (pos, vel, rho, p, m)))
    cells = CellGrid(src.pos, prm.support)
    L = np.zeros((n_dest, 3, 3)) if kernel_gradient else np.zeros((1, 3, 3))
    if kernel_gradient:
        neighbour_sums(n_dest, src, cells.view, prm, True, L, False, np.zeros(1))
    share = np.where(rng.uniform(0, 1, n_dest) < 0.4, rng.uniform(0.01, 0.3, n_dest), 0.0) if walls \
        else np.zeros(n_dest)
    normals = np.zeros((n_dest, dim, dim))
    for i in range(n_dest):
        e = rng.normal(size=dim)
        e /= np.linalg.norm(e)
        normals[i] = np.outer(e, e)
    wall = WallTerms(share, rng.normal(0, 50.0, (n_dest, dim)), rng.normal(0, 1.0, (n_dest, dim)), normals,
                     rng.uniform(0.5, 1.5, n_dest), walls)
    return n_dest, src, cells, prm, L, wall


def _reference(n_dest, src, prm, L, wall):
    """Gather over every (i, j), i fluid, straight from the equations."""
    pos, vel, rho, p, m = src
    dim = pos.shape[1]
    h, c0, g = prm.h, prm.c0, prm.gravity[:dim]
    acc = np.zeros((n_dest, dim))
    drho = np.zeros(n_dest)
    for i in range(n_dest):
        a = np.zeros(3)
        dr = 0.0
        gam = 0.0
        b = np.zeros(3)
        for j in range(pos.shape[0]):
            x = pos[i] - pos[j]
            r = float(np.sqrt(x @ x))
            if j == i or r >= prm.support:
                continue
            gr = kernel_f(prm.kernel_id, r, h, dim) * x
            if prm.kernel_gradient:
                Lj = L[j, :dim, :dim] if j < L.shape[0] else np.eye(dim)
                gr = 0.5 * (L[i, :dim, :dim] @ gr + Lj @ gr)
            v = vel[i] - vel[j]
            xg = x @ gr
            dr += m[j] * (v @ gr)
            k_i, k_j = (prm.rho0 / c0 ** 2 * (r_ / prm.rho0) ** (2.0 - prm.gamma) for r_ in (rho[i], rho[j]))
            psi = rho[i] - rho[j] - 0.5 * (k_i + k_j) * (g @ x)
            dr += 2 * prm.delta * h * c0 * psi * m[j] / rho[j] * xg / (r * r + prm.eta2)
            s = p[i] / rho[i] ** 2 + p[j] / rho[j] ** 2
            vx = v @ x
            if vx < 0:
                mu = h * vx / (r * r + prm.eta2)
                s += (-prm.alpha * c0 * mu + prm.beta * mu * mu) / (0.5 * (rho[i] + rho[j]))
            a[:dim] -= m[j] * s * gr
            a[:dim] += m[j] * 4 * prm.nu / (rho[i] + rho[j]) * xg / (r * r + prm.eta2) * v
            if wall.active and wall.share[i] > 0:
                vj = m[j] / rho[j]
                gam += vj * kernel_w(prm.kernel_id, r, h, dim)
                b[:dim] += -vj * (x @ g) * gr
        if wall.active and wall.share[i] > 0:
            a0, a1, a2, dr = complete_at_wall(wall, i, dim, vel, rho[i], p[i], prm.rho_ref, prm.moment_norm,
                                               prm.gravity, a[0], a[1], a[2], dr, b[0], b[1], b[2], gam)
            a = np.array([a0, a1, a2])
        acc[i] = g + a[:dim]
        drho[i] = dr
    return acc, drho


def _padded(src, n_far, support):
    """src with n_far extra sources far from every particle: they interact with nothing,
    but push the pair loop onto its parallel branch (PAIRS_PARALLEL_MIN particles)."""
    dim = src.pos.shape[1]
    far = 100.0 * support + np.arange(n_far)[:, None] * 3.0 * support * np.ones((1, dim))
    extra = (far, np.zeros((n_far, dim)), np.full(n_far, 1000.0), np.zeros(n_far), np.full(n_far, 1e-3))
    return Fields(*(np.ascontiguousarray(np.concatenate([a, b])) for a, b in zip(src, extra)))


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("kernel_gradient", [False, True])
@pytest.mark.parametrize("walls", [False, True])
@pytest.mark.parametrize("branch", ["serial", "parallel"])
def test_pair_loop_equals_the_gather_of_every_term(tmp_path, dim, kernel_gradient, walls, branch):
    n_dest, src, cells, prm, L, wall = _setup(tmp_path, dim, 7 + dim, kernel_gradient, walls)
    if branch == "parallel":
        src = _padded(src, PAIRS_PARALLEL_MIN, prm.support)
        cells = CellGrid(src.pos, prm.support)
        assert src.pos.shape[0] >= PAIRS_PARALLEL_MIN
    acc = np.zeros((n_dest, dim))
    drho = np.zeros(n_dest)
    sph_rates(n_dest, src, cells.view, prm, L, wall, acc, drho, np.zeros((src.pos.shape[0], WORK_COLUMNS)),
              np.zeros_like(src.pos), numba.get_num_threads(), complete_at_wall)
    ref_acc, ref_drho = _reference(n_dest, src, prm, L, wall)
    assert np.abs(acc - ref_acc).max() <= 1e-11 * np.abs(ref_acc).max()
    assert np.abs(drho - ref_drho).max() <= 1e-11 * np.abs(ref_drho).max()


@pytest.mark.parametrize("dim", [2, 3])
def test_pair_forces_are_equal_and_opposite(tmp_path, dim):
    """Without ghosts, walls or gravity the pressure, viscous and laminar forces sum to zero
    over the particles to round-off: each pair is applied to both with opposite signs."""
    n_dest, src, cells, prm, L, wall = _setup(tmp_path, dim, 3, False, False)
    src = Fields(*(a[:n_dest].copy() for a in src))
    cells = CellGrid(src.pos, prm.support)
    prm = prm._replace(gravity=np.zeros(3))
    acc = np.zeros((n_dest, dim))
    drho = np.zeros(n_dest)
    sph_rates(n_dest, src, cells.view, prm, L, wall, acc, drho, np.zeros((src.pos.shape[0], WORK_COLUMNS)), np.zeros_like(src.pos), 2, complete_at_wall)
    force = (src.m[:, None] * acc).sum(axis=0)
    scale = np.abs(src.m[:, None] * acc).sum(axis=0)
    assert np.all(np.abs(force) <= 1e-14 * scale)


@pytest.mark.parametrize("dim", [2, 3])
def test_result_does_not_depend_on_the_thread_count(tmp_path, dim):
    """Slabs of one parity run in parallel; the order of the additions to a particle is set
    by the slabs alone, so one thread and two give the same bits, and so does a thread
    count passed to the kernel that differs from numba's (it only assigns slabs to threads)."""
    if numba.config.NUMBA_NUM_THREADS < 2:
        pytest.skip("numba is limited to one thread here (NUMBA_NUM_THREADS)")
    n_dest, src, cells, prm, L, wall = _setup(tmp_path, dim, 11, True, True, side=48 if dim == 2 else 13)
    assert src.pos.shape[0] >= PAIRS_PARALLEL_MIN  # large enough for the parallel pair loop
    assert len(cells.slab_start) - 1 >= 4  # at least two slabs in each phase
    out = []
    before = numba.get_num_threads()
    try:
        for threads, nth in ((1, 1), (2, 2), (2, 5)):
            numba.set_num_threads(threads)
            acc = np.zeros((n_dest, dim))
            drho = np.zeros(n_dest)
            sph_rates(n_dest, src, cells.view, prm, L, wall, acc, drho, np.zeros((src.pos.shape[0], WORK_COLUMNS)),
                      np.zeros_like(src.pos), nth, complete_at_wall)
            out.append((acc, drho))
    finally:
        numba.set_num_threads(before)
    for acc, drho in out[1:]:
        assert np.array_equal(out[0][0], acc) and np.array_equal(out[0][1], drho)


@pytest.mark.slow
@pytest.mark.parametrize("kernel_gradient", [False, True])
def test_three_passes_give_the_fused_loops_bits_in_3d(tmp_path, kernel_gradient):
    """The 3D pair loop walks a particle's partners in three passes (gather, vectorised
    terms, scatter in the partners' order); the fused walk of 2D, built here for 3D, must
    give the same bits, every term on, wall sums included (sphcore.physics.pairterms)."""
    from sphcore.physics.equations import _build

    fused = _build(3, complete_at_wall, three_pass=False)
    walls = _build(3, complete_at_wall)
    for rates, three in ((walls, True), (fused, False)):  # the two walks, not one twice
        assert rates.py_func.__globals__["_slab_pairs"].py_func.__globals__["THREE_PASS"] is three
    n_dest, src, cells, prm, L, wall = _setup(tmp_path, 3, 5, kernel_gradient, True)
    out = []
    for rates in (walls, fused):
        acc, drho = np.zeros((n_dest, 3)), np.zeros(n_dest)
        work = np.zeros((src.pos.shape[0], WORK_COLUMNS))
        rates(n_dest, src, cells.view, prm, L, wall, acc, drho, work, np.zeros_like(src.pos), 1)
        out.append((acc, drho, work))
    assert np.abs(out[0][0]).max() > 0.0 and np.count_nonzero(wall.share) > 0
    for a, b in zip(*out):
        assert np.array_equal(a, b)
