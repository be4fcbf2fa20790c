"""Wall planes n . (X - X0) = 0 (paper Eq. 3), the normal pointing into the domain.

The domain is the intersection of the planes' positive sides; a particle of radius r is
inside when its signed distance d = n . (C - X0) (Eq. 4) is at least r for every plane.
"""

from __future__ import annotations

import functools
from dataclasses import dataclass
from itertools import combinations

import numpy as np
from numba import njit


@njit(cache=True, inline="always")
def plane_distance(normals, offsets, k, x0, x1, x2):
    """Signed distance d = n_k . x - offset_k (m) of the point (x0, x1, x2) to plane k
    (paper Eq. 4), positive inside; x2 is ignored in 2D. The one definition every kernel
    uses (walls, checks, ghosts, free surface), so all of them agree to the last bit."""
    d = normals[k, 0] * x0 + normals[k, 1] * x1
    if normals.shape[1] == 3:
        d += normals[k, 2] * x2
    return d - offsets[k]


@njit(cache=True, inline="always")
def normal_parts(normals, near, m, dim, v0, v1, v2, c):
    """Write v = (v0, v1, v2) in the normals of the planes near[:m] (m <= 3): c[:m] with
    v = sum_u c[u] normals[near[u]] when v lies in their span (least squares otherwise),
    from the Gram system of the normals by Cramer's rule. Returns False when the normals
    are not independent (parallel planes) or m > 3; c is then left as it is. For walls
    that move apart (a piston meeting a fixed floor): each wall's share of a vector along
    the walls' normals."""
    if m > 3 or m < 1:
        return False
    M = np.eye(3)
    r = np.zeros(3)
    for u in range(m):
        a = near[u]
        r[u] = normals[a, 0] * v0 + normals[a, 1] * v1 + (normals[a, 2] * v2 if dim == 3 else 0.0)
        for w in range(m):
            b = near[w]
            acc = 0.0
            for e in range(dim):
                acc += normals[a, e] * normals[b, e]
            M[u, w] = acc
    det = _det3(M)
    if det <= 1e-9:
        return False
    col = np.empty((3, 3))
    for u in range(m):
        for a in range(3):
            for b in range(3):
                col[a, b] = r[a] if b == u else M[a, b]
        c[u] = _det3(col) / det
    return True


@njit(cache=True, inline="always")
def _det3(a):
    return (a[0, 0] * (a[1, 1] * a[2, 2] - a[1, 2] * a[2, 1]) - a[0, 1] * (a[1, 0] * a[2, 2] - a[1, 2] * a[2, 0])
            + a[0, 2] * (a[1, 0] * a[2, 1] - a[1, 1] * a[2, 0]))


@njit(cache=True, inline="always")
def particle_distance(normals, offsets, k, pos, i):
    """:func:`plane_distance` of particle i of ``pos`` (n, dim)."""
    return plane_distance(normals, offsets, k, pos[i, 0], pos[i, 1], pos[i, 2] if pos.shape[1] == 3 else 0.0)


@dataclass(frozen=True)
class Planes:
    """Wall planes: unit ``normals`` (k, dim) pointing into the domain, ``points`` (k, dim)."""

    normals: np.ndarray
    points: np.ndarray

    @property
    def count(self) -> int:
        return self.normals.shape[0]

    @functools.cached_property
    def offsets(self) -> np.ndarray:
        """n . X0 for each plane, so that d = n . C - offset (computed once: the time loop
        reads it every step)."""
        return np.einsum("kd,kd->k", self.normals, self.points)

    def distances(self, pos: np.ndarray) -> np.ndarray:
        """Signed distances d (n, k) of points to every plane (m); positive inside."""
        return pos @ self.normals.T - self.offsets

    @classmethod
    def from_lists(cls, normals, points) -> "Planes":
        nrm = np.asarray(normals, float).reshape(len(normals), -1)
        nrm = nrm / np.linalg.norm(nrm, axis=1, keepdims=True)
        return cls(np.ascontiguousarray(nrm), np.ascontiguousarray(np.asarray(points, float).reshape(nrm.shape)))

    @classmethod
    def box(cls, lo, hi) -> "Planes":
        """The 2*dim planes of an axis-aligned box [lo, hi]."""
        lo, hi = np.asarray(lo, float), np.asarray(hi, float)
        dim = lo.size
        eye = np.eye(dim)
        return cls(np.ascontiguousarray(np.concatenate([eye, -eye])),
                   np.ascontiguousarray(np.concatenate([np.tile(lo, (dim, 1)), np.tile(hi, (dim, 1))])))

    def concat(self, other: "Planes") -> "Planes":
        return Planes(np.ascontiguousarray(np.concatenate([self.normals, other.normals])),
                      np.ascontiguousarray(np.concatenate([self.points, other.points])))


