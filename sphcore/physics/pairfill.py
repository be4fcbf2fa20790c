"""The incompressible scheme's pair list built: the rows of every particle's partners with
W_ij and grad_i W_ij that the passes of :mod:`sphcore.physics.solvepairs` sweep, and their
renumbering after a reorder (the list as one object: :mod:`sphcore.physics.solvelist`).

Each row's capacity is its particle's count at the last listing and some room
(:func:`row_starts`), so the rows lie close together: the passes stream the list from
memory, and their time follows its size (rows of a fixed capacity of one and a half full
neighbourhoods took twice as long a pass in 3D).

The list is built by binning the particles into cells of the support's size (a counting
sort); the particles of a cell share their candidates, the 3^dim cells around it, and each
writes its partners into its row in the candidates' order. A row that overflows its capacity
is counted to the end and the walk repeated with capacities from the counts. Rows hold the
partners cell by cell, in the cells' sorted order: the list depends on the positions and
the particles' order only.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from sphcore.physics.kernels import kernel_f, kernel_w


def row_starts(caps, start) -> int:
    """Rows of ``caps[i]`` pairs one after another: ``start[i]`` = caps[0] + ... + caps[i-1]
    (in place); returns the list's length."""
    if caps.shape[0] == 0:
        return 0
    start[0] = 0
    np.cumsum(caps[:-1], out=start[1:])
    return int(start[-1] + caps[-1])


