"""Sorted-key cell grid: ``CellGrid`` + ``neighbour_pairs`` against brute force, the
occupied-cell structure, the slabs of the pair loop, and spreads far beyond the water.

Point sets come from hypothesis, with coordinates drawn both from the continuum and from
exact multiples of the cell size (points on cell edges), duplicated points, a single
particle and clusters inside one cell.
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sphcore.neighbours.cellgrid import CellGrid, candidates_bound, forward_pairs, forward_rows, neighbour_pairs

CELL_SIZES = [0.1, 0.25, 0.3, 1.0, 0.013]
MAX_CELLS = 7  # per axis of the drawn point sets


def brute_force_pairs(pos: np.ndarray, radius: float) -> set[tuple[int, int]]:
    """Every ordered pair i != j with |x_i - x_j|^2 < radius^2 (same arithmetic as the kernel)."""
    n, dim = pos.shape
    r2max = radius * radius
    out = set()
    for i in range(n):
        for j in range(n):
            if i == j:
                continue
            r2 = 0.0
            for d in range(dim):
                dd = float(pos[i, d]) - float(pos[j, d])
                r2 += dd * dd
            if r2 < r2max:
                out.add((i, j))
    return out


def grid_pairs(pos: np.ndarray, search_radius: float, radius: float, reach: int = 1):
    """Pairs within ``radius`` from a grid built for ``search_radius`` (cells of side
    search_radius / reach)."""
    grid = CellGrid(pos, search_radius, reach)
    pi, pj = neighbour_pairs(pos, grid.view, radius)
    pairs = list(zip(pi.tolist(), pj.tolist()))
    assert len(pairs) == len(set(pairs)), "a pair was reported twice"
    return set(pairs), grid


@st.composite
def point_sets(draw, dim: int):
    """(points (n, dim), cell size): edges, continuum, duplicates; optionally shifted."""
    cs = draw(st.sampled_from(CELL_SIZES))
    span = MAX_CELLS - 1
    on_edge = st.integers(0, span).map(lambda k: k * cs)
    anywhere = st.floats(0.0, span * cs, allow_nan=False, allow_infinity=False)
    half_edge = st.integers(0, 2 * span).map(lambda k: 0.5 * k * cs)
    coord = st.one_of(on_edge, anywhere, half_edge)
    pts = draw(st.lists(st.tuples(*[coord] * dim), min_size=1, max_size=60))
    dups = draw(st.lists(st.integers(0, len(pts) - 1), max_size=8))
    pts = pts + [pts[i] for i in dups]
    pos = np.array(pts, dtype=np.float64).reshape(-1, dim)
    order = draw(st.permutations(range(pos.shape[0])))
    pos = pos[list(order)]
    shift = draw(st.sampled_from([0.0, -3.7, 1e3]))
    return np.ascontiguousarray(pos + shift), cs


@settings(max_examples=120, deadline=None)
@given(data=st.one_of(point_sets(2), point_sets(3)), frac=st.floats(0.05, 1.0), reach=st.sampled_from([1, 2, 3]),
       dest=st.floats(0.0, 1.0))
def test_forward_partner_lists_hold_every_pair_once(data, frac, reach, dest):
    """The pair loop's partner lists (rows of cells, the particles after each in cell
    order): over all particles every pair closer than the radius appears exactly once, no
    pair of two sources (index >= n_dest) appears, and each list keeps the order of the
    cell walk (rows and cells in stencil order, particles in ``order``)."""
    pos, cs = data
    n, dim = pos.shape
    n_dest = int(round(dest * n))
    radius = frac * cs
    grid = CellGrid(pos, cs, reach)
    view = grid.view
    spos = np.ascontiguousarray(pos[grid.order])
    rows = np.empty((view.nbr.shape[1] // 2 + 1, 2), np.int64)
    buf = np.empty(candidates_bound(view), np.int64)
    found = []
    rank = np.empty(n, np.int64)
    rank[grid.order] = np.arange(n)
    for c in range(grid.ncells):
        nrows = forward_rows(c, view, dim, rows)
        for k in range(view.cell_start[c], view.cell_start[c + 1]):
            count = forward_pairs(k, n_dest, spos, grid.order, rows, nrows, radius * radius, buf)
            i = int(grid.order[k])
            partners = buf[:count].tolist()
            found += [(min(i, j), max(i, j)) for j in partners]
            # same cell or later rows: the ranks of the own cell's partners increase
            own = [j for j in partners if grid.pcell[j] == c]
            assert [rank[j] for j in own] == sorted(rank[j] for j in own)
    assert len(found) == len(set(found)), "a pair was listed twice"
    expected = {(i, j) for i, j in brute_force_pairs(pos, radius) if i < j and (i < n_dest or j < n_dest)}
    assert set(found) == expected


@settings(max_examples=150, deadline=None)
@given(data=point_sets(2))
def test_pairs_equal_brute_force_2d(data):
    pos, cs = data
    pairs, _ = grid_pairs(pos, cs, cs)
    assert pairs == brute_force_pairs(pos, cs)


@settings(max_examples=150, deadline=None)
@given(data=point_sets(3))
def test_pairs_equal_brute_force_3d(data):
    pos, cs = data
    pairs, _ = grid_pairs(pos, cs, cs)
    assert pairs == brute_force_pairs(pos, cs)


@settings(max_examples=80, deadline=None)
@given(data=st.one_of(point_sets(2), point_sets(3)), frac=st.floats(0.05, 1.0), reach=st.sampled_from([1, 2, 3]))
def test_pairs_for_a_radius_below_the_search_radius(data, frac, reach):
    pos, cs = data
    pairs, _ = grid_pairs(pos, cs, frac * cs, reach)
    assert pairs == brute_force_pairs(pos, frac * cs)


@pytest.mark.parametrize("dim", [2, 3])
def test_single_particle_has_no_neighbour(dim):
    pos = np.full((1, dim), 0.4)
    pairs, grid = grid_pairs(pos, 0.1, 0.1)
    assert pairs == set()
    assert grid.order.tolist() == [0]
    assert int(np.prod(grid.ncell)) == 1


@pytest.mark.parametrize("dim", [2, 3])
def test_duplicated_points_are_neighbours_of_each_other(dim):
    pos = np.zeros((4, dim))  # distance 0 < radius: every ordered pair
    pos[3] += 0.5  # and one far away
    pairs, _ = grid_pairs(pos, 0.1, 0.1)
    assert pairs == {(i, j) for i in range(3) for j in range(3) if i != j}


@settings(max_examples=50, deadline=None)
@given(dim=st.sampled_from([2, 3]), seed=st.integers(0, 2**32 - 1), n=st.integers(1, 80))
def test_all_particles_in_one_cell(dim, seed, n):
    cs = 0.1
    pos = np.random.default_rng(seed).uniform(0.0, 0.99 * cs, size=(n, dim))
    pairs, grid = grid_pairs(pos, cs, cs, reach=1)
    assert int(np.prod(grid.ncell)) == 1
    assert np.all(grid.pcell == 0)
    assert pairs == brute_force_pairs(pos, cs)
    # every pair within one cell of side cs is closer than sqrt(dim) cs; all closer than cs found
    assert len(pairs) == len(brute_force_pairs(pos, cs))


def cell_coords(grid, dim):
    """(m, dim) integer coordinates of the occupied cells, per original axis."""
    out = np.zeros((grid.ncells, dim), np.int64)
    k = grid.cell_key.copy()
    for a in range(dim - 1, -1, -1):  # the key's digits, minor axis last
        out[:, grid.axes[a]] = k % grid.ncell[a]
        k //= grid.ncell[a]
    return out


@settings(max_examples=100, deadline=None)
@given(data=st.one_of(point_sets(2), point_sets(3)), reach=st.sampled_from([1, 2, 3]))
def test_sort_is_a_stable_permutation_grouped_by_occupied_cell(data, reach):
    pos, radius = data
    n, dim = pos.shape
    grid = CellGrid(pos, radius, reach)
    cs = grid.cell_size
    m = grid.ncells
    # order is a permutation of the particles
    assert sorted(grid.order.tolist()) == list(range(n))
    # CSR offsets over occupied cells only: strictly increasing from 0 to n
    assert grid.cell_start.shape == (m + 1,)
    assert grid.cell_start[0] == 0 and grid.cell_start[-1] == n
    assert np.all(np.diff(grid.cell_start) > 0)
    assert np.all(np.diff(grid.cell_key) > 0)
    # each cell's slice holds exactly its particles, in their original order (stable sort)
    assert np.all(np.diff(grid.pcell[grid.order]) >= 0)
    for c in range(m):
        members = grid.order[grid.cell_start[c]:grid.cell_start[c + 1]]
        assert members.tolist() == np.flatnonzero(grid.pcell == c).tolist()
    # each particle's cell contains it (up to the clamp of the last cell and round-off)
    idx = cell_coords(grid, dim)[grid.pcell]
    lo_corner = grid.lo[:dim] + idx * cs
    tol = 1e-9 * (1.0 + np.abs(pos))
    assert np.all(pos >= lo_corner - tol)
    assert np.all(pos <= lo_corner + cs + tol)
    # the neighbour table lists exactly the occupied cells at each stencil offset
    coords = cell_coords(grid, dim)
    where = {tuple(c): i for i, c in enumerate(coords.tolist())}
    span = list(range(-reach, reach + 1))
    offsets = np.stack(np.meshgrid(*[span] * dim, indexing="ij"), -1).reshape(-1, dim)
    assert grid.nbr.shape == (m, len(span) ** dim)
    for c in range(m):
        for q, off in enumerate(offsets):
            # q's digits run over the key's axes, major first
            o = np.zeros(dim, np.int64)
            o[grid.axes] = off
            assert grid.nbr[c, q] == where.get(tuple((coords[c] + o).tolist()), -1)


@settings(max_examples=100, deadline=None)
@given(data=st.one_of(point_sets(2), point_sets(3)), reach=st.sampled_from([1, 2, 3]))
def test_slabs_of_one_parity_never_share_a_layer(data, reach):
    """The pair loop writes to a cell's own major layers and up to ``reach`` layers ahead;
    slabs of the same parity run at once, so the layers one writes must not reach the next
    slab of its parity."""
    pos, radius = data
    dim = pos.shape[1]
    grid = CellGrid(pos, radius, reach)
    s = grid.slab_start
    assert s[0] == 0 and s[-1] == grid.ncells and np.all(np.diff(s) > 0)
    major = cell_coords(grid, dim)[:, grid.axes[0]]
    first = [major[s[k]] for k in range(len(s) - 1)]  # first layer of each slab
    last = [major[s[k + 1] - 1] for k in range(len(s) - 1)]  # its last occupied layer
    for k in range(len(s) - 2):
        assert last[k] < first[k + 1]  # whole layers
    for k in range(len(s) - 3):
        assert last[k] + reach < first[k + 2]  # what slab k writes stops before slab k + 2


def test_far_flung_particle_costs_one_cell():
    """A particle 10^4 m from the rest (10^6 cells away) adds one occupied cell, not a
    grid over the box; pairs stay right."""
    pos = np.array([[0.001, 0.0], [0.004, 0.0], [1e4, 1e4]])  # the first two share a cell
    pairs, grid = grid_pairs(pos, 0.01, 0.01)
    assert grid.ncells == 2
    assert pairs == {(0, 1), (1, 0)}


def test_spread_beyond_two_million_cells_or_non_finite_overflows():
    with pytest.raises(OverflowError, match="cells along an axis"):
        CellGrid(np.array([[0.0, 0.0], [1e5, 0.0]]), 0.01)
    with pytest.raises(OverflowError, match="non-finite"):
        CellGrid(np.array([[0.0, 0.0], [np.nan, 0.0]]), 0.01)