def recession_direction(normals: np.ndarray, tol: float = 1e-12):
    """A unit direction u with n . u >= 0 for every normal, or None if there is none.

    If such a u exists, the intersection of the half-spaces (when non-empty) is unbounded
    along u. The cone {u : N u >= 0} is {0} unless one of its extreme rays (or a line in
    it) lies on the intersection of dim - 1 constraint planes, so checking those
    candidates is exact.
    """
    k, dim = normals.shape
    if k == 0 or np.linalg.matrix_rank(normals, tol=1e-9) < dim:
        # normals span less than the space: any direction orthogonal to all of them
        _, _, vt = np.linalg.svd(normals if k else np.eye(dim))
        return vt[-1] if k else vt[0]
    cands = []
    if dim == 2:
        for n in normals:
            cands.append(np.array([-n[1], n[0]]))
    else:
        for a, b in combinations(range(k), 2):
            c = np.cross(normals[a], normals[b])
            if np.linalg.norm(c) > 1e-12:
                cands.append(c / np.linalg.norm(c))
    for c in cands:
        for u in (c, -c):
            if np.all(normals @ u >= -tol):
                return u
    return None


def outline(planes: Planes):
    """The boundary of the region the planes enclose, as faces (segments in 2D, triangles
    in 3D, (nf, dim, dim) m) for drawing a tank, or None when the region is unbounded or
    empty. The region's corners are the points where dim planes meet and no plane is
    violated (within 1e-9 of the region's size); each plane's corners, in order about
    their centre, make its face."""
    normals, offsets = planes.normals, planes.offsets
    k, dim = normals.shape
    if k < dim + 1 or recession_direction(normals) is not None:
        return None
    scale = 1.0 + float(np.abs(planes.points).max())
    corners = []
    for idx in combinations(range(k), dim):
        a = normals[list(idx)]
        if abs(np.linalg.det(a)) < 1e-12:
            continue
        x = np.linalg.solve(a, offsets[list(idx)])
        if np.all(normals @ x - offsets >= -1e-9 * scale):
            corners.append(x)
    if len(corners) < dim + 1:
        return None
    corners = np.unique(np.round(np.array(corners) / (1e-9 * scale)) * (1e-9 * scale), axis=0)
    faces = []
    for j in range(k):
        on = corners[np.abs(corners @ normals[j] - offsets[j]) <= 1e-9 * scale]
        if len(on) < dim:
            continue
        c = on.mean(axis=0)
        if dim == 2:
            t = np.array([-normals[j, 1], normals[j, 0]])
            on = on[np.argsort((on - c) @ t)]
            faces.append([on[0], on[-1]])
            continue
        u = np.cross(normals[j], [1.0, 0.0, 0.0] if abs(normals[j, 0]) < 0.9 else [0.0, 1.0, 0.0])
        u /= np.linalg.norm(u)
        w = np.cross(normals[j], u)
        on = on[np.argsort(np.arctan2((on - c) @ w, (on - c) @ u))]
        faces += [[on[0], on[i], on[i + 1]] for i in range(1, len(on) - 1)]
    return np.ascontiguousarray(np.array(faces, dtype=np.float64)) if faces else None
