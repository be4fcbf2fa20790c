"""The divergence-free scheme (sphcore.physics.incompressible) run on small columns and
droplets: the keys it refuses, restarts bit for bit, no particle outside the walls, no
energy gained in a collision, the solves' error measures and last step, its shortcuts and
its pair list (the rates summed over it, a reorder renumbering it, the walls' density after
the start-up probe)."""

from __future__ import annotations

import numpy as np
import pytest

from sphcore.testing import run_case


def test_dfsph_refuses_the_keys_it_cannot_honour(tmp_path):
    from sphcore.testing import tiny_case, case_with

    base = case_with(tiny_case(), {"scheme.name": "dfsph"})
    for key, value, named in [("physics.modified_pressure", True, "physics.modified_pressure"),
                              ("corrections.shepard_every", 5, "corrections.shepard_every"),
                              ("physics.sph", False, "scheme.name"),
                              ("plugins.use", ["ghost", "reflective"], "plugins.use"),
                              ("plugins.use", ["reflective", "free_surface"], "plugins.use"),
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
    # numba cached its kernels: the next run does not say it compiles them
    assert runner.kernels_cached(2, "dfsph")


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


@pytest.mark.parametrize("dim", [2, 3])
def test_a_carried_tank_s_loads_hold_the_solved_pressure_and_balance_its_water(tmp_path, dim):
    """A layer of water at rest in a tank carried at 0.5 m/s, dfsph with the wall model:
    the walls' part of the solved pressure is given as kicks, outside the rates, and the
    tank's load adds it (ctx.solved_impulse). The loads integrated over the run equal
    M g T minus the water's change of momentum to round-off, as with the weakly
    compressible scheme; without the solved part they held the walls' hydrostatic push
    alone (0.22 of the weight in 2D). At rest in the tank's (inertial) frame the vertical
    load is the weight (within 1 % on average; measured 1.0016 in 2D, 0.9998 in 3D) and
    acts at the layer's centre: its moment about the tank's corner (its reference point,
    carried with it) is that of the weight there (within 1 %)."""
    from conftest import write_case

    from sphcore.run import runner
    from sphcore_plugins.wall_loads import read_loads

    out = tmp_path / "out"
    u = np.zeros(dim)
    u[0] = 0.5
    size = np.array([1.0, 0.1]) if dim == 2 else np.array([0.3, 0.06, 0.1])
    top = size.copy()
    top[1] = 1.0 if dim == 2 else 0.2
    case = {"case": {"dim": dim},
            "domain": {"min": [0.0] * dim, "max": top.tolist(),
                       "motion": [{"type": "constant_velocity", "velocity": u.tolist()}]},
            "blocks": [{"min": [0.0] * dim, "max": size.tolist(), "velocity": u.tolist()}],
            "particles": {"dx": 0.02 if dim == 2 else 0.01}, "time": {"t_end": 0.2}, "scheme": {"name": "dfsph"},
            "plugins": {"use": ["reflective", "wall_integral", "wall_loads"]}, "wall_loads": {"every_dt": 0.01}}
    result = runner.run(write_case(tmp_path / "carried", case), output=out, quiet=True)
    assert result.status == "completed", result["message"]
    st = result.simulation.state
    mass = float(st.m.sum())
    weight = np.zeros(dim)
    weight[1] = -mass * 9.81
    t, loads = read_loads(out / "wall_loads.nc")
    assert t[-1] == pytest.approx(0.2, abs=1e-12)
    integral = (loads[1:, 0, :dim] * np.diff(t)[:, None]).sum(axis=0)
    change = (st.m[:, None] * st.vel).sum(axis=0) - mass * u
    np.testing.assert_allclose(integral, weight * t[-1] - change, rtol=0, atol=1e-9 * mass * 9.81 * t[-1])
    assert loads[1:, 0, 1].mean() == pytest.approx(weight[1], rel=0.01)
    centre = np.zeros(3)
    centre[:dim] = 0.5 * size
    moment = np.cross(centre, np.append(weight, [0.0] * (3 - dim)))  # the weight at the layer's centre
    np.testing.assert_allclose(loads[1:, 0, 3:].mean(axis=0), moment, rtol=0, atol=0.01 * np.abs(moment).max())
