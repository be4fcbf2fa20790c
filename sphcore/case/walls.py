"""``[[domain.walls]]``: finite walls from case.toml (boxes, polygons, polylines, meshes).

Each entry becomes faces (:class:`sphcore.geometry.faces.Faces`). Closed walls (box, polygon,
mesh) bound a region: with ``fluid = "outside"`` it is a solid obstacle, with
``fluid = "inside"`` it is the tank. A polyline is an open, two-sided thin wall. Every
problem is a :class:`CaseError` naming the file and the key.
"""

from __future__ import annotations

import numpy as np

from sphcore.case import defaults
from sphcore.case.options import validate_table
from sphcore.errors import CaseError
from sphcore.geometry.faces import Faces, box, closed_wall, polygon, polyline
from sphcore.geometry.meshfile import check_closed, read_wall_mesh


def _points(file, key, value, dim, least):
    try:
        p = np.asarray(value, dtype=float)
    except (TypeError, ValueError):
        p = np.zeros((0,))
    if p.ndim != 2 or p.shape[1] != dim or p.shape[0] < least or not np.all(np.isfinite(p)):
        raise CaseError(file, key, f"expected a list of at least {least} points of {dim} finite numbers")
    return p


def _vec(file, key, value, dim):
    if value is None or len(value) != dim:
        raise CaseError(file, key, f"required: a list of {dim} numbers")
    return np.asarray(value, float)


def _simple_polygon(file, key, p):
    """Refuse repeated points, no area (collinear points) and crossing edges (a polygon must
    be simple and enclose a region)."""
    seg = polygon(p)
    size = np.ptp(p, axis=0).max()
    length = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1)
    if np.any(length <= 1e-12 * size):
        raise CaseError(file, key, f"edge {int(np.argmin(length))} has zero length (repeated point)")
    k = len(seg)
    for i in range(k):
        for j in range(i + 2, k):
            if i == 0 and j == k - 1:
                continue  # neighbours through the closing edge
            if _cross(seg[i], seg[j]):
                raise CaseError(file, key, f"edges {i} and {j} cross: expected a simple polygon")
    with np.errstate(all="ignore"):  # in units of the polygon's size: no overflow on huge coordinates
        x, y = (p[:, 0] - p[0, 0]) / size, (p[:, 1] - p[0, 1]) / size
        area = 0.5 * abs(float(np.dot(x, np.roll(y, -1)) - np.dot(y, np.roll(x, -1))))
    if not area > 1e-12:
        raise CaseError(file, key, f"the polygon's area is {area:.3g} of its size squared (its points lie on one "
                        "line): expected points enclosing a region")


def _cross(s, t):
    def orient(a, b, c):
        return np.sign((b[0] - a[0]) * (c[1] - a[1]) - (b[1] - a[1]) * (c[0] - a[0]))
    return (orient(s[0], s[1], t[0]) * orient(s[0], s[1], t[1]) <= 0
            and orient(t[0], t[1], s[0]) * orient(t[0], t[1], s[1]) <= 0)


def parse_walls(file, entries, dim, case_dir) -> tuple[Faces, list[tuple[int, int]]]:
    """Faces of every ``[[domain.walls]]`` entry, in order, and each entry's faces
    (start, stop)."""
    faces = Faces.empty(dim)
    ranges = []
    for k, entry in enumerate(entries):
        key = f"domain.walls[{k}]"
        w = validate_table(defaults.WALL, entry, file, key)
        shape = w["shape"]
        inside = w["fluid"] == "inside"
        if shape is None:
            raise CaseError(file, f"{key}.shape", "required: box, polygon, polyline or mesh")
        if w["tank"] and w["motion"]:
            raise CaseError(file, f"{key}.motion", "a wall that moves with the tank (tank = true) has no motion "
                            "of its own")
        need = {"box": ("min", "max"), "polygon": ("points",), "polyline": ("points",), "mesh": ("file",)}[shape]
        for name in ("min", "max", "points", "file"):
            if name not in need and w[name] is not None:
                raise CaseError(file, f"{key}.{name}", f"not used by shape = {shape!r} (it takes {', '.join(need)})")
            if name in need and w[name] is None:
                raise CaseError(file, f"{key}.{name}", f"required by shape = {shape!r}")
        if shape == "box":
            lo, hi = _vec(file, f"{key}.min", w["min"], dim), _vec(file, f"{key}.max", w["max"], dim)
            if np.any(hi <= lo):
                raise CaseError(file, f"{key}.max", f"expected every component above min {lo.tolist()}")
            part = closed_wall(box(lo, hi), inside)
        elif shape == "polygon":
            if dim != 2:
                raise CaseError(file, f"{key}.shape", "polygon is 2D; in 3D give a box or a mesh file")
            p = _points(file, f"{key}.points", w["points"], 2, 3)
            _simple_polygon(file, f"{key}.points", p)
            part = closed_wall(polygon(p), inside)
        elif shape == "polyline":
            if dim != 2:
                raise CaseError(file, f"{key}.shape", "polyline is 2D; in 3D give a mesh file")
            if entry.get("fluid") is not None:
                raise CaseError(file, f"{key}.fluid", "a polyline is open: the fluid is on both sides")
            p = _points(file, f"{key}.points", w["points"], 2, 2)
            seg = polyline(p)
            length = np.linalg.norm(seg[:, 1] - seg[:, 0], axis=1)
            if np.any(length <= 1e-12 * max(np.ptp(p, axis=0).max(), 1e-300)):
                raise CaseError(file, f"{key}.points", f"segment {int(np.argmin(length))} has zero length "
                                "(repeated point)")
            part = Faces(seg)
        else:
            path = (case_dir / w["file"]) if case_dir is not None else w["file"]
            verts = read_wall_mesh(path, dim, f"{key}.file", file)
            check_closed(verts, path, f"{key}.file", file)
            part = closed_wall(verts, inside)
        ranges.append((faces.count, faces.count + part.count))
        faces = faces.concat(part)
    return faces, ranges
