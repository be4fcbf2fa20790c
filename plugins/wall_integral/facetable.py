"""The faces' wall terms tabulated once per run on a grid (the walls do not move).

The exact terms of a particle near a mesh (:func:`.facewalls.point_terms`) integrate every
face within its support: about 170 triangles for a particle next to a sphere of 10^4
triangles, 50 us a particle, and the wall model took 72% of a 3D step at 10^5 particles
(``benchmarks/speed/bench_faces.py --wall-model``). Since s, G and T g are functions of position
alone, they are computed once at the nodes of a grid of spacing ``spacing`` over the faces'
box grown by 2h, and each step interpolates them (multilinear) at the particles. The
faces' projector onto their directions (``WallTerms.normals``) is taken from the nearest
node as it is, so that it stays a projector.

Interpolation error: O(spacing^2) times the curvature of the terms, which vary on the
scale h. At the default spacing h/4, at points of the fluid at least dx/2 (a particle's
radius) from the faces of a square tank (2D) and a box (3D): |s error| <= 0.010,
|G error| <= 0.010 / h (the scale of G is 0.75 / h at dx/2 from a face: 1.3 %), |T g
error| <= 0.15 m/s^2 (`tests/test_wall_face_table.py`). Faces carry, unlike planes, the
uncorrected lattice error of the truncated SPH sum, about 6 % of G next to a face.
``wall_integral.faces = "exact"`` keeps the exact integrals per particle and step.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np
from numba import njit, prange

from .facewalls import add_terms, point_terms
from .normals import add_direction, set_projector

GRID_SHIFT = 0.381966  # (3 - sqrt 5) / 2 of a spacing
NV = 14  # per node: s, G (3), T g (3), the faces' projector (00 01 02 11 12 22), faces within 2h (0 or 1)


class FaceTable(NamedTuple):
    """Nodes lo + (i, j, k) * spacing, i < shape[0], ...; ``tab`` (nodes, NV), node
    (i, j, k) at row (i * shape[1] + j) * shape[2] + k."""

    lo: np.ndarray
    inv: float
    shape: np.ndarray
    tab: np.ndarray


def table_shape(verts: np.ndarray, h: float, spacing: float):
    """(lo (3,), shape (3,) int64) of the grid over the faces' box grown by 2h + 1.38 spacings."""
    dim = verts.shape[2]
    # shifted by an irrational part of a spacing: a mesh's faces, edges and vertices usually
    # lie on round coordinates, and a node exactly on an edge or vertex would get the face's
    # value of the boundary integrals there (s = 1/2) instead of the edge's or vertex's
    pad = 2.0 * h + (1.0 + GRID_SHIFT) * spacing
    lo = np.zeros(3)
    lo[:dim] = verts.min(axis=(0, 1)) - pad
    hi = verts.max(axis=(0, 1)) + pad
    shape = np.ones(3, np.int64)
    shape[:dim] = np.floor((hi - lo[:dim]) / spacing).astype(np.int64) + 2
    return lo, shape


def build_table(verts, flat, grid, kernel_id, h, gravity, spacing, max_nodes) -> FaceTable | None:
    """The table of the faces ``verts`` (nf, corners, dim) with their face grid ``grid``
    (``FaceGrid.arrays()``); None when it would need more than ``max_nodes`` nodes."""
    lo, shape = table_shape(verts, h, spacing)
    nodes = int(np.prod(shape))
    if nodes > max_nodes:
        return None
    tab = np.zeros((nodes, NV))
    stamps = np.full((64, verts.shape[0]), -1, np.int64)
    _fill(lo, spacing, shape, verts.shape[2], verts, flat, *grid, stamps, kernel_id, h, np.asarray(gravity, np.float64),
          tab)
    return FaceTable(lo, 1.0 / spacing, shape, tab)


