"""Finite wall faces: segments (2D) and triangles (3D), beside the infinite planes.

``Faces.verts`` (nf, dim, dim): face f has vertices ``verts[f, j]``. Orientation: the
normal of a segment v0 -> v1 is (e1, -e0) / |e| (to the right of the direction), of a
triangle (v1 - v0) x (v2 - v0) / |.|; every closed wall is stored with its normals
pointing into the fluid. A closed wall whose normals point out of the region it encloses
(positive signed area or volume) is an obstacle, the fluid outside; one with negative
measure is a tank, the fluid inside. Open walls (a polyline: a thin plate) have no
inside and act on both sides.

A particle of radius r is admissible when it lies on the fluid side of every closed wall
and at distance >= r from every face (and, as before, inside every plane).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numba
import numpy as np
from numba import njit

from sphcore.geometry.facegeom import nearest_point


@dataclass(frozen=True)
class Faces:
    """Wall faces ``verts`` (nf, dim, dim) and the closed groups among them.

    ``groups``: (start, stop, sign) per closed wall, faces start:stop; sign +1 for an
    obstacle (fluid outside), -1 for a tank (fluid inside). Faces in no group are open.

    Geometry queries (numpy in, numpy out; brute force over the faces, for set-up and
    post-processing; the kernels use a :class:`FaceGrid`): :meth:`distances`,
    :meth:`nearest`, :meth:`signed_distance`, :meth:`normal_at`, :meth:`in_fluid`. The wall
    share of a kernel support with its gradient and moment for the same faces is the wall
    model's (``sphcore_plugins.wall_integral.meshfaces.face_terms_at``: it needs the
    kernel's radial tables).
    """

    verts: np.ndarray
    groups: tuple = field(default_factory=tuple)

    @property
    def count(self) -> int:
        return self.verts.shape[0]

    @property
    def dim(self) -> int:
        return self.verts.shape[2]

    @classmethod
    def empty(cls, dim: int) -> "Faces":
        return cls(np.zeros((0, dim, dim)))

    def concat(self, other: "Faces") -> "Faces":
        n = self.count
        groups = self.groups + tuple((a + n, b + n, s) for a, b, s in other.groups)
        return Faces(np.ascontiguousarray(np.concatenate([self.verts, other.verts])), groups)

    def normals(self) -> np.ndarray:
        """(nf, dim) unit normals (into the fluid for closed walls)."""
        v = self.verts
        if self.dim == 2:
            e = v[:, 1] - v[:, 0]
            n = np.stack([e[:, 1], -e[:, 0]], axis=1)
        else:
            n = np.cross(v[:, 1] - v[:, 0], v[:, 2] - v[:, 0])
        return n / np.linalg.norm(n, axis=1, keepdims=True)

    def distances(self, pos: np.ndarray) -> np.ndarray:
        """(n,) distance (m) of each point to the nearest face (inf without faces)."""
        pos = np.ascontiguousarray(pos, dtype=np.float64)
        return _nearest(self.verts, pos)[2]

    def nearest(self, pos: np.ndarray):
        """For each point: (the nearest point on any face (n, dim) m, that face's index (n,),
        the distance (n,) m). Brute force over the faces (set-up and post-processing)."""
        pos = np.ascontiguousarray(pos, dtype=np.float64)
        if self.count == 0:
            raise ValueError("no faces")
        return _nearest(self.verts, pos)

    def signed_distance(self, pos: np.ndarray) -> np.ndarray:
        """(n,) distance (m) to the nearest face, positive on the fluid side of every closed
        wall, negative inside a solid (an open wall has no inside: positive on both sides)."""
        dist = self.nearest(pos)[2]
        return np.where(self.in_fluid(pos), dist, -dist)

    def normal_at(self, pos: np.ndarray) -> np.ndarray:
        """(n, dim) unit normal of the walls at each point, towards the fluid: from the nearest
        point of the faces to the point (the face normal over a face's interior, radial about
        an edge or vertex), reversed inside a solid; the nearest face's normal for a point
        on a face (closer than 1e-12 of its coordinates' size: round-off). For an open wall,
        away from the wall on the point's side."""
        pos = np.ascontiguousarray(pos, dtype=np.float64)
        q, f, dist = self.nearest(pos)
        out = self.normals()[f]
        away = dist > 1e-12 * (1.0 + np.abs(pos).max(axis=1))
        sign = np.where(self.in_fluid(pos), 1.0, -1.0)
        out[away] = (pos[away] - q[away]) / dist[away, None] * sign[away, None]
        return out

    def in_fluid(self, pos: np.ndarray) -> np.ndarray:
        """(n,) bool: on the fluid side of every closed wall (generalised winding number:
        the enclosed region has |w| = 1, the rest w = 0)."""
        pos = np.ascontiguousarray(pos, dtype=np.float64)
        ok = np.ones(pos.shape[0], bool)
        for a, b, sign in self.groups:
            w = _winding(np.ascontiguousarray(self.verts[a:b]), pos)
            enclosed = np.abs(w) > 0.5
            ok &= ~enclosed if sign > 0 else enclosed
        return ok


def closed_wall(verts: np.ndarray, fluid_inside: bool) -> Faces:
    """A closed wall from consistently oriented faces: flipped if needed so that its normals
    point into the fluid (out of the enclosed region for an obstacle, into it for a tank)."""
    verts = np.ascontiguousarray(verts, dtype=np.float64)
    m = signed_measure(verts)
    if (m > 0) == fluid_inside:
        verts = np.ascontiguousarray(verts[:, ::-1] if verts.shape[2] == 2 else verts[:, [0, 2, 1]])
    return Faces(verts, ((0, verts.shape[0], -1 if fluid_inside else 1),))


def signed_measure(verts: np.ndarray) -> float:
    """Signed area (2D, m^2; shoelace, positive counter-clockwise) or volume (3D, m^3;
    sum det(v0, v1, v2) / 6, positive with outward normals) enclosed by closed faces;
    measured from the faces' centroid, so that a wall far from the origin loses no digits."""
    v = np.asarray(verts, float)
    v = v - v.reshape(-1, v.shape[2]).mean(axis=0)
    if v.shape[2] == 2:
        return 0.5 * float(np.sum(v[:, 0, 0] * v[:, 1, 1] - v[:, 1, 0] * v[:, 0, 1]))
    return float(np.sum(np.linalg.det(v))) / 6.0


def polygon(points) -> np.ndarray:
    """Segments of the closed polygon through ``points`` (k, 2), in the given order."""
    p = np.asarray(points, float)
    return np.ascontiguousarray(np.stack([p, np.roll(p, -1, axis=0)], axis=1))


def polyline(points) -> np.ndarray:
    """Segments of the open polyline through ``points`` (k, dim)."""
    p = np.asarray(points, float)
    return np.ascontiguousarray(np.stack([p[:-1], p[1:]], axis=1))


def box(lo, hi) -> np.ndarray:
    """Faces of the axis-aligned box [lo, hi], outward normals: 4 segments in 2D, 12
    triangles in 3D."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    if lo.size == 2:
        return polygon([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    c = np.array([[lo[0] if i & 1 == 0 else hi[0], lo[1] if i & 2 == 0 else hi[1],
                   lo[2] if i & 4 == 0 else hi[2]] for i in range(8)])
    quads = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]
    tris = []
    for a, b, cc, d in quads:
        tris += [(a, b, cc), (a, cc, d)]
    return np.ascontiguousarray(c[np.array(tris)])


@njit(cache=True, parallel=True)
def _nearest(verts, pos):
    """(nearest point (n, dim), its face (n,), distance (n,)) over all faces, brute force;
    no faces: distance inf."""
    n, dim = pos.shape
    pts = np.zeros((n, dim))
    face = np.zeros(n, np.int64)
    dist = np.full(n, np.inf)
    for i in numba.prange(n):
        x2 = pos[i, 2] if dim == 3 else 0.0
        for f in range(verts.shape[0]):
            q0, q1, q2 = nearest_point(verts, f, pos[i, 0], pos[i, 1], x2)
            d = math.sqrt((pos[i, 0] - q0) ** 2 + (pos[i, 1] - q1) ** 2 + (x2 - q2) ** 2)
            if d < dist[i]:
                dist[i] = d
                face[i] = f
                pts[i, 0] = q0
                pts[i, 1] = q1
                if dim == 3:
                    pts[i, 2] = q2
    return pts, face, dist


@njit(cache=True, parallel=True)
def _winding(verts, pos):
    """Winding number of closed faces about each point: 2D sum of signed angles / 2 pi;
    3D sum of signed solid angles / 4 pi (Van Oosterom & Strackee 1983)."""
    n = pos.shape[0]
    out = np.zeros(n)
    dim = pos.shape[1]
    for i in numba.prange(n):
        w = 0.0
        for f in range(verts.shape[0]):
            if dim == 2:
                a0, a1 = verts[f, 0, 0] - pos[i, 0], verts[f, 0, 1] - pos[i, 1]
                b0, b1 = verts[f, 1, 0] - pos[i, 0], verts[f, 1, 1] - pos[i, 1]
                w += math.atan2(a0 * b1 - a1 * b0, a0 * b0 + a1 * b1)
            else:
                z = pos[i, 2]
                a0, a1, a2 = verts[f, 0, 0] - pos[i, 0], verts[f, 0, 1] - pos[i, 1], verts[f, 0, 2] - z
                b0, b1, b2 = verts[f, 1, 0] - pos[i, 0], verts[f, 1, 1] - pos[i, 1], verts[f, 1, 2] - z
                c0, c1, c2 = verts[f, 2, 0] - pos[i, 0], verts[f, 2, 1] - pos[i, 1], verts[f, 2, 2] - z
                la = math.sqrt(a0 * a0 + a1 * a1 + a2 * a2)
                lb = math.sqrt(b0 * b0 + b1 * b1 + b2 * b2)
                lc = math.sqrt(c0 * c0 + c1 * c1 + c2 * c2)
                det = a0 * (b1 * c2 - b2 * c1) - a1 * (b0 * c2 - b2 * c0) + a2 * (b0 * c1 - b1 * c0)
                den = (la * lb * lc + (a0 * b0 + a1 * b1 + a2 * b2) * lc
                       + (a0 * c0 + a1 * c1 + a2 * c2) * lb + (b0 * c0 + b1 * c1 + b2 * c2) * la)
                w += 2.0 * math.atan2(det, den)
        out[i] = w / (2.0 * math.pi if dim == 2 else 4.0 * math.pi)
    return out
