"""Kept pair lists (:mod:`sphcore.neighbours.pairlist`): the pair loop over a list built up to half a
skin ago gives the rates of a fresh cell walk (to round-off: only the order of a particle's
additions may differ), every pair within 2h is listed while no particle has moved more than
half the skin, the list follows a reorder into its own cell order unchanged, and a run
restarted from a checkpoint taken while a list is kept continues bit for bit."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from conftest import by_id, make_sim, write_case
from core_cases import colliding
from hypothesis import given, settings
from hypothesis import strategies as st

from sphcore.neighbours.cellgrid import CellGrid, neighbour_pairs
from sphcore.neighbours.pairlist import PairList
from sphcore.physics.equations import WallTerms, sph_rates
from sphcore_plugins.wall_integral.completion import complete_at_wall
from sphcore.physics.pairterms import WORK_COLUMNS
from sphcore.physics.particles import Fields
from sphcore.run import runner
from sphcore.testing import case_with


def _cloud(dim, side, seed, dx=0.02):
    """A jittered lattice of particles with random velocities, densities, pressures, masses."""
    rng = np.random.default_rng(seed)
    lattice = np.stack(np.meshgrid(*[np.arange(side) * dx] * dim, indexing="ij"), -1).reshape(-1, dim)
    n = lattice.shape[0]
    pos = lattice + rng.uniform(-0.3, 0.3, lattice.shape) * dx
    return rng, Fields(np.ascontiguousarray(pos), rng.normal(0.0, 0.5, (n, dim)),
                       1000.0 * (1.0 + rng.uniform(-0.02, 0.02, n)), rng.uniform(-50.0, 400.0, n),
                       1000.0 * dx ** dim * (1.0 + rng.uniform(-0.1, 0.1, n)))


def _params(tmp_path, dim, dx=0.02):
    from core_cases import blob

    prm = make_sim(write_case(tmp_path / "blob", blob())).params
    h = 1.3 * dx
    gravity = np.zeros(3)
    gravity[dim - 1] = -9.81
    return prm._replace(dim=dim, h=h, support=2.0 * h, alpha=0.3, beta=0.2, nu=1e-3, delta=0.1,
                        diffusion_hydrostatic=True, eta2=0.01 * h * h, c0=20.0, gravity=gravity,
                        kernel_gradient=False, modified_pressure=False)


def _walls(n, dim, seed, active):
    """Wall terms on about 40 % of the particles (random), as tests/test_core_pairs.py: their
    near-wall sums are accumulated from both sides of each pair; or none."""
    if not active:
        return WallTerms(np.zeros(n), np.zeros((n, dim)), np.zeros((n, dim)), np.zeros((n, dim, dim)), np.zeros(n),
                         False)
    rng = np.random.default_rng(seed)
    share = np.where(rng.uniform(0, 1, n) < 0.4, rng.uniform(0.01, 0.3, n), 0.0)
    e = rng.normal(size=(n, dim))
    e /= np.linalg.norm(e, axis=1)[:, None]
    return WallTerms(share, rng.normal(0, 50.0, (n, dim)), rng.normal(0, 1.0, (n, dim)),
                     np.einsum("ni,nj->nij", e, e), rng.uniform(0.5, 1.5, n), True)


def _rates(src, view, prm, wall=None):
    n, dim = src.pos.shape
    wall = wall if wall is not None else _walls(n, dim, 0, False)
    acc, drho = np.zeros((n, dim)), np.zeros(n)
    sph_rates(n, src, view, prm, np.zeros((1, 3, 3)), wall, acc, drho, np.zeros((n, WORK_COLUMNS)),
              np.zeros_like(src.pos), numba.get_num_threads(), complete_at_wall)
    return acc, drho


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("walls", [False, True])
def test_a_kept_list_gives_the_rates_of_a_fresh_walk_until_half_the_skin(tmp_path, dim, walls):
    prm = _params(tmp_path, dim)._replace(moment_norm=0.97, rho_ref=1000.0)
    rng, src = _cloud(dim, 14 if dim == 2 else 7, 5 + dim)
    skin = 0.3 * prm.support
    pairs = PairList(prm.support, skin)
    view, rebuilt = pairs.view_of(src.pos)
    assert rebuilt and view.pair_start.shape[0] == src.pos.shape[0] + 1
    # every particle moves by just under half the skin in a random direction
    step = rng.normal(size=src.pos.shape)
    step *= 0.499 * skin / np.linalg.norm(step, axis=1)[:, None]
    moved = src._replace(pos=np.ascontiguousarray(src.pos + step))
    view, rebuilt = pairs.view_of(moved.pos)
    assert not rebuilt  # the list is kept
    wall = _walls(moved.pos.shape[0], dim, 1, walls)
    acc, drho = _rates(moved, view, prm, wall)
    ref_acc, ref_drho = _rates(moved, CellGrid(moved.pos, prm.support).view, prm, wall)
    assert np.abs(acc - ref_acc).max() <= 1e-12 * np.abs(ref_acc).max()
    assert np.abs(drho - ref_drho).max() <= 1e-12 * np.abs(ref_drho).max()
    # one particle beyond half the skin: rebuilt
    far = moved.pos.copy()
    far[0] += 0.502 * skin * np.eye(dim)[0] - step[0]
    assert pairs.view_of(far)[1]


def _listed(view):
    """The set of (i, j), i < j, held as candidates by a pair-list view."""
    out = set()
    order = view.order
    for k in range(view.pair_start.shape[0] - 1):
        for u in range(view.pair_start[k], view.pair_start[k + 1]):
            i, j = int(order[k]), int(order[view.pair_cand[u]])
            out.add((min(i, j), max(i, j)))
    return out


@settings(max_examples=40, deadline=None)
@given(seed=st.integers(0, 2**32 - 1), dim=st.sampled_from([2, 3]), skin=st.floats(0.01, 1.0),
       spread=st.floats(0.0, 3.0))
def test_every_pair_within_the_support_is_listed_while_no_particle_moved_half_the_skin(seed, dim, skin, spread):
    rng = np.random.default_rng(seed)
    n = 60 if dim == 2 else 90
    support = 1.0
    pos = rng.uniform(0.0, 2.0 + spread, (n, dim))
    pairs = PairList(support, skin * support)
    view, _ = pairs.view_of(pos)
    step = rng.normal(size=pos.shape)
    step *= rng.uniform(0.0, 0.5, (n, 1)) * skin * support / np.linalg.norm(step, axis=1)[:, None]
    moved = pos + step
    view, rebuilt = pairs.view_of(moved)
    assert not rebuilt
    listed = _listed(view)
    i, j = neighbour_pairs(moved, CellGrid(moved, support).view, support)
    assert {(a, b) for a, b in zip(i, j) if a < b} <= listed
    # and nothing farther than the support plus the skin at the build
    for a, b in listed:
        assert np.linalg.norm(pos[a] - pos[b]) < support * (1 + skin)


@pytest.mark.parametrize("dim", [2, 3])
def test_a_reorder_into_the_lists_cell_order_keeps_the_list_and_a_rebuild_gives_the_same(tmp_path, dim):
    prm = _params(tmp_path, dim)
    rng, src = _cloud(dim, 12 if dim == 2 else 6, 3)
    pairs = PairList(prm.support, 0.3 * prm.support)
    view, _ = pairs.view_of(src.pos)
    acc, drho = _rates(src, view, prm)
    order = view.order.copy()
    assert not np.array_equal(order, np.arange(order.size))  # a real permutation
    sorted_src = Fields(*(np.ascontiguousarray(a[order]) for a in src))
    pairs.follow(order)
    view2, rebuilt = pairs.view_of(sorted_src.pos)
    assert not rebuilt and pairs.sorted and np.array_equal(view2.order, np.arange(order.size))
    acc2, drho2 = _rates(sorted_src, view2, prm)
    assert np.array_equal(acc2, acc[order]) and np.array_equal(drho2, drho[order])  # the same bits
    # a new list built from the permuted positions of the build: the same lists (a restart)
    fresh = PairList(prm.support, 0.3 * prm.support)
    fresh.restore(pairs.checkpoint())
    view3, _ = fresh.view_of(sorted_src.pos)
    for name in ("order", "cell_start", "pcell", "slab_start", "pair_start", "pair_cand"):
        assert np.array_equal(getattr(view3, name), getattr(view2, name)), name


@pytest.mark.parametrize("skin", [0.0, 0.004, 0.3])
@pytest.mark.parametrize("at", [14, 15])
def test_restart_with_a_kept_list_is_bit_for_bit(tmp_path, skin, at):
    """A restart in the middle of a list's life (the checkpoint's positions are not those of
    the last build) continues as the uninterrupted run, also when its first step reorders
    (at = 14, sort_every = 7); skin 0.004 rebuilds every few steps."""
    dt = 2.0**-13
    t_end, t1 = 40 * dt, at * dt
    case = case_with(colliding(), {"time.t_end": t_end, "time.dt": dt, "neighbours": {"skin": skin, "sort_every": 7}})
    case_dir = write_case(tmp_path / "case", case)
    full = runner.run(case_dir, output=tmp_path / "full", quiet=True)
    part = runner.run(case_dir, output=tmp_path / "part", t_end=t1, quiet=True)
    sim = part.simulation
    if skin > 0:
        assert sim.forces.pairs.ready(sim.state.pos)
        builds = full.simulation.counters["pair_list_builds"]  # the run's own, the look-ahead's not counted
        if skin < 0.01:
            assert builds > 5
        else:  # one build: the checkpoint's positions are not those of the build
            assert builds == 1 and not np.array_equal(sim.forces.pairs.pos_ref, sim.state.pos)
    else:
        assert sim.forces.pairs is None
    rest = runner.run(case_dir, output=tmp_path / "part", t_end=t_end, restart=True, quiet=True)
    a, b = full.simulation, rest.simulation
    assert a.step == b.step == 40
    sa, sb = by_id(a.state), by_id(b.state)
    for name in sa:
        assert np.array_equal(sa[name], sb[name]), name


def test_a_restart_that_takes_no_step_keeps_the_lists_anchor(tmp_path):
    """Restarting a completed run at its own t_end takes no step but rewrites the
    checkpoint: the rewritten one must carry the pair list's anchor, so that a later
    extension continues as an extension of the run without that restart, bit for bit."""
    dt = 2.0**-13
    t1, t2 = 15 * dt, 40 * dt
    case = case_with(colliding(), {"time.t_end": t2, "time.dt": dt, "neighbours.skin": 0.3})
    case_dir = write_case(tmp_path / "case", case)
    for name in ("plain", "noop"):
        runner.run(case_dir, output=tmp_path / name, t_end=t1, quiet=True)
    noop = runner.run(case_dir, output=tmp_path / "noop", t_end=t1, restart=True, quiet=True)
    assert noop.status == "completed" and noop.simulation.step == 15
    with np.load(tmp_path / "noop" / "checkpoint.npz") as z:
        assert "pair_list_positions" in z.files
    a = runner.run(case_dir, output=tmp_path / "plain", t_end=t2, restart=True, quiet=True).simulation
    b = runner.run(case_dir, output=tmp_path / "noop", t_end=t2, restart=True, quiet=True).simulation
    assert a.step == b.step == 40
    sa, sb = by_id(a.state), by_id(b.state)
    for name in sa:
        assert np.array_equal(sa[name], sb[name]), name
