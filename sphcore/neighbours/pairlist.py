"""Kept pair lists (Verlet lists): the pair loop's partner candidates, found once and
reused while no particle has moved more than half a skin.

Without a list the pair loop finds each particle's partners every evaluation by walking
its cell and the forward neighbour cells (cells of side 2h) and testing every candidate:
in 2D three candidates per partner, in 3D six, plus the cell grid's build (sort, table).
A :class:`PairList` builds a cell grid with cells of side 2h + s (s: the skin) and stores,
for every particle, the forward candidates closer than 2h + s (CSR, cell-order indices,
in the order of the cell walk). While every particle is within s/2 of where it was at the
build, every pair closer than 2h now was closer than 2h + s then (two particles close in
by at most s), so the pair loop tests only the stored candidates
(:func:`sphcore.neighbours.cellgrid.listed_pairs`; (1 + s / 2h)^dim candidates per partner at most,
1.44 in 2D and 1.73 in 3D for the default s = 0.2 (2h)) and no grid is built (Verlet 1967;
Allen & Tildesley, *Computer Simulation of Liquids*, 2nd ed. 2017, section 5.3.1).

Why it keeps the results exact: a listed pair beyond 2h is not a partner (the distance
test is the one of the walk), and every partner is listed; only the order of a particle's
additions can differ from a fresh walk's (the list keeps the order of its build), so the
results are those of the pair loop to round-off, and for a given build they do not depend
on the thread count: the lists are cut into the build grid's slabs, whose race-free
schedule (see :mod:`sphcore.neighbours.cellgrid`) holds as long as the list is kept, since it is
written in particle indices. A restart rebuilds the list from the positions of the last
build (saved in the checkpoint), so it continues bit for bit.

The rule to rebuild is geometric only (a particle more than s/2 from its position at the
build, or another particle count), so anything that moves particles (the integrator, a
wall's reflection, a plugin) keeps the lists valid; the core's reorder puts the particles
in the list's own cell order (:meth:`PairList.follow`), which the list survives. Runs with
plugin source particles (ghosts, whose set changes every step) walk the cells instead.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from sphcore.jit.parallel import by_size, serial_and_parallel
from sphcore.neighbours.cellgrid import CellGrid, Grid, forward_rows

BUILD_PARALLEL_MIN = 1000  # particles: the list build runs parallel from here


def _moved(pos, ref, limit2):
    """How many particles are farther than sqrt(limit2) from ``ref`` (an integer sum: the
    same for any thread count)."""
    n, dim = pos.shape
    far = 0
    for i in prange(n):
        d2 = 0.0
        for d in range(dim):
            x = pos[i, d] - ref[i, d]
            d2 += x * x
        far += 1 if d2 > limit2 else 0
    return far


def _find_candidates(spos, grid, r2, start, cand, fill):
    """Per particle (cell-order index k) its forward candidates closer than sqrt(r2):
    their count in ``start[k + 1]`` (``fill`` false), or (``fill`` true, ``start`` the CSR
    offsets from the counts) the candidates themselves in ``cand[start[k]:start[k + 1]]``,
    in the order of :func:`sphcore.neighbours.cellgrid.forward_pairs`' walk. Branch-free, as that
    walk (the index is written, the count advances when the test passes; the fill stops
    when the particle's row is full, so it writes nothing beyond it). Cells in parallel
    (each writes only its own particles' rows)."""
    dim = spos.shape[1]
    cell_start = grid.cell_start
    nrow = grid.nbr.shape[1] // 2 + 1
    for c in prange(cell_start.shape[0] - 1):
        rows = np.empty((nrow, 2), np.int64)
        nrows = forward_rows(c, grid, dim, rows)
        for k in range(cell_start[c], cell_start[c + 1]):
            p0 = spos[k, 0]
            p1 = spos[k, 1]
            p2 = spos[k, 2] if dim == 3 else 0.0
            u = start[k] if fill else 0
            end = start[k + 1] if fill else 0
            for r in range(nrows):
                if fill and u >= end:
                    break
                k0 = k + 1 if r == 0 else rows[r, 0]
                for k2 in range(k0, rows[r, 1]):
                    d0 = p0 - spos[k2, 0]
                    d1 = p1 - spos[k2, 1]
                    d2 = p2 - spos[k2, 2] if dim == 3 else 0.0
                    near = d0 * d0 + d1 * d1 + d2 * d2 < r2
                    if fill:
                        if u >= end:
                            break
                        cand[u] = k2
                    u += 1 if near else 0
            if not fill:
                start[k + 1] = u


_moved = by_size(_moved)
# the build tests every candidate of the cells of side 2h + s, twice (count, fill): work per
# particle like the pair loop's, so parallel from the same size, not from the element-wise
# passes' PARALLEL_MIN
_candidates_serial, _candidates_parallel = serial_and_parallel(_find_candidates)


def _candidates(spos, grid, r2, start, cand, fill):
    """:func:`_find_candidates`, parallel from BUILD_PARALLEL_MIN particles."""
    kernel = _candidates_parallel if spos.shape[0] >= BUILD_PARALLEL_MIN else _candidates_serial
    kernel(spos, grid, r2, start, cand, fill)


class PairList:
    """The pair list of one run's fluid (see the module docstring). ``support``: 2h (m);
    ``skin``: s (m), > 0."""

    def __init__(self, support: float, skin: float):
        self.support, self.skin = float(support), float(skin)
        self.cells: CellGrid | None = None
        self.view: Grid | None = None
        self.pos_ref = np.zeros((0, 0))  # positions at the last build
        self.builds = 0
        self._valid = False
        self._restored = False
        self._followed = False
        self._start = np.zeros(1, np.int64)
        self._cand = np.zeros(0, np.int32)
        self._spos = np.zeros((0, 0))
        self._order = self._pcell = self._identity = np.zeros(0, np.int64)  # after follow()

    def ready(self, pos: np.ndarray) -> bool:
        """Is a list of these particles kept (built, or to be rebuilt from a restart's
        positions: then built now, as the interrupted run had it)?"""
        if self._restored and self.pos_ref.shape == pos.shape:
            self._build(self.pos_ref)
            self._restored = False
        return self._valid and self.pos_ref.shape == pos.shape

    def invalidate(self):
        """The particles were reordered otherwise than by :meth:`follow`: rebuild at the next use."""
        self._valid = False

    @property
    def sorted(self) -> bool:
        """Are the particles in this list's cell order already (:meth:`follow` since the build)?"""
        return self._followed

    def follow(self, order: np.ndarray):
        """The particles were put in the order of this list's grid (new index k = old index
        ``order[k]``, ``order`` = ``self.view.order``): the lists stay valid as they are (they
        hold cell-order indices), the grid's order becomes the identity and the positions of
        the build are permuted alike. A build from those positions gives the same lists,
        which keeps restarts bit for bit."""
        n = order.shape[0]
        np.take(self.pos_ref, order, axis=0, out=self._spos[:n], mode="clip")
        self.pos_ref[:] = self._spos[:n]
        np.take(self.view.pcell, order, out=self._pcell[:n], mode="clip")
        self._order[:n] = self._identity[:n]
        v = self.view
        self.view = Grid(self._order[:n], v.cell_start, self._pcell[:n], v.nbr, v.slab_start, v.pair_start,
                         v.pair_cand)
        self._followed = True

    def checkpoint(self) -> np.ndarray | None:
        """The positions of the last build, or those a restart will build from (None: no
        list kept), for a checkpoint: a checkpoint written before the restarted run's first
        evaluation carries the same anchor as the one it restarted from."""
        return self.pos_ref if self._valid or self._restored else None

    def restore(self, pos_ref: np.ndarray):
        """Continue a run: the next :meth:`view_of` rebuilds from these positions first."""
        self.pos_ref = np.array(pos_ref, dtype=np.float64)
        self._restored = True

    def view_of(self, pos: np.ndarray) -> tuple[Grid, bool]:
        """(the grid view with the lists of ``pos``, whether they were rebuilt now). Raises
        OverflowError as :class:`sphcore.neighbours.cellgrid.CellGrid` does."""
        rebuilt = self._restored
        self.ready(pos)
        self._restored = False
        half = 0.5 * self.skin
        if (not self._valid or self.pos_ref.shape != pos.shape
                or _moved(pos, self.pos_ref, half * half) > 0):
            self._build(pos)
            rebuilt = True
        return self.view, rebuilt

    def _build(self, pos):
        n, dim = pos.shape
        if self.pos_ref.shape != pos.shape:
            self.pos_ref = np.empty_like(pos)
        if self.pos_ref is not pos:
            self.pos_ref[:] = pos
        reach = self.support + self.skin
        if self.cells is None:
            self.cells = CellGrid(self.pos_ref, reach)
        else:
            self.cells.rebuild(self.pos_ref)
        cells = self.cells
        if self._spos.shape[0] < n or self._spos.shape[1] != dim:
            self._spos = np.empty((n + n // 4 + 1, dim))
            self._start = np.zeros(n + n // 4 + 2, np.int64)
            self._order, self._pcell = np.empty(n + n // 4 + 1, np.int64), np.empty(n + n // 4 + 1, np.int64)
            self._identity = np.arange(n + n // 4 + 1, dtype=np.int64)
        spos, start = self._spos[:n], self._start[:n + 1]
        np.take(self.pos_ref, cells.order, axis=0, out=spos, mode="clip")
        r2 = reach * reach
        start[0] = 0
        _candidates(spos, cells.view, r2, start, self._cand, False)
        np.cumsum(start, out=start)
        total = int(start[n])
        if self._cand.shape[0] < total:
            self._cand = np.empty(total + total // 4 + 1, np.int32)
        _candidates(spos, cells.view, r2, start, self._cand, True)
        v = cells.view
        self.view = Grid(v.order, v.cell_start, v.pcell, v.nbr, v.slab_start, start, self._cand[:total])
        self._valid = True
        self._followed = False
        self.builds += 1
