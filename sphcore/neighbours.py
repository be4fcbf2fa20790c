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
(-1: empty or outside), found once per build by binary search over the keys; every kernel
walks the neighbours through it:

    c = cell_of(grid, i)
    for q in range(grid.nbr.shape[1]):
        k0, k1 = cell_range(grid, c, q)
        for k in range(k0, k1):
            j = grid.order[k]

Why cells of side 2h: cells of side h (reach 2) hold 5^dim h^dim around a particle
instead of 6^dim, 42% fewer candidate pairs in 3D, but walking four (eight) times as many,
nearly empty cells cost more than the candidates saved: measured with
``benchmarks/bench_scale.py``, one thread, 2D 10^5 particles 3.76 -> 2.09 million
particle-steps/s, 3D 10^5 0.93 -> 0.64 million, and the grid build 47 -> 333 us for 2,592
particles. ``reach`` stays a parameter (tested for 1 to 3).

Stencil index q = sum over axes (major first) of (offset + reach) w^(dim-1-a), w = 2 reach
+ 1; q = centre (the middle index) is the cell itself, q > centre are the "forward"
neighbours, so that walking the cell and its forward neighbours visits every pair of
cells once (the pair loop of :func:`sphcore.equations.sph_rates`). ``slab_start`` cuts
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
from numba import njit, prange

from .parallel import serial_and_parallel

MAX_AXIS_CELLS = 1 << 21  # cells per axis; the keys of three axes then fit in an int64
MAX_SLABS = 64  # slabs of the pair loop (two phases of up to 32 parallel tasks)
REACH = 1  # cells per search radius: cells of side 2h for the 2h support, a 3^dim stencil


class Grid(NamedTuple):
    """The arrays a kernel needs to walk neighbours: one numba argument.

    ``order`` (n,) particle indices grouped by cell; ``cell_start`` (m + 1,) CSR offsets of
    the m occupied cells; ``pcell`` (n,) the occupied cell of each particle; ``nbr``
    (m, (2 reach + 1)**dim) occupied neighbour cells (-1: none); ``slab_start`` (nslab + 1,) cell
    offsets of the slabs of the pair loop; ``lo`` (3,) lower corner (m) and ``cell_size`` (m).
    """

    order: np.ndarray
    cell_start: np.ndarray
    pcell: np.ndarray
    nbr: np.ndarray
    slab_start: np.ndarray
    lo: np.ndarray
    cell_size: float


@njit(cache=True)
def bounding_box(pos):
    """Lower and upper corner (3,) of the points; z is 0 in 2D; NaN where a coordinate is."""
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
            if x != x:  # NaN: the box becomes NaN too (and stays: comparisons are false)
                lo[d] = x
    return lo, hi


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


@njit(cache=True)
def _keys(pos, lo, cell_size, axes, ncell, key):
    """key[i] = mixed-radix cell index, axes[0] (major) most significant."""
    n, dim = pos.shape
    for i in range(n):
        k = 0
        for a in range(dim):
            ax = axes[a]
            c = min(int((pos[i, ax] - lo[ax]) / cell_size), ncell[a] - 1)
            k = k * ncell[a] + c
        key[i] = k


