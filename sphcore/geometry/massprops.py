"""Mass properties of a closed wall of uniform density: mass, centre of mass, inertia.

A 2D wall is a closed polygon (vertices in order, either sense); a 3D wall a closed
triangle mesh whose triangles are wound consistently (either sense). Both come from the
divergence theorem, so no interior sampling is needed and the figures are exact for the
polygon or mesh given.

2D, Green's theorem over the polygon's edges (p_i, p_{i+1}), c_i = p_i x p_{i+1}:

    A = 1/2 sum c_i,    A C = 1/6 sum (p_i + p_{i+1}) c_i,
    J_O = 1/12 sum c_i (p_i.p_i + p_i.p_{i+1} + p_{i+1}.p_{i+1})   (polar moment about the origin),

and the moment of inertia about the centre of mass is rho (J_O - A |C|^2).

3D: the mesh is the signed sum of the tetrahedra (0, a, b, c) over its triangles. Each has
the volume v = a.(b x c)/6, its centre (a + b + c)/4 and the second moment
int x x^T dV = v/20 (a a^T + b b^T + c c^T + s s^T), s = a + b + c; the inertia tensor
about a point is rho (tr(S) 1 - S) of the second moment S about that point.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np


@dataclass(frozen=True)
class MassProperties:
    """``mass`` (kg; 2D: kg per metre of span), ``centre`` of mass (m), ``inertia`` about
    the centre of mass in the reference frame: 2D a (1, 1) array (kg m^2 / m, about z),
    3D the (3, 3) tensor (kg m^2); ``size`` the area (m^2) or volume (m^3)."""

    mass: float
    centre: np.ndarray
    inertia: np.ndarray
    size: float


def polygon(vertices: np.ndarray, density: float) -> MassProperties:
    """The mass properties of a closed polygon (n, 2) of uniform ``density`` (kg/m^3)."""
    p = np.asarray(vertices, float)
    return _segments(p, np.roll(p, -1, axis=0), density)


def mesh(points: np.ndarray, triangles: np.ndarray, density: float) -> MassProperties:
    """The mass properties of a closed triangle mesh (points (n, 3), triangles (m, 3))."""
    x = np.asarray(points, float)
    # about a point inside the bounding box: the sums then cancel less
    origin = 0.5 * (x.min(axis=0) + x.max(axis=0))
    a, b, cc = (x[np.asarray(triangles)[:, k]] - origin for k in range(3))
    v = np.einsum("ij,ij->i", a, np.cross(b, cc)) / 6.0
    volume = v.sum()
    if volume == 0.0:
        raise ValueError("the mesh encloses no volume")
    s = a + b + cc
    centre = (v[:, None] * s).sum(axis=0) / (4.0 * volume)
    second = sum(np.einsum("i,ij,ik->jk", v, p, p) for p in (a, b, cc, s)) / 20.0
    sign = 1.0 if volume > 0 else -1.0  # triangles wound inwards: every sum changes sign
    volume, second = sign * volume, sign * second
    second = second - volume * np.outer(centre, centre)  # about the centre of mass
    inertia = density * (np.trace(second) * np.eye(3) - second)
    return MassProperties(density * volume, centre + origin, inertia, volume)


def box(lo: np.ndarray, hi: np.ndarray, density: float) -> MassProperties:
    """A box [lo, hi] (2D or 3D) of uniform density."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    e = hi - lo
    size = float(np.prod(e))
    m = density * size
    if len(e) == 2:
        inertia = np.array([[m * (e[0] ** 2 + e[1] ** 2) / 12.0]])
    else:
        inertia = np.diag([m * (e[1] ** 2 + e[2] ** 2), m * (e[0] ** 2 + e[2] ** 2), m * (e[0] ** 2 + e[1] ** 2)]) / 12.0
    return MassProperties(m, 0.5 * (lo + hi), inertia, size)


def of_faces(verts: np.ndarray, density: float) -> MassProperties:
    """The mass properties of a closed wall given by its faces ``verts`` (nf, dim, dim):
    segments in 2D (Green's theorem needs only each edge's ends, in any order of the
    edges), triangles in 3D; either orientation."""
    verts = np.asarray(verts, float)
    if verts.shape[2] == 2:
        return _segments(verts[:, 0], verts[:, 1], density)
    points = verts.reshape(-1, 3)
    return mesh(points, np.arange(len(points)).reshape(-1, 3), density)


def _segments(p: np.ndarray, q: np.ndarray, density: float) -> MassProperties:
    origin = 0.5 * (np.minimum(p.min(0), q.min(0)) + np.maximum(p.max(0), q.max(0)))
    p, q = p - origin, q - origin
    c = p[:, 0] * q[:, 1] - p[:, 1] * q[:, 0]
    area = 0.5 * c.sum()
    if area == 0.0:
        raise ValueError("the wall encloses no area")
    centre = ((p + q) * c[:, None]).sum(axis=0) / (6.0 * area)
    polar = (c * ((p * p).sum(1) + (p * q).sum(1) + (q * q).sum(1))).sum() / 12.0
    sign = 1.0 if area > 0 else -1.0
    area, polar = sign * area, sign * polar
    return MassProperties(density * area, centre + origin, np.array([[density * (polar - area * float(centre @ centre))]]),
                          area)
