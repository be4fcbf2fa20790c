"""Neighbour search on sorted cell keys: memory follows the particles, not the box.

Particles are binned into square/cubic cells of side ``radius / reach`` (radius: the
kernel support 2h; ``reach`` = 1 by default, so cells of side 2h). Each particle gets the
integer key of its cell on the grid over the particles' bounding box, with the axis that
has the most cells as the most significant digit (the "major" axis). A stable LSD radix
sort of the keys gives ``order`` (particle indices grouped by cell, in key order); only
the cells that hold particles are kept (``cell_start``: CSR offsets, cell c holds
``order[cell_start[c]:cell_start[c+1]]``), so a few particles far from the rest cost a few
cells, not a grid over the whole box. For every occupied cell the table ``nbr``
(m, (2 reach + 1)^dim) lists its occupied neighbour cells within ``reach`` cells per axis
(-1: empty or outside), found once per build by a merge over the sorted keys; every kernel
walks the neighbours through it:

    c = cell_of(grid, i)
    for q in range(grid.nbr.shape[1]):
        k0, k1 = cell_range(grid, c, q)
        for k in range(k0, k1):
            j = grid.order[k]

Why cells of side 2h: cells of side h (reach 2) hold 5^dim h^dim around a particle
instead of 6^dim, 42% fewer candidate pairs in 3D, but walking four (eight) times as many,
nearly empty cells cost more than the candidates saved: measured with
``benchmarks/speed/bench_scale.py``, one thread, 2D 10^5 particles 3.76 -> 2.09 million
particle-steps/s, 3D 10^5 0.93 -> 0.64 million, and the grid build 47 -> 333 us for 2,592
particles. ``reach`` stays a parameter (tested for 1 to 3).

Stencil index q = sum over axes (major first) of (offset + reach) w^(dim-1-a), w = 2 reach
+ 1; q = centre (the middle index) is the cell itself, q > centre are the "forward"
neighbours, so that walking the cell and its forward neighbours visits every pair of
cells once (the pair loop of :func:`sphcore.physics.equations.sph_rates`). ``slab_start`` cuts
the occupied cells into slabs of at least ``reach`` whole layers along the major axis,
balanced by particle count; a cell's forward neighbours lie at most ``reach`` layers
ahead, so a slab writes into itself and the next slab only, and slabs of the same parity
never touch the same particles: the pair loop runs the even slabs in parallel, then the
odd ones, race-free, and the order of the additions to each particle depends on the slabs
alone, not on the thread count.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit

from sphcore.neighbours.cellkeys import (
    MAX_AXIS_CELLS,
    MAX_SLABS,
    PARALLEL_CELLS,
    build_cells,
    neighbour_table_parallel,
    neighbour_table_serial,
)

REACH = 1  # cells per search radius: cells of side 2h for the 2h support, a 3^dim stencil


class Grid(NamedTuple):
    """The arrays a kernel needs to walk neighbours: one numba argument.

    ``order`` (n,) particle indices grouped by cell; ``cell_start`` (m + 1,) CSR offsets of
    the m occupied cells; ``pcell`` (n,) the occupied cell of each particle; ``nbr``
    (m, (2 reach + 1)**dim) occupied neighbour cells (-1: none); ``slab_start``
    (nslab + 1,) cell offsets of the slabs of the pair loop; ``pair_start`` (n + 1,) and
    ``pair_cand`` (int32): the partner candidates of a kept pair list
    (:class:`sphcore.neighbours.pairlist.PairList`), those of the particle at cell-order index k being
    ``pair_cand[pair_start[k]:pair_start[k + 1]]`` (cell-order indices); both empty for a
    grid without one (the pair loop then walks the cells).
    """

    order: np.ndarray
    cell_start: np.ndarray
    pcell: np.ndarray
    nbr: np.ndarray
    slab_start: np.ndarray
    pair_start: np.ndarray
    pair_cand: np.ndarray


@njit(cache=True, inline="always")
def cell_of(grid, i):
    """The occupied cell of particle i (an index into ``grid.nbr``)."""
    return grid.pcell[i]


@njit(cache=True, inline="always")
def cell_range(grid, c, q):
    """(k0, k1): the particles of the q-th neighbour cell of occupied cell c are
    ``grid.order[k0:k1]``; an empty range where that cell holds none."""
    c2 = grid.nbr[c, q]
    if c2 < 0:
        return 0, 0
    return grid.cell_start[c2], grid.cell_start[c2 + 1]


@njit(cache=True, inline="always")
def separation(pos, i, j, dim):
    """(x0, x1, x2, r^2): x_i - x_j (x2 = 0 in 2D) and its squared length, as every pair
    kernel computes it."""
    x0 = pos[i, 0] - pos[j, 0]
    x1 = pos[i, 1] - pos[j, 1]
    x2 = pos[i, 2] - pos[j, 2] if dim == 3 else 0.0
    return x0, x1, x2, x0 * x0 + x1 * x1 + x2 * x2


@njit(cache=True, inline="always")
def forward_rows(c, grid, dim, rows):
    """The forward stencil of occupied cell c as particle ranges, one per stencil row:
    ``order[rows[r, 0]:rows[r, 1]]``, r < the count returned; row 0 is c's own row (c and
    the cells after it along the minor axis). Returns the count.

    A row is the 2 reach + 1 cells that differ along the minor axis only: their keys are
    consecutive, so the occupied ones are consecutive occupied cells and their particles
    one contiguous range of ``order``, in the order the stencil walk visits them. Three
    cells become one loop (2D: 5 loops per particle become 2, 3D: 14 become 5).
    """
    nbr, cell_start = grid.nbr, grid.cell_start
    nq = nbr.shape[1]
    w = 1
    while w ** dim < nq:
        w += 1
    count = 0
    q = nq // 2
    while q < nq:
        row_end = (q // w + 1) * w
        first = -1
        last = -1
        for qq in range(q, row_end):
            c2 = nbr[c, qq]
            if c2 >= 0:
                if first < 0:
                    first = c2
                last = c2
        if first >= 0:
            rows[count, 0] = cell_start[first]
            rows[count, 1] = cell_start[last + 1]
            count += 1
        q = row_end
    return count


@njit(cache=True, inline="always")
def forward_pairs(k, n_dest, spos, order, rows, nrows, r2max, buf):
    """The partners j of particle i = order[k] in the pair loop: the particles after it in
    its own cell and those of the forward neighbour cells (``rows``, ``nrows``: from
    :func:`forward_rows` for k's cell) that are closer than sqrt(r2max), excluding pairs of
    two sources (i, j >= n_dest). Writes them to ``buf[:count]`` in the order of the cell
    walk and returns the count. ``spos``: the positions in cell order, ``spos[k] =
    pos[order[k]]``.

    Why a list: the distance test fails for most candidates (2D: 2 of 3, 3D: 5 of 6 with
    cells of side 2h), and as a branch in the pair loop it is mispredicted often in a
    flow (on a lattice at rest the predictor learns the pattern); here it is a branch-free
    compaction over positions contiguous in memory (the index is always stored, the count
    advances only when the test passes), and the pair loop then runs over partners only
    (``benchmarks/speed/bench_pairs.py`` measures it; docs/explanation/performance.md).
    """
    dim = spos.shape[1]
    p0 = spos[k, 0]
    p1 = spos[k, 1]
    p2 = spos[k, 2] if dim == 3 else 0.0
    count = 0
    for r in range(nrows):
        k0 = k + 1 if r == 0 else rows[r, 0]
        for k2 in range(k0, rows[r, 1]):
            d0 = p0 - spos[k2, 0]
            d1 = p1 - spos[k2, 1]
            r2 = d0 * d0 + d1 * d1
            if dim == 3:
                d2 = p2 - spos[k2, 2]
                r2 += d2 * d2
            buf[count] = k2
            count += 1 if r2 < r2max else 0
    # to particle indices; a pair of two sources (ghosts) does not interact
    fluid_i = order[k] < n_dest
    kept = 0
    for u in range(count):
        j = order[buf[u]]
        buf[kept] = j
        kept += 1 if (fluid_i or j < n_dest) else 0
    return kept


@njit(cache=True, inline="always")
def listed_pairs(k, spos, order, pair_start, pair_cand, r2max, buf):
    """The partners j of particle i = order[k] from its kept candidates (a pair list of
    :mod:`sphcore.neighbours.pairlist`): those closer than sqrt(r2max) now, in the list's order, as
    particle indices in ``buf[:count]``; returns the count. The same branch-free compaction
    as :func:`forward_pairs`, over the candidates of a skin rather than of whole cells.
    Lists are kept only for runs without plugin sources, so no pair of two sources occurs.
    The distance test is written out here as in :func:`forward_pairs`: one inline helper
    for both made this loop 20 % slower (PySPH's dam break, one thread, frozen state: 0.264
    -> 0.313-0.318 ms a call, ``benchmarks/speed/bench_pairs.py``)."""
    dim = spos.shape[1]
    p0 = spos[k, 0]
    p1 = spos[k, 1]
    p2 = spos[k, 2] if dim == 3 else 0.0
    count = 0
    for u in range(pair_start[k], pair_start[k + 1]):
        k2 = pair_cand[u]
        d0 = p0 - spos[k2, 0]
        d1 = p1 - spos[k2, 1]
        r2 = d0 * d0 + d1 * d1
        if dim == 3:
            d2 = p2 - spos[k2, 2]
            r2 += d2 * d2
        buf[count] = order[k2]
        count += 1 if r2 < r2max else 0
    return count


@njit(cache=True)
def candidates_bound(grid):
    """An upper bound on the partners :func:`forward_pairs` can return for one particle:
    the most particles of any occupied cell times the cells of the forward stencil."""
    most = 0
    cs = grid.cell_start
    for c in range(cs.shape[0] - 1):
        most = max(most, cs[c + 1] - cs[c])
    return most * (grid.nbr.shape[1] // 2 + 1)


def _grow(arr, n, tail=()):
    """``arr`` if it holds n rows, else a new array of n + n/4 rows (amortised growth)."""
    if arr.shape[0] >= n and arr.shape[1:] == tail:
        return arr
    return np.empty((n + n // 4 + 1,) + tail, arr.dtype)


class CellGrid:
    """The sorted-key cell grid of a set of points, rebuilt for every force evaluation.

    :meth:`rebuild` reuses the arrays of the previous build (they grow when needed, by a
    quarter more than asked), so a time step allocates none; ``order``, ``cell_start``,
    ``pcell``, ``nbr`` and ``view`` are views of them, valid until the next rebuild.
    Memory is O(n): a particle far from the rest adds one cell. Raises OverflowError only
    for non-finite positions or a spread of 2**21 cells or more along an axis.
    """

    def __init__(self, pos: np.ndarray, radius: float, reach: int = REACH):
        self.radius, self.reach = float(radius), int(reach)
        self.cell_size = self.radius / self.reach
        i64 = np.empty(0, np.int64)
        self._key = self._order = self._tmp = self._pcell = self._cell_key = self._start = i64
        self._nbr = np.empty((0, (2 * self.reach + 1) ** 3), np.int64)
        self._count = np.empty((1 << 16) + 2, np.int64)
        self._slab = np.empty(MAX_SLABS + 1, np.int64)
        self._no_list = (np.empty(0, np.int64), np.empty(0, np.int32))
        self.lo = np.zeros(3)
        self._ncell = np.ones(3, np.int64)
        self._axes = np.zeros(3, np.int64)
        self.rebuild(pos)

    def rebuild(self, pos: np.ndarray) -> "CellGrid":
        n, dim = pos.shape
        self._key, self._order, self._tmp, self._pcell = (_grow(a, n) for a in
                                                          (self._key, self._order, self._tmp, self._pcell))
        self._cell_key, self._start = _grow(self._cell_key, n + 1), _grow(self._start, n + 1)
        ncell, axes = self._ncell[:dim], self._axes[:dim]
        m, nslab = build_cells(pos, self.cell_size, self.reach, self.lo, ncell, axes, self._key[:n], self._order[:n],
                          self._tmp[:n], self._count, self._pcell[:n], self._cell_key, self._start, self._slab)
        if m == -2:
            raise OverflowError("non-finite particle positions")
        if m == -1:
            raise OverflowError(f"particles spread over {nslab} cells along an axis (at most {MAX_AXIS_CELLS})")
        self.ncell, self.axes, self.ncells = ncell, axes, m
        self.order, self.pcell = self._order[:n], self._pcell[:n]
        # the table has one row per occupied cell (about n / 7 in 2D, n / 18 in 3D at h = 1.3 dx)
        self._nbr = _grow(self._nbr, m, ((2 * self.reach + 1) ** dim,))
        self.cell_key, self.cell_start, self.nbr = self._cell_key[:m], self._start[:m + 1], self._nbr[:m]
        (neighbour_table_parallel if m > PARALLEL_CELLS else neighbour_table_serial)(self.cell_key, m, ncell, dim, self.reach, self.nbr)
        self.slab_start = self._slab[:nslab + 1]
        self.view = Grid(self.order, self.cell_start, self.pcell, self.nbr, self.slab_start, *self._no_list)
        return self


@njit(cache=True)
def neighbour_pairs(pos, grid, radius):
    """All pairs (i, j), i != j, closer than ``radius``, found through the cell grid.

    Used by tests and diagnostics; the force kernels walk the cells the same way without
    storing pairs.
    """
    n, dim = pos.shape
    r2max = radius * radius
    out_i = []
    out_j = []
    for i in range(n):
        c = cell_of(grid, i)
        for q in range(grid.nbr.shape[1]):
            k0, k1 = cell_range(grid, c, q)
            for k in range(k0, k1):
                j = grid.order[k]
                if j == i:
                    continue
                r2 = 0.0
                for d in range(dim):
                    dd = pos[i, d] - pos[j, d]
                    r2 += dd * dd
                if r2 < r2max:
                    out_i.append(i)
                    out_j.append(j)
    return np.array(out_i, dtype=np.int64), np.array(out_j, dtype=np.int64)
