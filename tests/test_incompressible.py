"""The divergence-free scheme's pieces (sphcore.physics.solvepairs, sphcore.physics.incompressible)
against what they must give exactly: the pair list against all pairs, the summed density of
the initial lattice, the hydrostatic kernel average, the Jacobi weight's eigenvalue, and the
keys the scheme refuses."""

from __future__ import annotations

import numpy as np
import pytest

from sphcore.physics import solvepairs as sp
from sphcore.physics.kernels import KERNEL_IDS, SUPPORT, kernel_f, kernel_w, lattice_nodes
from sphcore.testing import run_case

WENDLAND = KERNEL_IDS["wendland_c2"]


def _pairs(pos, h, kid=WENDLAND, cap=4):
    """The pair list of ``pos`` as solvepairs builds it: (start, end, nb, w, g); ``cap`` the
    first rows' capacity (a small one: rows overflow and the walk is repeated with the
    counts as capacities, as the scheme does)."""
    n, dim = pos.shape
    support = SUPPORT * h
    cell, order = np.zeros(n, np.int64), np.zeros(n, np.int64)
    cell_start, nc0, nc1, nc2 = sp.bin_cells(pos, support, cell, order, np.zeros(1, np.int64))
    counts = np.zeros(n, np.int64)
    caps = np.full(n, cap, np.int64)
    start = np.zeros(n, np.int64)
    while True:
        size = sp.row_starts(caps, start)
        nb, w, g = np.zeros(size, np.int32), np.zeros(size), np.zeros((size, dim))
        sp.fill_pairs(pos, np.zeros_like(pos), support, order, cell_start, nc0, nc1, nc2, kid, h, start, caps,
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


def test_dfsph_refuses_the_keys_it_cannot_honour(tmp_path):
    from sphcore.testing import tiny_case, case_with

    base = case_with(tiny_case(), {"scheme.name": "dfsph"})
    for key, value, named in [("physics.modified_pressure", True, "physics.modified_pressure"),
                              ("corrections.shepard_every", 5, "corrections.shepard_every"),
                              ("physics.sph", False, "scheme.name"),
                              ("plugins.use", ["ghost", "reflective"], "plugins.use"),
                              ("bodies", [{"wall": 0, "density": 500.0}], "bodies")]:
        with pytest.raises(Exception) as err:
            run_case(tmp_path / key, case_with(base, {key: value}))
        assert named in str(err.value)
        assert not (tmp_path / key / "output").exists()


def _column(dt, t_end):
    """A 2D water column of 12 x 24 particles against the left wall of a box, dfsph with the
    wall model, a fixed step."""
    return {
        "case": {"dim": 2},
        "domain": {"min": [0.0, 0.0], "max": [0.4, 0.3]},
        "blocks": [{"min": [0.0, 0.0], "max": [0.12, 0.24]}],
        "particles": {"dx": 0.01},
        "scheme": {"name": "dfsph"},
        "time": {"t_end": t_end, "dt": dt},
        "neighbours": {"sort_every": 3},
        "plugins": {"use": ["reflective", "wall_integral"]},
        "reflective": {"cr": 1.0},
    }


def _column_3d(dt, t_end):
    """The column of :func:`_column` in 3D, 6 x 12 x 6 particles across the box's depth."""
    case = _column(dt, t_end)
    case["case"]["dim"] = 3
    case["domain"] = {"min": [0.0, 0.0, 0.0], "max": [0.2, 0.2, 0.06]}
    case["blocks"] = [{"min": [0.0, 0.0, 0.0], "max": [0.06, 0.12, 0.06]}]
    return case


@pytest.mark.parametrize("dim", [2, 3])
def test_a_dfsph_restart_continues_bit_for_bit(tmp_path, dim, monkeypatch):
    """A run stopped after 27 steps and restarted from its checkpoint ends as the run that
    went through. A reorder comes at the restart's first step (every 9 steps), where the
    run that went through renumbers its pair list and the restarted one lists the pairs
    anew: the restarted run's reorders are recorded to show it does reorder there."""
    from conftest import by_id, write_case

    from sphcore.physics import incompressible
    from sphcore.run import runner

    dt = 2.0 ** -10
    case = (_column if dim == 2 else _column_3d)(dt, 40 * dt)
    case["neighbours"]["sort_every"] = 9
    case_dir = write_case(tmp_path / "case", case)
    full = runner.run(case_dir, output=tmp_path / "full", quiet=True)
    runner.run(case_dir, output=tmp_path / "part", t_end=27 * dt, quiet=True)
    plan = incompressible.DivergenceFree.reorder_plan
    reorders = []

    def recorded(self, forces):
        order = plan(self, forces)
        reorders.append((self.ctx.step, order is not None))
        return order

    monkeypatch.setattr(incompressible.DivergenceFree, "reorder_plan", recorded)
    rest = runner.run(case_dir, output=tmp_path / "part", t_end=40 * dt, restart=True, quiet=True)
    assert (27, True) in reorders
    a, b = full.simulation, rest.simulation
    assert a.step == b.step == 40
    sa, sb = by_id(a.state), by_id(b.state)
    for name in sa:
        assert np.array_equal(sa[name], sb[name]), name
    # the solves' figures in summary.json, continued across the restart
    assert full.summary["dfsph"]["density_solves"] == rest.summary["dfsph"]["density_solves"] == 40
    assert full.summary["dfsph"]["density_iterations_total"] == rest.summary["dfsph"]["density_iterations_total"]
    assert full.summary["dfsph"]["density_error_last"] <= 1e-4


def test_a_falling_column_stays_in_the_box_near_rho0_and_spreads(tmp_path):
    from conftest import write_case

    from sphcore.run import runner

    dt = 2.0 ** -10
    result = runner.run(write_case(tmp_path / "case", _column(dt, 0.15)), output=tmp_path / "out", quiet=True)
    assert result.status == "completed"
    st = result.simulation.state
    assert np.all(st.pos >= 0.0) and np.all(st.pos <= [0.4, 0.3])  # no particle outside the walls
    # incompressible: the summed density within 2 % of rho0 everywhere (a splash is lower)
    assert st.rho.max() <= 1020.0
    # the front has run out along the floor: shallow water's 2 sqrt(g H) t bound on it
    front = st.pos[:, 0].max()
    assert 0.12 + 0.05 < front < 0.12 + 2.0 * np.sqrt(9.81 * 0.24) * 0.15
    fig = result.summary["dfsph"]
    assert fig["density_error_mean"] <= 1e-4 and fig["divergence_error_mean"] <= 1e-3


def test_droplets_that_collide_gain_no_energy(tmp_path):
    """Two droplets of 2 x 2 particles fly at each other (no gravity) and meet at the edge of
    each other's support, where a particle's own pressure barely changes its density (a
    near-zero diagonal). The divergence solve leaves such thin neighbourhoods alone, and the
    collision adds no kinetic energy: no particle ends faster than the droplets came in."""
    from conftest import write_case

    from sphcore.run import runner

    v0 = 1.0
    case = {
        "case": {"dim": 2},
        "domain": {"min": [0.0, 0.0], "max": [0.4, 0.2]},
        "blocks": [{"min": [0.1, 0.09], "max": [0.12, 0.11], "velocity": [v0, 0.0]},
                   {"min": [0.28, 0.095], "max": [0.30, 0.115], "velocity": [-v0, 0.0]}],
        "particles": {"dx": 0.01},
        "physics": {"gravity": [0.0, 0.0, 0.0]},
        "eos": {"c0": 10.0},  # the height rule needs gravity; dfsph does not use it
        "scheme": {"name": "dfsph"},
        "time": {"t_end": 0.12, "dt": 2.0 ** -11},
        "plugins": {"use": ["reflective", "wall_integral"]},
    }
    result = runner.run(write_case(tmp_path / "case", case), output=tmp_path / "out", quiet=True)
    assert result.status == "completed"
    st = result.simulation.state
    assert np.abs(st.pos[:, 0] - 0.2).max() < 0.1  # they met
    speed = np.sqrt((st.vel * st.vel).sum(axis=1))
    assert speed.max() <= v0 * (1.0 + 1e-9)
    assert 0.5 * (st.m * speed * speed).sum() <= 0.5 * st.m.sum() * v0 * v0 * (1.0 + 1e-9)


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


def test_the_compression_error_stops_a_solve_no_later(tmp_path):
    """The iterations do not depend on what the error counts, only when they stop: counting
    compression alone (SPlisHSPlasH's measure, max(e, 0) <= |e| for every particle) stops
    the first step's density solve no later; on this column with a step of 4 ms, sooner (9
    iterations against 7; with 1 ms, 4 either way)."""
    from conftest import write_case

    from sphcore.run import runner

    dt = 2.0 ** -8
    figs = {}
    for error in ("both", "compression"):
        case = _column(dt, dt)
        case["scheme"]["error"] = error
        result = runner.run(write_case(tmp_path / error, case), output=tmp_path / f"out_{error}", quiet=True)
        figs[error] = result.summary["dfsph"]
    assert figs["compression"]["density_iterations_total"] < figs["both"]["density_iterations_total"]


def test_a_run_that_ends_between_steps_takes_no_sliver_of_a_step(tmp_path):
    """t_end a thousandth of a step after the fifth step: the last two steps share what
    remains. A sliver of a step would have the density solve remove the step's density error
    within it (kappa ~ 1 / dt^2), a kick of metres a second (13 m/s here). The column's face
    starts at up to about twice g (its fastest particle at 1.5 g t after five full steps and
    1.8 g t after six): no particle may be faster than 3 g t."""
    from conftest import write_case

    from sphcore.run import runner

    dt = 2.0 ** -10
    t_end = 5.001 * dt
    result = runner.run(write_case(tmp_path / "case", _column(dt, t_end)), output=tmp_path / "out", quiet=True)
    sim = result.simulation
    assert sim.step == 6 and sim.t == pytest.approx(t_end, rel=1e-12)
    speed = np.sqrt((sim.state.vel ** 2).sum(axis=1)).max()
    assert speed <= 3.0 * 9.81 * t_end


def test_the_schemes_shortcuts_change_no_bit(tmp_path, monkeypatch):
    """dfsph reuses the wall terms its last finish computed at the same state, and sizes each
    pair-list row to the particle's partners at the last listing and some room. A run with
    the wall terms computed at every evaluation and rows without room (the first listing's
    empty: they overflow and are walked again) gives the same bits. Its rates are summed
    over the solves' pair list, with the density diffusion left out (it sums its density)."""
    from conftest import by_id, write_case

    from sphcore.physics import incompressible
    from sphcore.run import runner

    dt = 2.0 ** -10
    case = _column(dt, 12 * dt)
    case["density_diffusion"] = {"delta": 0.1}
    case_dir = write_case(tmp_path / "case", case)
    fast = runner.run(case_dir, output=tmp_path / "fast", quiet=True)

    init = incompressible.DivergenceFree.__init__

    def plain(self, run, forces, ctx, scheme):
        init(self, run, forces, ctx, scheme)
        forces.reuse_wall_terms = False
        self.pairs.room = 0  # rows of no room: a particle that gained a partner overflows its row
        self.pairs.counts[:] = 0  # and the first listing's rows are empty: every one overflows

    restored = incompressible.DivergenceFree.restored

    def emptied(self):  # after the start-up probe's listing too
        restored(self)
        self.pairs.counts[:] = 0

    monkeypatch.setattr(incompressible.DivergenceFree, "__init__", plain)
    monkeypatch.setattr(incompressible.DivergenceFree, "restored", emptied)
    slow = runner.run(case_dir, output=tmp_path / "slow", quiet=True)
    sa, sb = by_id(fast.simulation.state), by_id(slow.simulation.state)
    for name in sa:
        assert np.array_equal(sa[name], sb[name]), name
    fc, sc = fast.summary["counters"], slow.summary["counters"]
    assert fc["wall_terms"] < sc["wall_terms"]
    assert fc["rates_from_pair_list"] == fc["rates"] and fc.get("neighbour_search", 0) == 0
    assert fc.get("density_diffusion", 0) == 0
    assert sc["dfsph_pair_overflows"] > 0 and fc.get("dfsph_pair_overflows", 0) == 0


@pytest.mark.parametrize("dim", [2, 3])
def test_the_rates_summed_over_the_pair_list_are_the_cell_walk_s_to_round_off(tmp_path, dim):
    """The non-pressure rates of a dfsph state (artificial and laminar viscosity, the wall
    model's completion next to the floor and walls, gravity) summed over the solves' pair
    list (sphcore.physics.listedrates) against the weakly compressible pair loop's cell
    walk, which evaluates each pair once: the same terms, added in another order."""
    from conftest import write_case

    from sphcore.run import runner

    dt = 2.0 ** -10
    case = (_column if dim == 2 else _column_3d)(dt, 8 * dt)
    case["viscosity"] = {"alpha": 0.2, "beta": 0.1}
    case["fluid"] = {"nu": 1e-3}
    result = runner.run(write_case(tmp_path / "case", case), output=tmp_path / "out", quiet=True)
    sim = result.simulation
    st, forces = sim.state, sim.forces
    assert result.summary["counters"]["rates_from_pair_list"] == result.summary["counters"]["rates"]
    rng = np.random.default_rng(5)
    st.vel += rng.normal(0.0, 0.05, st.vel.shape)  # shear and approaching pairs for the viscosities
    assert forces.listed() is not None  # the list holds the final state
    acc_list, drho_list = np.zeros_like(st.vel), np.zeros(st.n)
    forces.evaluate(acc_list, drho_list)
    listed, forces.listed = forces.listed, None
    acc_walk, drho_walk = np.zeros_like(st.vel), np.zeros(st.n)
    forces.evaluate(acc_walk, drho_walk)
    forces.listed = listed
    near = forces.wall_terms().share > 0.0
    assert near.sum() > st.n // 4  # the completion is exercised
    scale = np.abs(acc_walk - np.asarray(sim.ctx.params.gravity[:dim])).max()
    assert scale > 1.0  # the pair terms are not negligible
    np.testing.assert_allclose(acc_list, acc_walk, rtol=0.0, atol=1e-12 * scale)
    np.testing.assert_allclose(drho_list, drho_walk, rtol=0.0, atol=1e-12 * np.abs(drho_walk).max())


def test_the_walls_density_is_measured_after_the_start_up_probe(tmp_path):
    """The start-up probe evaluates the first rates (which list the pairs and measure the
    walls' part of the density) and puts the run state back: the run measures it again, so
    that the column's lattice starts at rho0 next to the walls as inside. Without it the
    floor's and the wall's layers would start at about rho0 (1 - s), half of it at the floor."""
    from conftest import write_case

    from sphcore.run import runner

    dt = 2.0 ** -10
    result = runner.run(write_case(tmp_path / "case", _column(dt, dt)), output=tmp_path / "out", quiet=True)
    st = result.simulation.state
    wall_rho = result.simulation.run.kept["dfsph"]["wall_rho"]
    assert np.count_nonzero(wall_rho) > st.n // 4
    support = result.simulation.params.support
    covered = (st.pos[:, 0] < 0.12 - support) & (st.pos[:, 1] < 0.24 - support)  # away from the free surfaces
    assert covered.sum() > st.n // 2 and np.count_nonzero(wall_rho[covered]) > st.n // 8
    assert np.abs(st.rho[covered] / 1000.0 - 1.0).max() < 2e-3


@pytest.mark.parametrize("plan", ["scheme", "random"])
def test_a_reorder_renumbers_the_pair_list_as_a_new_listing_would_give_it(tmp_path, plan):
    """After a reorder the pair list is not made again: each row follows its particle and its
    partners are renumbered. In the scheme's own order (its cells') a new listing at the
    same positions gives the same rows in the same order, and the same diagonal and summed
    density to the last bit, so that a run restarted from a checkpoint (which lists anew)
    continues bit for bit. In any other order each row holds the same partners with the
    same W_ij and grad W_ij, the diagonal and density equal to round-off."""
    from conftest import write_case

    from sphcore.run import runner

    dt = 2.0 ** -10
    result = runner.run(write_case(tmp_path / "case", _column(dt, 4 * dt)), output=tmp_path / "out", quiet=True)
    sim = result.simulation
    integ, st, pl = sim.integrator, sim.state, sim.integrator.pairs

    def reorder(order):
        st.permute(order)
        integ.permute(order)
        sim.forces.reordered(order)

    reorder(np.random.default_rng(2).permutation(st.n))  # the particles shuffled
    if plan == "scheme":  # listed in that order, then put in the cells' order
        integ.restored()
        integ._list_pairs(sim.forces.wall_terms)
        order = integ.reorder_plan(sim.forces)
        assert order is not None
        reorder(order)
    assert pl.mark.holds(st)  # the list holds the reordered state

    def rows():
        integ._list_pairs(sim.forces.wall_terms)
        out = []
        for i in range(st.n):
            part = slice(pl.start[i], pl.end[i])
            k = np.argsort(pl.nb[part], kind="stable") if plan == "random" else slice(None)
            out.append((pl.nb[part][k].copy(), pl.w[part][k].copy(), pl.g[part][k].copy()))
        return out, integ.alpha.copy(), st.rho.copy()

    followed, alpha_f, rho_f = rows()
    integ.restored()  # forget the listing: made anew at the same positions
    fresh, alpha_n, rho_n = rows()
    for (nb_f, w_f, g_f), (nb_n, w_n, g_n) in zip(followed, fresh):
        assert np.array_equal(nb_f, nb_n) and np.array_equal(w_f, w_n) and np.array_equal(g_f, g_n)
    assert sum(len(r[0]) for r in fresh) > 5 * st.n
    if plan == "scheme":
        assert np.array_equal(alpha_f, alpha_n) and np.array_equal(rho_f, rho_n)
    else:
        np.testing.assert_allclose(alpha_f, alpha_n, rtol=1e-12)
        np.testing.assert_allclose(rho_f, rho_n, rtol=1e-13)
