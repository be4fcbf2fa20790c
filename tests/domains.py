"""Bounded convex wall domains and admissible start points, for tests and the fuzz benchmark.

A :class:`Domain` is a :class:`sphcore.geometry.planes.Planes` with a ``centre`` whose signed
distance to every plane is at least ``inradius`` (m): the region {d >= r} a particle
centre of radius r < inradius may occupy is then non-empty and contains ``centre``.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from sphcore.geometry.planes import Planes, recession_direction


@dataclass(frozen=True)
class Domain:
    planes: Planes
    centre: np.ndarray  # (dim,) m, an interior point
    inradius: float  # m, min over planes of the centre's distance

    @property
    def dim(self) -> int:
        return self.planes.normals.shape[1]

    @property
    def size(self) -> float:
        """A length scale of the domain (m): twice the longest of 512 rays from the centre
        to the walls (fixed directions), about its diameter."""
        u = random_directions(np.random.default_rng(0), 512, self.dim)
        room = self.planes.distances(self.centre[None, :])[0]
        nu = u @ self.planes.normals.T
        with np.errstate(divide="ignore"):
            reach = np.where(nu < 0, room[None, :] / np.where(nu < 0, -nu, 1.0), np.inf)
        return float(2 * reach.min(axis=1).max())


def random_rotation(rng, dim: int) -> np.ndarray:
    """A random orthogonal (dim, dim) matrix (QR of a Gaussian matrix, sign-fixed)."""
    q, rr = np.linalg.qr(rng.standard_normal((dim, dim)))
    return q * np.sign(np.diag(rr))


def _from_normals(normals, heights, centre) -> Domain:
    """Planes with inward ``normals`` at distance ``heights`` from ``centre``."""
    normals = np.asarray(normals, float)
    normals = normals / np.linalg.norm(normals, axis=1, keepdims=True)
    heights = np.asarray(heights, float)
    centre = np.asarray(centre, float)
    points = centre[None, :] - heights[:, None] * normals
    return Domain(Planes(np.ascontiguousarray(normals), np.ascontiguousarray(points)),
                  centre, float(heights.min()))


def box(lo, hi, rotation=None) -> Domain:
    """An axis-aligned box [lo, hi], optionally turned by ``rotation`` about its centre."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    dim = lo.size
    centre = (lo + hi) / 2
    half = (hi - lo) / 2
    normals = np.concatenate([np.eye(dim), -np.eye(dim)])
    if rotation is not None:
        normals = normals @ np.asarray(rotation, float).T
    return _from_normals(normals, np.concatenate([half, half]), centre)


def wedge(angle_deg: float, length: float = 1.0, dim: int = 2, height: float = 1.0) -> Domain:
    """A wedge of opening ``angle_deg`` with its apex at the origin, opening along +x,
    closed by a cap plane x = ``length``; in 3D extruded over 0 <= z <= ``height``.

    The centre is the incentre of the 2D triangle (radius L sin b / (1 + sin b), b the
    half-angle), at mid-height in 3D.
    """
    b = np.radians(angle_deg) / 2
    sb, cb = np.sin(b), np.cos(b)
    n2 = [[sb, cb], [sb, -cb], [-1.0, 0.0]]
    p2 = [[0.0, 0.0], [0.0, 0.0], [length, 0.0]]
    cx = length - length * sb / (1 + sb)
    if dim == 2:
        planes, centre = Planes.from_lists(n2, p2), np.array([cx, 0.0])
    else:
        n3 = [n + [0.0] for n in n2] + [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
        p3 = [p + [0.0] for p in p2] + [[0.0, 0.0, 0.0], [0.0, 0.0, height]]
        planes, centre = Planes.from_lists(n3, p3), np.array([cx, 0.0, height / 2])
    return Domain(planes, centre, float(np.min(planes.distances(centre[None, :]))))


def random_polytope(rng, dim: int, nplanes: int, hmin: float = 0.3, hmax: float = 1.0,
                    centre=None) -> Domain:
    """A bounded random convex polygon (2D) or polyhedron (3D).

    Planes with random unit normals lie at random distances in [hmin, hmax] from the
    centre (tangent planes of spheres about it). While the intersection is unbounded
    along some u (all n . u >= 0), a plane with normal -u is added, so it always ends
    bounded; ``centre`` has clearance >= hmin from every plane.
    """
    normals = rng.standard_normal((nplanes, dim))
    normals /= np.linalg.norm(normals, axis=1, keepdims=True)
    while (u := recession_direction(normals)) is not None:
        normals = np.concatenate([normals, -u[None, :] / np.linalg.norm(u)])
    heights = rng.uniform(hmin, hmax, normals.shape[0])
    if centre is None:
        centre = rng.uniform(-1.0, 1.0, dim)
    return _from_normals(normals, heights, centre)


def sample_inside(rng, domain: Domain, radius: float, m: int, on_wall: float = 0.1) -> np.ndarray:
    """(m, dim) centres with d >= radius for every plane (radius < domain.inradius).

    Points lie along random rays from the centre, at a uniform fraction of the admissible
    length; a fraction ``on_wall`` of them at the full length, i.e. touching a wall.
    """
    if not radius < domain.inradius:
        raise ValueError("radius must be below the domain's inradius")
    dim = domain.dim
    u = rng.standard_normal((m, dim))
    u /= np.linalg.norm(u, axis=1, keepdims=True)
    room = domain.planes.distances(domain.centre[None, :])[0] - radius  # (k,) > 0
    nu = u @ domain.planes.normals.T  # (m, k)
    with np.errstate(divide="ignore"):
        reach = np.where(nu < 0, room[None, :] / np.where(nu < 0, -nu, 1.0), np.inf)
    tmax = reach.min(axis=1)  # finite: the domain is bounded
    frac = rng.uniform(0.0, 1.0, m)
    frac[rng.uniform(0.0, 1.0, m) < on_wall] = 1.0
    return np.ascontiguousarray(domain.centre[None, :] + (frac * tmax)[:, None] * u)


def random_directions(rng, m: int, dim: int) -> np.ndarray:
    """(m, dim) unit vectors, uniform on the sphere."""
    u = rng.standard_normal((m, dim))
    return u / np.linalg.norm(u, axis=1, keepdims=True)
