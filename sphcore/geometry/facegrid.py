"""A uniform grid over wall faces, so that a particle tests only the faces near it.

Every face is listed in each cell it may touch (the cell's centre within half a cell
diagonal of the face: a conservative test). A query over the box of a particle's step
inflated by its radius then meets every face the sphere can touch. The grid spans the
faces' bounding box; the cost of a query does not grow with the faces far away.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from numba import njit

from sphcore.geometry.facegeom import face_distance

#: cells are capped; past this the cell side grows
MAX_CELLS = 1 << 22


@dataclass(frozen=True)
class FaceGrid:
    """``lo`` (3,) lower corner (m), ``cell`` side (m), ``shape`` (3,) cells per axis (1 for
    an absent z), ``start`` (ncells + 1,) and ``items``: faces of cell c are
    ``items[start[c]:start[c + 1]]``."""

    lo: np.ndarray
    cell: float
    shape: np.ndarray
    start: np.ndarray
    items: np.ndarray

    def arrays(self):
        """The tuple the kernels take: (lo, inv_cell, shape, start, items)."""
        return self.lo, 1.0 / self.cell, self.shape, self.start, self.items


def build_grid(verts: np.ndarray, cell: float) -> FaceGrid:
    """Grid of side ``cell`` (m; grown until at most MAX_CELLS cells) over the faces."""
    nf, dim = verts.shape[0], verts.shape[2]
    lo = np.zeros(3)
    hi = np.zeros(3)
    if nf:
        lo[:dim] = verts.min(axis=(0, 1)) - cell
        hi[:dim] = verts.max(axis=(0, 1)) + cell
    ext = np.maximum(hi - lo, 0.0)
    while True:
        shape = np.maximum(np.ceil(ext / cell), 1).astype(np.int64)
        shape[dim:] = 1
        if int(np.prod(shape)) <= MAX_CELLS:
            break
        cell *= 1.5
    counts = np.zeros(int(np.prod(shape)) + 1, np.int64)
    _fill(verts, lo, cell, shape, counts, np.zeros(0, np.int32), False)
    start = np.zeros_like(counts)
    np.cumsum(counts[:-1], out=start[1:])
    items = np.zeros(int(start[-1]), np.int32)
    _fill(verts, lo, cell, shape, start.copy(), items, True)
    return FaceGrid(lo, float(cell), shape, start, items)


@njit(cache=True)
def _fill(verts, lo, cell, shape, cursor, items, write):
    """Count (write False: cursor[c] += 1) or list (cursor[c] is the next slot) the faces
    of every cell."""
    dim = verts.shape[2]
    half_diag = 0.5 * cell * math.sqrt(dim)
    for f in range(verts.shape[0]):
        i0 = np.zeros(3, np.int64)
        i1 = np.zeros(3, np.int64)
        for c in range(dim):
            vmin = verts[f, 0, c]
            vmax = verts[f, 0, c]
            for j in range(1, dim):
                vmin = min(vmin, verts[f, j, c])
                vmax = max(vmax, verts[f, j, c])
            i0[c] = max(int(math.floor((vmin - lo[c]) / cell)) - 1, 0)
            i1[c] = min(int(math.floor((vmax - lo[c]) / cell)) + 1, shape[c] - 1)
        for a in range(i0[0], i1[0] + 1):
            for b in range(i0[1], i1[1] + 1):
                for z in range(i0[2], i1[2] + 1):
                    x0 = lo[0] + (a + 0.5) * cell
                    x1 = lo[1] + (b + 0.5) * cell
                    x2 = lo[2] + (z + 0.5) * cell if dim == 3 else 0.0
                    if face_distance(verts, f, x0, x1, x2) <= half_diag:
                        c_id = (a * shape[1] + b) * shape[2] + z
                        if write:
                            items[cursor[c_id]] = f
                            cursor[c_id] += 1
                        else:
                            cursor[c_id] += 1


@njit(cache=True, inline="always")
def cell_span(lo, inv_cell, shape, c, xmin, xmax):
    """Cells (first, last) along axis c covering [xmin, xmax] (m); first > last if none."""
    # clamp as floats before floor: a point far away (or inf) must not overflow the int
    a = (xmin - lo[c]) * inv_cell
    b = (xmax - lo[c]) * inv_cell
    if not (a <= b):  # NaN compares false: no cell
        return 1, 0
    a = math.floor(min(max(a, 0.0), float(shape[c])))
    b = math.floor(min(max(b, -1.0), float(shape[c] - 1)))
    if a > b:
        return 1, 0
    return int(a), int(b)


@njit(cache=True, inline="always")
def box_cells(lo, inv_cell, shape, dim, a0, a1, a2, b0, b1, b2, pad):
    """(x0, x1, y0, y1, z0, z1): the cells covering the box of the segment A -> B inflated
    by ``pad`` (m) on every side (a2, b2 ignored in 2D); empty ranges where it misses."""
    x0, x1 = cell_span(lo, inv_cell, shape, 0, min(a0, b0) - pad, max(a0, b0) + pad)
    y0, y1 = cell_span(lo, inv_cell, shape, 1, min(a1, b1) - pad, max(a1, b1) + pad)
    if dim == 3:
        z0, z1 = cell_span(lo, inv_cell, shape, 2, min(a2, b2) - pad, max(a2, b2) + pad)
    else:
        z0, z1 = 0, 0
    return x0, x1, y0, y1, z0, z1
