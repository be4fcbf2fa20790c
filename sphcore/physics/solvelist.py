"""The incompressible scheme's pair list as one object: its rows, the cells it was binned
into, the state it was listed at, and how it follows a reordering of the particles.

The kernels that build the list are in :mod:`sphcore.physics.pairfill`, those that walk it
in :mod:`sphcore.physics.solvepairs`; what the scheme derives from it (the summed density,
the diagonal, the walls' terms) is in :mod:`sphcore.physics.incompressible`.
"""

from __future__ import annotations

import numba
import numpy as np

from sphcore.errors import Instability
from sphcore.physics import pairfill as pf
from sphcore.physics import solvepairs as sp
from sphcore.physics.kernels import SUPPORT, lattice_nodes
from sphcore.physics.particles import StateMark

# each row of the pair list holds the particle's partners at the last listing and this share of
# a full neighbourhood more (at least 2): a row that overflows repeats the step's walk (the 3D
# dam break at h = dx: 97 of 380 listings overflowed with 0.125, none with 0.25)
ROW_ROOM = 0.25


class SolveList:
    """Particle i's partners ``nb[start[i]:end[i]]`` with W_ij (``w``) and grad_i W_ij
    (``g``), listed at the positions and particle order :attr:`mark` holds; ``counts`` the
    partners at the last listing (the next rows' capacities), ``n_full`` a full
    neighbourhood's partners on the initial lattice. ``prm``: the run's Params; ``ctx``:
    the run context (clock and counters, for messages)."""

    def __init__(self, prm, ctx):
        self.prm, self.ctx = prm, ctx
        _, r = lattice_nodes(prm.h, prm.dx, prm.dim)
        self.n_full = int(np.count_nonzero(r < SUPPORT * prm.h))
        self.room = max(2, int(ROW_ROOM * self.n_full))
        self.mark = StateMark()  # the positions and ids the pairs were listed at
        self.resize(0)

    def resize(self, n):
        dim = self.prm.dim
        self.cell = np.zeros(n, np.int64)
        self.order = np.zeros(n, np.int64)
        self.cell_start = np.zeros(1, np.int64)
        self.counts = np.full(n, self.n_full, np.int64)
        self.start = np.zeros(n, np.int64)
        self.end = np.zeros(n, np.int64)
        self.caps = np.zeros(n, np.int64)
        self.new_index = np.zeros(n, np.int64)  # a reorder's new number of each particle
        self.spos = np.zeros((n, dim))
        self.nb = np.zeros(0, np.int32)
        self.w = np.zeros(0)
        self.g = np.zeros((0, dim))
        self.mark.clear()

    def bin(self, st):
        """The particles binned into cells of the support's size (``cell``, ``order``,
        ``cell_start``); returns the cells per axis."""
        try:
            self.cell_start, nc0, nc1, nc2 = pf.bin_cells(st.pos, SUPPORT * self.prm.h, self.cell, self.order,
                                                          self.cell_start)
        except Exception as e:  # a particle far away: a grid too large to allocate
            raise Instability(self.ctx.step, self.ctx.t, -1, f"neighbour search failed: {e}") from None
        return nc0, nc1, nc2

    def fill(self, st):
        """List the pairs of the current positions (the mark is set by the caller, once what
        it derives from them is done)."""
        nc0, nc1, nc2 = self.bin(st)
        while True:
            self._rows()
            sp.run_pass(pf.fill_pairs, st.pos, self.spos, SUPPORT * self.prm.h, self.order, self.cell_start, nc0, nc1,
                        nc2, self.prm.kernel_id, self.prm.h, self.start, self.caps, self.nb, self.w, self.g,
                        self.counts, numba.get_num_threads())
            if not np.any(self.counts > self.caps):
                break
            self.ctx.counters["dfsph_pair_overflows"] += 1  # a row overflowed: the walk again, rows from its counts
        np.add(self.start, self.counts, out=self.end)

    def plan(self, st):
        """The particles in the order of the list's cells (the last listing's, when it holds
        the current positions), or None when they are in it: after the reorder a new listing
        gives each row in the order the renumbered one has (cell by cell, within a cell by
        number, which the reorder keeps), so that a run restarted from a checkpoint, which
        lists its pairs anew, adds the same terms in the same order."""
        if not self.mark.holds(st):
            self.bin(st)
        if np.all(self.order[1:] > self.order[:-1]):
            return None
        return self.order.copy()

    def permute(self, order):
        """Follow a reordering of the particles: particle k's row is the old row of
        ``order[k]``, where it lies (the rows are no longer in particle order until the next
        listing), its partners renumbered; the cells' order and the mark follow too (``cell``
        is the binning's scratch, read by nothing after it)."""
        for a in (self.counts, self.start, self.end):
            a[...] = a[order]
        self.new_index[order] = np.arange(order.shape[0])
        sp.run_pass(pf.renumber, self.start, self.end, self.nb, self.new_index)
        # the cells' order in the new numbers (the identity after the list's own plan), so that
        # a second reorder before the next listing (positions that did not change) finds none
        self.order[...] = self.new_index[self.order]
        self.mark.permute(order)

    def _rows(self):
        """Each particle's row sized to its partners at the last listing and ROW_ROOM more
        (:func:`sphcore.physics.pairfill.row_starts`); the list's arrays grow when short."""
        np.add(self.counts, self.room, out=self.caps)
        size = pf.row_starts(self.caps, self.start)
        if self.nb.shape[0] < size:
            size += size // 8
            self.nb = np.zeros(size, np.int32)
            self.w = np.zeros(size)
            self.g = np.zeros((size, self.prm.dim))
