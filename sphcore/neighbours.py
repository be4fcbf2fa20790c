"""Cell-linked-list neighbour search.

Particles are binned into square/cubic cells of side ``cell_size`` (the kernel support,
2h) and counting-sorted by cell, giving ``order`` (particle indices grouped by cell) and
``cell_start`` (CSR offsets: the particles of cell c are ``order[cell_start[c]:cell_start[c+1]]``).
A particle's neighbours within the support lie in its own and the adjacent cells. In 2D
the grid has one layer in z, so the same code serves both dimensions.
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np
from numba import njit


class Grid(NamedTuple):
    """The arrays a kernel needs to walk neighbours: one numba argument instead of five.

    ``order`` (n,) particle indices grouped by cell, ``cell_start`` (ncells + 1,) CSR
    offsets, ``lo`` (3,) lower corner (m), ``cell_size`` (m), ``ncell`` (3,) cells per axis.
    """

    order: np.ndarray
    cell_start: np.ndarray
    lo: np.ndarray
    cell_size: float
    ncell: np.ndarray


@njit(cache=True)
def bounding_box(pos):
    """Lower and upper corner (3,) of the points; z is 0 in 2D."""
    n, dim = pos.shape
    lo = np.zeros(3)
    hi = np.zeros(3)
    for d in range(dim):
        lo[d] = np.inf
        hi[d] = -np.inf
    for i in range(n):
        for d in range(dim):
            x = pos[i, d]
            if x < lo[d]:
                lo[d] = x
            if x > hi[d]:
                hi[d] = x
    return lo, hi


@njit(cache=True, inline="always")
def cell_coords(pos, i, lo, cell_size, ncell):
    """Integer cell coordinates of particle i (clamped into the grid)."""
    dim = pos.shape[1]
    cx = min(int((pos[i, 0] - lo[0]) / cell_size), ncell[0] - 1)
    cy = min(int((pos[i, 1] - lo[1]) / cell_size), ncell[1] - 1)
    cz = 0
    if dim == 3:
        cz = min(int((pos[i, 2] - lo[2]) / cell_size), ncell[2] - 1)
    return cx, cy, cz


@njit(cache=True)
def neighbour_cell(cx, cy, cz, q, ncell, dim):
    """Flat index of the q-th cell around (cx, cy, cz), or -1 when it lies outside the grid.

    q runs over ``range(3 ** dim)``: the 9 cells of the particle's layer in 2D, the 27 of
    the three layers in 3D. Kernels walk a particle's neighbours as
    ``for q in range(3 ** dim): c = neighbour_cell(...)``, then the particles
    ``order[cell_start[c]:cell_start[c + 1]]``."""
    if dim == 2:
        q += 9  # the middle layer: z = cz
    z = cz + q // 9 - 1
    if z < 0 or z >= ncell[2]:
        return -1
    y = cy + (q // 3) % 3 - 1
    if y < 0 or y >= ncell[1]:
        return -1
    x = cx + q % 3 - 1
    if x < 0 or x >= ncell[0]:
        return -1
    return x + ncell[0] * (y + ncell[1] * z)


@njit(cache=True, inline="always")
def cell_of(grid, pos, i):
    """Cell coordinates (cx, cy, cz) of particle i in ``grid``."""
    return cell_coords(pos, i, grid.lo, grid.cell_size, grid.ncell)


@njit(cache=True, inline="always")
def cell_range(grid, cx, cy, cz, q, dim):
    """(k0, k1): the particles of the q-th cell around (cx, cy, cz) are
    ``grid.order[k0:k1]``; an empty range for a cell outside the grid.

    Every kernel walks the neighbours of particle i the same way::

        cx, cy, cz = cell_of(grid, pos, i)
        for q in range(3 ** dim):
            k0, k1 = cell_range(grid, cx, cy, cz, q, dim)
            for k in range(k0, k1):
                j = grid.order[k]
    """
    c = neighbour_cell(cx, cy, cz, q, grid.ncell, dim)
    if c < 0:
        return 0, 0
    return grid.cell_start[c], grid.cell_start[c + 1]


@njit(cache=True)
def _cell_ids(pos, lo, cell_size, ncell, out):
    for i in range(pos.shape[0]):
        cx, cy, cz = cell_coords(pos, i, lo, cell_size, ncell)
        out[i] = cx + ncell[0] * (cy + ncell[1] * cz)


@njit(cache=True)
def _counting_sort(cell, ncells, order, cell_start, fill):
    """order <- particle indices grouped by cell; cell_start (ncells + 1) CSR offsets; ``fill``
    (>= ncells) is scratch."""
    cell_start[:] = 0
    for i in range(cell.shape[0]):
        cell_start[cell[i] + 1] += 1
    for c in range(ncells):
        cell_start[c + 1] += cell_start[c]
    for c in range(ncells):
        fill[c] = cell_start[c]
    for i in range(cell.shape[0]):  # stable: keeps the current order inside a cell
        c = cell[i]
        order[fill[c]] = i
        fill[c] += 1


def grid_shape(lo, hi, cell_size, dim):
    """Cells per axis (3,) int64 covering [lo, hi]."""
    ncell = np.ones(3, np.int64)
    ncell[:dim] = np.floor((hi[:dim] - lo[:dim]) / cell_size).astype(np.int64) + 1
    return ncell


class CellGrid:
    """A cell grid over a set of points, rebuilt for every force evaluation.

    :meth:`rebuild` reuses the arrays of the previous build (they grow when needed, by a
    quarter more than asked), so a time step allocates none; ``order``, ``cell_start`` and
    ``view`` are then views of them, valid until the next rebuild.
    """

    def __init__(self, pos: np.ndarray, cell_size: float):
        self.cell_size = float(cell_size)
        self._cell = self._order = np.empty(0, np.int64)
        self._start = self._fill = np.empty(0, np.int64)
        self.rebuild(pos)

    def rebuild(self, pos: np.ndarray) -> "CellGrid":
        n, dim = pos.shape
        lo, hi = bounding_box(pos)
        self.lo = lo
        self.ncell = grid_shape(lo, hi, self.cell_size, dim)
        ncells = int(np.prod(self.ncell))
        if ncells > 8 * n + 4096:
            # a few particles flew far from the rest: the grid would be mostly empty.
            raise OverflowError(f"cell grid of {ncells} cells for {n} particles")
        if self._cell.shape[0] < n:
            self._cell, self._order = np.empty(n + n // 4, np.int64), np.empty(n + n // 4, np.int64)
        if self._start.shape[0] < ncells + 1:
            self._start, self._fill = np.empty(ncells + ncells // 4 + 1, np.int64), np.empty(ncells + ncells // 4 + 1, np.int64)
        self.cell, self.order, self.cell_start = self._cell[:n], self._order[:n], self._start[:ncells + 1]
        _cell_ids(pos, lo, self.cell_size, self.ncell, self.cell)
        _counting_sort(self.cell, ncells, self.order, self.cell_start, self._fill)
        self.view = Grid(self.order, self.cell_start, self.lo, self.cell_size, self.ncell)
        return self


@njit(cache=True)
def neighbour_pairs(pos, order, cell_start, lo, cell_size, ncell, radius):
    """All pairs (i, j), i != j, closer than ``radius``, found through the cell grid.

    Used by tests and diagnostics; the force kernels walk the cells the same way without
    storing pairs.
    """
    n, dim = pos.shape
    r2max = radius * radius
    out_i = []
    out_j = []
    for i in range(n):
        cx, cy, cz = cell_coords(pos, i, lo, cell_size, ncell)
        for q in range(3 ** dim):
            c = neighbour_cell(cx, cy, cz, q, ncell, dim)
            if c < 0:
                continue
            for k in range(cell_start[c], cell_start[c + 1]):
                j = order[k]
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