@njit(cache=True, parallel=True)
def _fill(lo, spacing, shape, dim, verts, flat, glo, ginv, gshape, gstart, gitems, stamps, kernel_id, h, gravity, tab):
    nodes = tab.shape[0]
    rows = stamps.shape[0]
    q0 = np.zeros((dim, dim))  # no other plugin's directions: the faces' own projector is stored
    for b in prange(rows):
        for m in range(b * nodes // rows, (b + 1) * nodes // rows):
            k = m % shape[2]
            j = (m // shape[2]) % shape[1]
            i = m // (shape[2] * shape[1])
            x0 = lo[0] + i * spacing
            x1 = lo[1] + j * spacing
            x2 = lo[2] + k * spacing if dim == 3 else 0.0
            near, s, gr0, gr1, gr2, t0, t1, t2, basis, count = point_terms(
                x0, x1, x2, dim, verts, flat, glo, ginv, gshape, gstart, gitems, stamps, np.int64(b), m, kernel_id, h,
                gravity, q0)
            if near == 0:
                continue
            if s < -1e-6:
                # inside a solid the boundary integrals give s - 1 (the kernel's singular point
                # lies in the integrated region): the continuation is s + 1, smooth across the
                # face. Outside, s >= 0 up to round-off (-1e-17 where the support just touches a
                # face); inside, within a node diagonal of a face (the only inside nodes a
                # particle's interpolation reaches: particles keep dx/2 from faces), s - 1 < -0.2
                s += 1.0
            row = tab[m]
            row[0], row[1], row[2], row[3], row[4], row[5], row[6] = s, gr0, gr1, gr2, t0, t1, t2
            c = 7
            for a in range(3):
                for a2 in range(a, 3):
                    acc = 0.0
                    for e in range(count):
                        acc += basis[3 * e + a] * basis[3 * e + a2]
                    row[c] = acc
                    c += 1
            row[13] = 1.0


@njit(cache=True, inline="always")
def _corner(u, n):
    """Lower node index and weight of the upper node along one axis (u in node units)."""
    i0 = min(max(int(math.floor(u)), 0), n - 2)
    return i0, u - i0


@njit(cache=True, parallel=True)
def table_wall_terms(pos, lo, inv, shape, tab, full, share, grad, hydro, fill, q):
    """Add the tabulated faces' terms to share, grad, hydro, fill and q (as
    :func:`.facewalls.face_wall_terms` adds the exact ones) for every particle of ``pos``
    inside the table's grid; the grid covers everything within 2h of a face."""
    n, dim = pos.shape
    for i in prange(n):
        u0 = (pos[i, 0] - lo[0]) * inv
        u1 = (pos[i, 1] - lo[1]) * inv
        u2 = (pos[i, 2] - lo[2]) * inv if dim == 3 else 0.0
        if u0 < 0.0 or u1 < 0.0 or u2 < 0.0 or u0 > shape[0] - 1 or u1 > shape[1] - 1 or u2 > shape[2] - 1:
            continue
        i0, f0 = _corner(u0, shape[0])
        i1, f1 = _corner(u1, shape[1])
        i2, f2 = _corner(u2, shape[2]) if dim == 3 else (0, 0.0)
        s = g0 = g1 = g2 = t0 = t1 = t2 = 0.0
        for c in range(8 if dim == 3 else 4):
            a, b, e = c & 1, (c >> 1) & 1, (c >> 2) & 1
            w = (f0 if a else 1.0 - f0) * (f1 if b else 1.0 - f1) * ((f2 if e else 1.0 - f2) if dim == 3 else 1.0)
            r = ((i0 + a) * shape[1] + i1 + b) * shape[2] + i2 + e
            s += w * tab[r, 0]
            g0 += w * tab[r, 1]
            g1 += w * tab[r, 2]
            g2 += w * tab[r, 3]
            t0 += w * tab[r, 4]
            t1 += w * tab[r, 5]
            t2 += w * tab[r, 6]
        near = tab[((int(u0 + 0.5)) * shape[1] + int(u1 + 0.5)) * shape[2] + int(u2 + 0.5)]
        if s <= 0.0 and near[13] == 0.0:
            continue
        add_terms(i, dim, s, g0, g1, g2, t0, t1, t2, full, share, grad, hydro, fill)
        if near[13] == 0.0:
            continue
        basis = (0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)
        count = 0
        for a in range(dim):  # what the planes put in q, then the faces' directions
            basis, count = add_direction(basis, count, dim, q[i, 0, a], q[i, 1, a], q[i, 2, a] if dim == 3 else 0.0)
        for a in range(dim):
            c0 = near[7 + a] if a == 0 else (near[8] if a == 1 else near[9])  # row a of the faces' projector
            c1 = near[8] if a == 0 else (near[10] if a == 1 else near[11])
            c2 = near[9] if a == 0 else (near[11] if a == 1 else near[12])
            basis, count = add_direction(basis, count, dim, c0, c1, c2)
        set_projector(q[i], dim, basis, count)