@njit(cache=True)
def _radix_sort(key, nbits, order, tmp, count):
    """order <- the stable permutation sorting ``key`` (non-negative, < 2**nbits): LSD radix
    sort, passes of at most 16 bits; ``tmp`` (n,) and ``count`` (>= 2**16 + 1) scratch."""
    n = key.shape[0]
    for i in range(n):
        order[i] = i
    passes = max(1, (nbits + 15) // 16)
    bits = max(1, (nbits + passes - 1) // passes)
    mask = (1 << bits) - 1
    src, dst = order, tmp
    for p in range(passes):
        shift = p * bits
        count[:mask + 2] = 0
        for i in range(n):
            count[((key[src[i]] >> shift) & mask) + 1] += 1
        for b in range(mask + 1):
            count[b + 1] += count[b]
        for i in range(n):
            b = (key[src[i]] >> shift) & mask
            dst[count[b]] = src[i]
            count[b] += 1
        src, dst = dst, src
    if passes % 2 == 1:
        for i in range(n):
            order[i] = tmp[i]


@njit(cache=True)
def _cells(key, order, cell_key, cell_start, pcell):
    """Occupied cells from the sorted keys; returns their number m."""
    n = key.shape[0]
    m = 0
    for k in range(n):
        kk = key[order[k]]
        if k == 0 or kk != cell_key[m - 1]:
            cell_key[m] = kk
            cell_start[m] = k
            m += 1
        pcell[order[k]] = m - 1
    cell_start[m] = n
    return m


@njit(cache=True, inline="always")
def _lower_bound(a, m, x):
    lo, hi = 0, m
    while lo < hi:
        mid = (lo + hi) >> 1
        if a[mid] < x:
            lo = mid + 1
        else:
            hi = mid
    return lo


PARALLEL_CELLS = 4096  # occupied cells: the neighbour table is built in parallel above
TABLE_CHUNK = 256  # cells per task of the neighbour table


def _neighbour_table(cell_key, m, ncell, dim, reach, nbr):
    """nbr[c, q]: the occupied cell at stencil offset q of cell c, or -1; offsets -reach ..
    reach per axis (compiled twice: serial below PARALLEL_CELLS occupied cells).

    For each row of w = 2 reach + 1 cells along the minor axis the first key wanted grows
    with c, so within a chunk of cells one pointer per row walks forward (a merge); a
    binary search starts it, and restarts it where the wanted key went back (a clamp at the
    edge of the grid)."""
    w = 2 * reach + 1
    nq = w ** dim
    nrow = nq // w
    nminor = ncell[dim - 1]
    for ch in prange((m + TABLE_CHUNK - 1) // TABLE_CHUNK):
        ptr = np.full(nrow, -1, np.int64)
        for c in range(ch * TABLE_CHUNK, min(m, (ch + 1) * TABLE_CHUNK)):
            # the cell's coordinates, major axis first
            k = cell_key[c]
            x_minor = k % nminor
            k //= nminor
            x_mid = 0
            if dim == 3:
                x_mid = k % ncell[1]
                k //= ncell[1]
            x_major = k
            for q in range(nq):
                nbr[c, q] = -1
            for row in range(nrow):
                o_major = row // w - reach if dim == 3 else row - reach
                o_mid = row % w - reach if dim == 3 else 0
                a = x_major + o_major
                b = x_mid + o_mid
                if a < 0 or a >= ncell[0] or (dim == 3 and (b < 0 or b >= ncell[1])):
                    continue
                base = (a * ncell[1] + b if dim == 3 else a) * nminor
                start = base + max(x_minor - reach, 0)
                p = ptr[row]
                if p < 0 or (p > 0 and cell_key[p - 1] >= start):
                    p = _lower_bound(cell_key, m, start)
                while p < m and cell_key[p] < start:
                    p += 1
                ptr[row] = p
                for off in range(-reach, reach + 1):
                    x = x_minor + off
                    if x < 0 or x >= nminor:
                        continue
                    want = base + x
                    while p < m and cell_key[p] < want:
                        p += 1
                    if p < m and cell_key[p] == want:
                        nbr[c, row * w + off + reach] = p


_table_serial, _table_parallel = serial_and_parallel(_neighbour_table)


@njit(cache=True)
def _slabs(cell_key, cell_start, m, layer_cells, reach, nslab_max, slab_start):
    """Cut the occupied cells into at most ``nslab_max`` slabs of whole major layers
    holding about equal numbers of particles (``slab_start``: first cell of each slab, then
    m); returns the number of slabs. Balanced by particles rather than layers, so that the
    even (odd) slabs of water lying on a floor split evenly between threads. Every slab
    but the last spans at least ``reach`` layers: a cell's forward neighbours reach that far
    ahead, so a slab writes into the next one only, never into the one after."""
    n = cell_start[m]
    target = n / nslab_max
    slab_start[0] = 0
    s = 1
    cum = 0
    prev = -1
    first = cell_key[0] // layer_cells if m else 0
    for c in range(m):
        layer = cell_key[c] // layer_cells
        if (c > 0 and layer != prev and layer - first >= reach and cum >= s * target
                and s < nslab_max):
            slab_start[s] = c
            s += 1
            first = layer
        cum += cell_start[c + 1] - cell_start[c]
        prev = layer
    slab_start[s] = m
    return s


@njit(cache=True)
def _build(pos, cell_size, reach, lo, ncell, axes, key, order, tmp, count, pcell, cell_key, cell_start, slab):
    """The whole build but the neighbour table; returns (m, nslab), or
    (-1, axis cells) when the particles spread over MAX_AXIS_CELLS or more cells along an
    axis, (-2, 0) for non-finite positions. ``lo`` (3,), ``ncell`` and ``axes`` (dim,) out."""
    n, dim = pos.shape
    box_lo, box_hi = bounding_box(pos)
    cells = np.ones(3, np.int64)
    for d in range(dim):
        if n == 0:
            box_lo[d] = 0.0
            box_hi[d] = 0.0
        if not (np.isfinite(box_lo[d]) and np.isfinite(box_hi[d])):
            return -2, 0
        span = (box_hi[d] - box_lo[d]) / cell_size
        if span >= MAX_AXIS_CELLS - 1:
            return -1, int(min(span, 9.0e18))
        cells[d] = int(np.floor(span)) + 1
        lo[d] = box_lo[d]
    # axes by decreasing cell count (stable: ties keep x before y before z)
    for a in range(dim):
        axes[a] = a
    for a in range(dim):
        for b in range(dim - 1 - a):
            if cells[axes[b + 1]] > cells[axes[b]]:
                axes[b], axes[b + 1] = axes[b + 1], axes[b]
    nbits = 0  # bits of the largest key: the sum over axes of ceil(log2(cells))
    for a in range(dim):
        ncell[a] = cells[axes[a]]
        b = 0
        while (1 << b) < ncell[a]:
            b += 1
        nbits += b
    _keys(pos, lo, cell_size, axes, ncell, key)
    _radix_sort(key, nbits, order, tmp, count)
    if n == 0:
        cell_start[0] = 0
        slab[0] = 0
        return 0, 0
    m = _cells(key, order, cell_key, cell_start, pcell)
    layer_cells = 1
    for a in range(1, dim):
        layer_cells *= ncell[a]
    nslab = _slabs(cell_key, cell_start, m, layer_cells, reach, MAX_SLABS, slab)
    return m, nslab


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
        m, nslab = _build(pos, self.cell_size, self.reach, self.lo, ncell, axes, self._key[:n], self._order[:n], self._tmp[:n],
                          self._count, self._pcell[:n], self._cell_key, self._start, self._slab)
        if m == -2:
            raise OverflowError("non-finite particle positions")
        if m == -1:
            raise OverflowError(f"particles spread over {nslab} cells along an axis (at most {MAX_AXIS_CELLS})")
        self.ncell, self.axes, self.ncells = ncell, axes, m
        self.order, self.pcell = self._order[:n], self._pcell[:n]
        # the table has one row per occupied cell (about n / 7 in 2D, n / 18 in 3D at h = 1.3 dx)
        self._nbr = _grow(self._nbr, m, ((2 * self.reach + 1) ** dim,))
        self.cell_key, self.cell_start, self.nbr = self._cell_key[:m], self._start[:m + 1], self._nbr[:m]
        (_table_parallel if m > PARALLEL_CELLS else _table_serial)(self.cell_key, m, ncell, dim, self.reach, self.nbr)
        self.slab_start = self._slab[:nslab + 1]
        self.view = Grid(self.order, self.cell_start, self.pcell, self.nbr, self.slab_start, self.lo, self.cell_size)
        return self

    @property
    def cell(self) -> np.ndarray:
        """(n,) the occupied cell of each particle (same as ``pcell``)."""
        return self.pcell


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
