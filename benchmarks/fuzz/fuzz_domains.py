"""Random domains and trajectories for ``fuzz_faces.py`` (and ``tests/test_reflective_faces.py``).

The domain kinds (obstacles, non-convex tanks, plates, sheets; 2D and 3D), the
admissibility of a point (inside every plane and closed wall, at least r from every face),
the start points (10 % touching a wall) and the scenes of n trajectories; the kinds and
their distributions are described in ``fuzz_faces.py``.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from sphcore.geometry.faces import Faces, box, closed_wall, polygon, polyline, signed_measure
from sphcore.geometry.planes import Planes

#: relative contact allowance of the kernel (collision.TOL_REL)
TOL_REL = 1e-9

KINDS = ("obstacles-2d", "obstacles-3d", "nonconvex-2d", "nonconvex-3d",
         "plate-2d", "plate-3d", "sheet-2d", "sheet-3d")


@dataclass
class Domain:
    """Walls (``planes`` or None, ``faces`` or None), a box ``lo``, ``hi`` (m) holding the
    fluid region, a length ``size`` (m), and for plates the plate's mid-plane
    (``plate_point``, ``plate_normal``) that must not be crossed."""

    dim: int
    planes: Planes | None
    faces: Faces | None
    lo: np.ndarray
    hi: np.ndarray
    size: float
    plate_point: np.ndarray | None = None
    plate_normal: np.ndarray | None = None


def random_rotation(rng, dim):
    """A random proper rotation (dim, dim) (QR of a Gaussian matrix, det +1)."""
    q, rr = np.linalg.qr(rng.standard_normal((dim, dim)))
    q = q * np.sign(np.diag(rr))
    if np.linalg.det(q) < 0:
        q[:, 0] = -q[:, 0]
    return q


def random_directions(rng, m, dim):
    u = rng.standard_normal((m, dim))
    return u / np.linalg.norm(u, axis=1, keepdims=True)


def turned_box(lo, hi, rotation, centre=None):
    """Faces of the box [lo, hi] turned by ``rotation`` about ``centre`` (default: its own
    centre); a polygon of the turned corners in 2D, the turned triangles in 3D."""
    lo, hi = np.asarray(lo, float), np.asarray(hi, float)
    c = (lo + hi) / 2 if centre is None else np.asarray(centre, float)
    if lo.size == 2:
        corners = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
        return polygon((corners - c) @ rotation.T + c)
    return np.ascontiguousarray((box(lo, hi) - c) @ rotation.T + c)


def star_polygon(rng, centre, radius):
    """A random simple star-shaped polygon about ``centre``: 4 to 12 spikes of radius
    0.6..1 ``radius`` between concave corners at 0.1..0.45 ``radius``."""
    k = int(rng.integers(4, 13))
    ang = (np.arange(2 * k) + rng.uniform(-0.3, 0.3, 2 * k)) * (np.pi / k)
    rad = np.where(np.arange(2 * k) % 2 == 0, rng.uniform(0.6, 1.0, 2 * k), rng.uniform(0.1, 0.45, 2 * k))
    return centre + radius * rad[:, None] * np.stack([np.cos(ang), np.sin(ang)], axis=1)


def heightmap_mesh(rng, origin, scale):
    """Outward-oriented triangles of a step- or L-shaped solid: columns of boxes over an
    nx x ny grid (random spacings, total about ``scale``), column heights 1..3 layers, not
    all equal (at least one step). Each boundary square of a cell is two triangles."""
    while True:
        nx, ny = int(rng.integers(1, 4)), int(rng.integers(1, 4))
        if nx * ny == 1:
            continue
        h = rng.integers(1, 4, (nx, ny))
        if h.max() > h.min():
            break
    nz = int(h.max())
    lines = [np.concatenate([[0.0], np.cumsum(rng.uniform(0.5, 1.5, m))]) for m in (nx, ny, nz)]
    lines = [origin[j] + scale * g / g[-1] * (m / 3.0) for j, (g, m) in enumerate(zip(lines, (nx, ny, nz)))]
    filled = np.zeros((nx + 2, ny + 2, nz + 2), bool)
    for i in range(nx):
        for j in range(ny):
            filled[i + 1, j + 1, 1:h[i, j] + 1] = True
    tris = []
    for i, j, k in zip(*np.nonzero(filled)):
        for axis in range(3):
            for side in (0, 1):
                nb = [i, j, k]
                nb[axis] += 1 if side else -1
                if filled[tuple(nb)]:
                    continue
                # the square of cell (i, j, k) at lines[axis][cell + side], outward along +-axis
                a1, a2 = (axis + 1) % 3, (axis + 2) % 3
                idx = [i - 1, j - 1, k - 1]
                fixed = lines[axis][idx[axis] + side]
                s0, s1 = lines[a1][idx[a1]], lines[a1][idx[a1] + 1]
                t0, t1 = lines[a2][idx[a2]], lines[a2][idx[a2] + 1]
                quad = []
                for s, t in ((s0, t0), (s1, t0), (s1, t1), (s0, t1)):
                    p = np.empty(3)
                    p[axis], p[a1], p[a2] = fixed, s, t
                    quad.append(p)
                # (a1, a2, axis) is right-handed: counter-clockwise in (a1, a2) faces +axis
                if not side:
                    quad = quad[::-1]
                tris += [(quad[0], quad[1], quad[2]), (quad[0], quad[2], quad[3])]
    return np.ascontiguousarray(np.array(tris))


def make_domain(kind, rng, r):
    """A random domain of ``kind`` for particles of radius up to r (m); its scale is
    about 1 m, shifted by up to 10 m from the origin."""
    dim = 2 if kind.endswith("2d") else 3
    shift = rng.uniform(-10.0, 10.0, dim)
    turn = rng.uniform() < 0.5
    if kind.startswith("nonconvex"):
        if dim == 2:
            R = rng.uniform(0.5, 1.0)
            faces = closed_wall(polygon(star_polygon(rng, shift, R)), fluid_inside=True)
        else:
            tris = heightmap_mesh(rng, np.zeros(3), rng.uniform(0.8, 1.6))
            assert signed_measure(tris) > 0, "the mesh must be built with outward normals"
            if turn:
                tris = tris @ random_rotation(rng, 3).T
            faces = closed_wall(tris + shift, fluid_inside=True)
        v = faces.verts.reshape(-1, dim)
        lo, hi = v.min(axis=0), v.max(axis=0)
        return Domain(dim, None, faces, lo, hi, float((hi - lo).max()))
    lo = shift
    hi = shift + rng.uniform(0.5, 1.5, dim)
    size = float((hi - lo).max())
    planes = Planes.box(lo, hi)
    if kind.startswith("obstacles"):
        faces = Faces.empty(dim)
        for _ in range(int(rng.integers(1, 7))):
            c = rng.uniform(lo, hi)
            half = size * rng.uniform(0.03, 0.2, dim)
            rot = random_rotation(rng, dim) if rng.uniform() < 0.5 else np.eye(dim)
            faces = faces.concat(closed_wall(turned_box(c - half, c + half, rot), fluid_inside=False))
        return Domain(dim, planes, faces, lo, hi, size)
    # a plate through a point in the middle half of the tank, wider than the tank
    c = lo + (hi - lo) * rng.uniform(0.25, 0.75, dim)
    rot = random_rotation(rng, dim) if turn else np.eye(dim)[:, rng.permutation(dim)]
    if np.linalg.det(rot) < 0:
        rot[:, 1] = -rot[:, 1]
    normal = rot[:, 0]
    # half-width: every point of the tank lies within |x - centre| + |centre - c| of c; no
    # wider, since the face grid (and a long step's cost) grows with the plate
    w = 1.01 * (0.5 * float(np.linalg.norm(hi - lo)) + float(np.linalg.norm(c - (lo + hi) / 2))) + r
    if kind.startswith("plate"):
        half = np.full(dim, w)
        half[0] = r  # thickness exactly 2r
        verts = turned_box(-half, half, rot, np.zeros(dim)) + c
        faces = closed_wall(verts, fluid_inside=False)
    elif dim == 2:
        t = rot[:, 1]
        faces = Faces(polyline([c - w * t, c + w * t]))
    else:
        sq = np.array([[-w, -w], [w, -w], [w, w], [-w, w]])
        p = c + sq[:, :1] * rot[:, 1] + sq[:, 1:] * rot[:, 2]
        faces = Faces(np.ascontiguousarray(np.array([[p[0], p[1], p[2]], [p[0], p[2], p[3]]])))
    return Domain(dim, planes, faces, lo, hi, size, c, normal)


def admissible(dom, pos, radius):
    """(n,) bool: inside every plane, at least r - 1e-9 r from every face, in the fluid."""
    lim = radius - TOL_REL * radius
    ok = np.ones(pos.shape[0], bool)
    if dom.planes is not None:
        ok &= (dom.planes.distances(pos) >= lim[:, None]).all(axis=1)
    if dom.faces is not None and dom.faces.count:
        ok &= dom.faces.distances(pos) >= lim
        ok &= dom.faces.in_fluid(pos)
    return ok


def on_wall_points(rng, dom, r, m):
    """(m', dim) candidate centres at distance r from a random wall (not yet checked)."""
    dim = dom.dim
    pts = []
    if dom.faces is not None and dom.faces.count:
        v = dom.faces.verts
        f = rng.integers(0, v.shape[0], m)
        w = rng.uniform(0.0, 1.0, (m, dim))
        if dim == 3:
            flip = w[:, 1] + w[:, 2] > 1.0
            w[flip, 1:] = 1.0 - w[flip, 1:]
            w[:, 0] = 1.0 - w[:, 1] - w[:, 2]
        else:
            w[:, 1] = 1.0 - w[:, 0]
        q = np.einsum("mj,mjd->md", w, v[f])
        n = dom.faces.normals()[f]
        if not dom.faces.groups:  # open: either side
            n *= rng.choice([-1.0, 1.0], (m, 1))
        pts.append(q + r * n)
    if dom.planes is not None:
        p = rng.uniform(dom.lo + r, dom.hi - r, (m, dim))
        j = rng.integers(0, dim, m)
        side = rng.integers(0, 2, m)
        p[np.arange(m), j] = np.where(side == 1, dom.hi[j] - r, dom.lo[j] + r)
        pts.append(p)
    return np.concatenate(pts)


def sample_starts(rng, dom, radius, on_wall=0.1):
    """(n, dim) admissible start points for particles of ``radius`` (n,): uniform in the
    box [lo, hi], a fraction ``on_wall`` at distance r (the largest radius) from a wall."""
    n = radius.size
    r = float(radius.max())
    out = np.empty((n, dom.dim))
    have = 0
    n_wall = int(on_wall * n) if np.all(radius == r) else 0  # touching needs one radius
    for _ in range(50):
        if have >= n_wall:
            break
        cand = on_wall_points(rng, dom, r, 2 * (n_wall - have) + 16)
        cand = cand[admissible(dom, cand, np.full(len(cand), r))][: n_wall - have]
        out[have:have + len(cand)] = cand
        have += len(cand)
    for _ in range(1000):
        if have == n:
            break
        cand = rng.uniform(dom.lo, dom.hi, (2 * (n - have) + 64, dom.dim))
        cand = cand[admissible(dom, cand, np.full(len(cand), r))][: n - have]
        out[have:have + len(cand)] = cand
        have += len(cand)
    if have < n:
        raise RuntimeError("no room for the particles")
    return np.ascontiguousarray(out[rng.permutation(n)])


@dataclass
class Scene:
    dom: Domain
    radius: np.ndarray
    pos0: np.ndarray
    pos1: np.ndarray
    vel: np.ndarray
    acc: np.ndarray
    cr: float
    contact: bool


def make_scene(kind, rng, n, cr=None, accelerate=None, contact=None, max_step=100.0, on_wall=0.1):
    """A random domain of ``kind`` with n trajectories (see the module docstring)."""
    dim = 2 if kind.endswith("2d") else 3
    # radius relative to a 1 m domain: 3 mm .. 50 mm in 2D, 10 .. 50 mm in 3D
    r = 10.0 ** rng.uniform(-2.5 if dim == 2 else -2.0, -1.3)
    dom = make_domain(kind, rng, r)
    one_r = kind.startswith(("plate", "sheet")) or rng.uniform() < 0.5
    radius = np.full(n, r) if one_r else r * rng.uniform(0.3, 1.0, n)
    pos0 = sample_starts(rng, dom, radius, on_wall)
    length = dom.size * 10.0 ** rng.uniform(-4.0, math.log10(max_step), (n, 1))
    step = random_directions(rng, n, dim) * length
    step[rng.uniform(size=n) < 0.02] = 0.0
    dt = 1e-3
    vel = step / dt
    acc = np.zeros((n, dim))
    if accelerate if accelerate is not None else rng.uniform() < 0.5:
        acc = random_directions(rng, n, dim) * 10.0 ** rng.uniform(-1, 4, (n, 1))
        step += 0.5 * dt * dt * acc
        vel += dt * acc
    if cr is None:
        u = rng.uniform()
        cr = 0.0 if u < 0.2 else 1.0 if u < 0.4 else float(rng.uniform())
    if contact is None:
        contact = bool(rng.uniform() < 0.5)
    return Scene(dom, radius, pos0, np.ascontiguousarray(pos0 + step), vel, acc, cr, contact)
