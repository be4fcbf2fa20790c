"""The build of :class:`sphcore.neighbours.cellgrid.CellGrid`: cell keys, their radix sort, the
occupied cells, their neighbour table and the slabs of the pair loop (numba kernels; the
data structure and how kernels walk it are described in :mod:`sphcore.neighbours.cellgrid`).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from sphcore.jit.parallel import CHUNKS, PARALLEL_MIN, serial_and_parallel

MAX_AXIS_CELLS = 1 << 21  # cells per axis; the keys of three axes then fit in an int64
MAX_SLABS = 64  # slabs of the pair loop (two phases of up to 32 parallel tasks)


def _bounding_box(pos):
    """Lower and upper corner (3,) of the points; z is 0 in 2D; NaN where a coordinate is.
    Over CHUNKS ranges of particles, merged in order (a minimum and a maximum do not
    depend on the order; a NaN in any range makes that lower corner NaN)."""
    n, dim = pos.shape
    part = np.empty((CHUNKS, 2, 3))
    for ch in prange(CHUNKS):
        lo = np.zeros(3)
        hi = np.zeros(3)
        for d in range(dim):
            lo[d] = np.inf
            hi[d] = -np.inf
        for i in range(ch * n // CHUNKS, (ch + 1) * n // CHUNKS):
            for d in range(dim):
                x = pos[i, d]
                if x < lo[d]:
                    lo[d] = x
                if x > hi[d]:
                    hi[d] = x
                if x != x:  # NaN: the box becomes NaN too (and stays: comparisons are false)
                    lo[d] = x
        for d in range(3):
            part[ch, 0, d] = lo[d]
            part[ch, 1, d] = hi[d]
    lo = np.zeros(3)
    hi = np.zeros(3)
    for d in range(dim):
        lo[d] = np.inf
        hi[d] = -np.inf
        for ch in range(CHUNKS):
            x = part[ch, 0, d]
            if x < lo[d] or x != x:
                lo[d] = x
            hi[d] = max(hi[d], part[ch, 1, d])
    return lo, hi


def _keys(pos, lo, cell_size, axes, ncell, key):
    """key[i] = mixed-radix cell index, axes[0] (major) most significant."""
    n, dim = pos.shape
    for i in prange(n):
        k = 0
        for a in range(dim):
            ax = axes[a]
            c = min(int((pos[i, ax] - lo[ax]) / cell_size), ncell[a] - 1)
            k = k * ncell[a] + c
        key[i] = k


# serial and parallel builds (the same results: sphcore.jit.parallel.serial_and_parallel); the
# build below takes the parallel ones from PARALLEL_MIN particles
_box_serial, _box_parallel = serial_and_parallel(_bounding_box)
_keys_serial, _keys_parallel = serial_and_parallel(_keys)


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

    For each row of w = 2 reach + 1 cells along the minor axis the first key wanted never
    decreases as c grows, so within a chunk of cells one pointer per row walks forward (a
    merge); a binary search starts it in each chunk (and would restart it, were the wanted
    key ever to go back: a guard, not a path taken)."""
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


neighbour_table_serial, neighbour_table_parallel = serial_and_parallel(_neighbour_table)


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
def build_cells(pos, cell_size, reach, lo, ncell, axes, key, order, tmp, count, pcell, cell_key, cell_start, slab):
    """The whole build but the neighbour table; returns (m, nslab), or
    (-1, axis cells) when the particles spread over MAX_AXIS_CELLS or more cells along an
    axis, (-2, 0) for non-finite positions. ``lo`` (3,), ``ncell`` and ``axes`` (dim,) out."""
    n, dim = pos.shape
    parallel = n >= PARALLEL_MIN
    box_lo, box_hi = _box_parallel(pos) if parallel else _box_serial(pos)
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
    if parallel:
        _keys_parallel(pos, lo, cell_size, axes, ncell, key)
    else:
        _keys_serial(pos, lo, cell_size, axes, ncell, key)
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