@njit(cache=True)
def bin_cells(pos, support, cell, order, cell_start):
    """Counting sort of the particles into cells of side ``support`` over their bounding
    box: ``cell`` (n,) each particle's cell, ``order`` (n,) the particles cell by cell,
    ``cell_start`` the rows of each cell in ``order`` (returned, with the cells per axis
    as (nc0, nc1, nc2))."""
    n, dim = pos.shape
    lo = np.empty(3)
    hi = np.empty(3)
    for d in range(3):
        lo[d] = 0.0
        hi[d] = 0.0
    for d in range(dim):
        lo[d] = pos[0, d]
        hi[d] = pos[0, d]
    for i in range(n):
        for d in range(dim):
            lo[d] = min(lo[d], pos[i, d])
            hi[d] = max(hi[d], pos[i, d])
    nc = np.ones(3, np.int64)
    for d in range(dim):
        nc[d] = int((hi[d] - lo[d]) / support) + 1
    ncell = nc[0] * nc[1] * nc[2]
    if cell_start.shape[0] < ncell + 1:
        cell_start = np.empty(ncell + ncell // 4 + 1, np.int64)
    for c in range(ncell + 1):
        cell_start[c] = 0
    for i in range(n):
        c = 0
        for d in range(dim - 1, -1, -1):
            k = min(int((pos[i, d] - lo[d]) / support), nc[d] - 1)
            c = c * nc[d] + k
        cell[i] = c
        cell_start[c + 1] += 1
    for c in range(ncell):
        cell_start[c + 1] += cell_start[c]
    fill = cell_start[:ncell].copy()
    for i in range(n):
        c = cell[i]
        order[fill[c]] = i
        fill[c] += 1
    return cell_start, nc[0], nc[1], nc[2]


@njit(cache=True, inline="always")
def _cell_pairs(c, spos, r2max, cell_start, order, nc0, nc1, nc2, kid, h, start, caps, nb, w, g, counts, cand, ck,
                r2, sel):
    """The rows of cell c's particles. Its candidates, the particles of the 3^dim cells
    around it, are copied once into ``cand`` (positions) and ``ck`` (their places in cell
    order), three cells along the first axis at a time (one run of ``spos``); each particle
    then takes its distances to all of them in one loop (``r2``, no branch: vectorised),
    selects those within the support and not itself into ``sel`` (without a branch: a
    partner is found in about one candidate of seven in 3D, a branch the CPU would
    mispredict), and writes their W_ij and grad_i W_ij while its capacity ``caps[i]``
    lasts; ``counts[i]`` is all of them. Rows hold the partners in the candidates' order."""
    dim = spos.shape[1]
    ci0 = c % nc0
    ci1 = (c // nc0) % nc1
    ci2 = c // (nc0 * nc1)
    a0 = max(ci0 - 1, 0)
    b0 = min(ci0 + 1, nc0 - 1)
    reach2 = 1 if dim == 3 else 0
    m = 0
    for c2 in range(max(ci2 - reach2, 0), min(ci2 + reach2, nc2 - 1) + 1):
        for c1 in range(max(ci1 - 1, 0), min(ci1 + 1, nc1 - 1) + 1):
            row = (c2 * nc1 + c1) * nc0
            for k in range(cell_start[row + a0], cell_start[row + b0 + 1]):
                for d in range(dim):
                    cand[d, m] = spos[k, d]
                ck[m] = k
                m += 1
    for k in range(cell_start[c], cell_start[c + 1]):
        i = order[k]
        x0 = spos[k, 0]
        x1 = spos[k, 1]
        x2 = spos[k, 2] if dim == 3 else 0.0
        for u in range(m):
            d0 = x0 - cand[0, u]
            d1 = x1 - cand[1, u]
            r2[u] = d0 * d0 + d1 * d1
            if dim == 3:
                d2 = x2 - cand[2, u]
                r2[u] += d2 * d2
        cnt = 0
        for u in range(m):
            sel[cnt] = u
            cnt += (r2[u] < r2max) & (ck[u] != k)
        p = start[i]
        for v in range(min(cnt, caps[i])):
            u = sel[v]
            r = math.sqrt(r2[u])
            nb[p] = order[ck[u]]
            w[p] = kernel_w(kid, r, h, dim)
            f = kernel_f(kid, r, h, dim)
            g[p, 0] = f * (x0 - cand[0, u])
            g[p, 1] = f * (x1 - cand[1, u])
            if dim == 3:
                g[p, 2] = f * (x2 - cand[2, u])
            p += 1
        counts[i] = cnt


@njit(cache=True, parallel=True)
def fill_pairs(pos, spos, support, order, cell_start, nc0, nc1, nc2, kid, h, start, caps, nb, w, g, counts, nth):
    """Rows start[i]:start[i] + counts[i] of nb, w (W_ij) and g (grad_i W_ij) for every
    particle, ``counts[i]`` its partners; a row with counts[i] > caps[i] (its capacity) is
    incomplete. ``spos``: the positions in cell order (filled here). The particles of a cell
    share their candidates (:func:`_cell_pairs`: 1.8 times as fast as a walk of the cells
    around each particle, with the same rows, on the 3D dam break at 0.12 s on one thread).
    Task t of ``nth`` (numba's thread count; any count >= 1 gives the same rows) takes every
    nth cell, with its own scratch; a row depends on the positions and the particles' order
    only."""
    n, dim = pos.shape
    ncell = nc0 * nc1 * nc2
    for k in prange(n):
        for d in range(dim):
            spos[k, d] = pos[order[k], d]
    most = 0
    for c in range(ncell):
        most = max(most, cell_start[c + 1] - cell_start[c])
    bound = min(most * (27 if dim == 3 else 9), n)  # the candidates of a cell, at most
    for t in prange(nth):
        cand = np.empty((dim, bound))
        ck = np.empty(bound, np.int64)
        r2 = np.empty(bound)
        sel = np.empty(bound, np.int64)
        for c in range(t, ncell, nth):
            if cell_start[c + 1] > cell_start[c]:
                _cell_pairs(c, spos, support * support, cell_start, order, nc0, nc1, nc2, kid, h, start, caps, nb, w,
                            g, counts, cand, ck, r2, sel)


@njit(cache=True, parallel=True)
def renumber(start, end, nb, new_index):
    """nb <- new_index[nb] in every row: the partners' numbers after the particles were
    reordered (the rows themselves keep their place in the list)."""
    for i in prange(start.shape[0]):
        for p in range(start[i], end[i]):
            nb[p] = new_index[nb[p]]
