"""Wall meshes read from files (through meshio), checked for closure and measured.

Coordinates are taken as they are in the file, in metres (m); no unit conversion.
A wall is returned as ``verts`` of shape ``(nf, dim, dim)`` (float64, C-contiguous):
in 3D ``nf`` triangles of 3 vertices x 3 coordinates, in 2D ``nf`` segments of
2 vertices x 2 coordinates. Every problem raises :class:`sphcore.errors.CaseError`
naming the case file, the case key and the mesh file.
"""

from __future__ import annotations

import contextlib
import io
import os
import stat
import warnings
from pathlib import Path

import numpy as np

from sphcore.errors import CaseError

#: relative tolerance (times the bounding-box size, squared for areas) below which
#: a segment, triangle or cell counts as degenerate, and above which a 2D z is refused
REL_TOL = 1e-12
SURFACE_TYPES = ("triangle", "quad", "polygon")
#: largest mesh file read (bytes): only a regular file of at most this size is opened
MAX_MESH_BYTES = 1 << 30


def _fail(case_file, key, path, what: str):
    return CaseError(case_file, key, f"mesh file '{path}': {what}")


def _load(path: Path, key, case_file):
    """Read ``path`` with meshio, turning every failure into a CaseError."""
    import meshio

    try:
        st = os.stat(path)  # through a link: what would be read (a link to /dev/zero is a device)
    except FileNotFoundError:
        raise _fail(case_file, key, path, "no such file (expected a wall mesh file)") from None
    except (OSError, ValueError) as e:  # a name too long, a NUL byte, no permission
        raise _fail(case_file, key, path, f"cannot read: {getattr(e, 'strerror', None) or e}") from None
    if stat.S_ISDIR(st.st_mode):
        raise _fail(case_file, key, path, "is a directory (expected a wall mesh file)")
    if not stat.S_ISREG(st.st_mode):
        raise _fail(case_file, key, path, "not a regular file (a device, a pipe, a socket): expected a wall "
                    "mesh file")
    if st.st_size > MAX_MESH_BYTES:
        raise _fail(case_file, key, path, f"{st.st_size / 2**20:.0f} MiB, larger than {MAX_MESH_BYTES >> 20} MiB: "
                    "expected a wall mesh of a size a run can hold")
    try:
        with open(path, "rb"):
            pass
    except OSError as e:
        raise _fail(case_file, key, path, f"cannot read: {e.strerror}") from None
    known = getattr(meshio, "extension_to_filetypes", None)
    sfx = [s.lower() for s in path.suffixes]
    if known is not None and not any("".join(sfx[i:]) in known for i in range(len(sfx))):
        raise _fail(case_file, key, path, f"unknown mesh format '{path.suffix}' (expected an "
                    "extension meshio reads: .stl, .obj, .vtu, .vtk, .ply, .msh, ...)")
    said = io.StringIO()  # meshio prints reader errors and calls sys.exit on some failures
    try:
        with contextlib.redirect_stdout(said), contextlib.redirect_stderr(said), \
                warnings.catch_warnings(), np.errstate(all="ignore"):
            warnings.simplefilter("ignore")
            return meshio.read(path)
    except (Exception, SystemExit) as e:
        reason = str(e) if not isinstance(e, SystemExit) else ""
        reason = reason or " ".join(said.getvalue().replace("Error:", "").split()) or type(e).__name__
        raise _fail(case_file, key, path, f"cannot be read as a {path.suffix} mesh "
                    f"({reason}); expected a valid mesh file") from None


def _fan(cells: np.ndarray) -> np.ndarray:
    """Split polygons (n, k) into triangles (n*(k-2), 3) by a fan from vertex 0."""
    k = cells.shape[1]
    tris = [np.stack([cells[:, 0], cells[:, i], cells[:, i + 1]], axis=1) for i in range(1, k - 1)]
    return np.stack(tris, axis=1).reshape(-1, 3)


def _boundary_2d(cells, X, tol_area, fail):
    """Boundary edges (m, 2) of a 2D region made of polygon cells, region on their left."""
    edges = []
    for c in cells:
        p = X[c]  # (n, k, 2)
        area = 0.5 * np.sum(p[..., 0] * np.roll(p[..., 1], -1, axis=1)
                            - np.roll(p[..., 0], -1, axis=1) * p[..., 1], axis=1)
        bad = np.flatnonzero(np.abs(area) <= tol_area)
        if bad.size:
            raise fail(f"{bad.size} degenerate cell(s) of area <= {tol_area:.3g} m^2, "
                       f"first cell {bad[0]} of its block (expected cells of positive area)")
        c = np.where((area < 0)[:, None], c[:, ::-1], c)  # counter-clockwise cells
        edges.append(np.stack([c, np.roll(c, -1, axis=1)], axis=2).reshape(-1, 2))
    e = np.concatenate(edges)
    _, inv, cnt = np.unique(np.sort(e, axis=1), axis=0, return_inverse=True, return_counts=True)
    inv = inv.reshape(-1)
    if np.any(cnt > 2):
        raise fail(f"{np.sum(cnt > 2)} edge(s) shared by more than two cells "
                   "(expected a 2D region without overlapping cells)")
    shared = cnt[inv] == 2
    same = np.zeros(cnt.size, int)
    np.add.at(same, inv[shared], np.where(e[shared, 0] < e[shared, 1], 1, -1))
    if np.any(same != 0):
        raise fail(f"{np.sum(same != 0)} inner edge(s) traversed the same way by both cells "
                   "(expected a 2D region without folded or overlapping cells)")
    return e[cnt[inv] == 1]


def read_wall_mesh(path, dim: int, key: str, case_file) -> np.ndarray:
    """Read a wall mesh file and return its faces ``verts`` (float64, C-contiguous).

    ``dim = 3``: triangle, quad and (convex) polygon cells give triangles (nf, 3, 3),
    polygons split by a fan from their first vertex, orientation kept.
    ``dim = 2``: "line" cells give segments (nf, 2, 2) as they are; otherwise
    triangle/quad/polygon cells give the region's boundary edges (those of exactly one
    cell), oriented counter-clockwise around the region (region on their left). In 2D
    every z must be 0 (|z| <= 1e-12 x the bounding-box size). Coordinates in m; vertices
    that coincide exactly are merged. ``key``/``case_file`` name the case entry in errors.
    """
    path = Path(path)
    fail = lambda what: _fail(case_file, key, path, what)  # noqa: E731
    mesh = _load(path, key, case_file)
    pts = np.asarray(mesh.points, dtype=np.float64)
    if pts.size == 0:  # e.g. meshio reads an STL of garbage without line breaks as empty
        raise fail(f"no points and no cells (expected a wall mesh; is it a valid {path.suffix} file?)")
    if pts.ndim != 2 or pts.shape[1] not in (2, 3):
        raise fail(f"points of shape {pts.shape}: expected 2 or 3 coordinates per point")
    if pts.shape[1] == 2:
        pts = np.concatenate([pts, np.zeros((len(pts), 1))], axis=1)
    blocks = [(c.type, np.asarray(c.data, dtype=np.int64)) for c in mesh.cells if len(c.data)]
    found = sorted({t for t, _ in blocks})
    lines = [d for t, d in blocks if t == "line"]
    surf = [d for t, d in blocks if t.startswith(SURFACE_TYPES) and d.ndim == 2 and d.shape[1] >= 3]
    use = surf if dim == 3 else (lines or surf)
    if not use:
        want = "triangle, quad or polygon" if dim == 3 else "line, triangle, quad or polygon"
        raise fail(f"no usable cells (found: {', '.join(found) or 'none'}; "
                   f"expected {want} cells for a {dim}D wall)")
    for d in use:
        if d.min() < 0 or d.max() >= len(pts):
            raise fail(f"a cell refers to a point index outside 0..{len(pts) - 1}")
    used = np.unique(np.concatenate([d.reshape(-1) for d in use]))
    P = pts[used]
    nonfinite = np.flatnonzero(~np.all(np.isfinite(P), axis=1))
    if nonfinite.size:
        raise fail(f"{nonfinite.size} point(s) with NaN or infinite coordinates, first point "
                   f"{used[nonfinite[0]]} (expected finite coordinates in m)")
    size = float(np.linalg.norm(P[:, :dim].max(axis=0) - P[:, :dim].min(axis=0)))
    if dim == 2:
        zbad = np.flatnonzero(np.abs(P[:, 2]) > REL_TOL * size)
        if zbad.size:
            raise fail(f"{zbad.size} point(s) with z != 0, first {P[zbad[0]].tolist()} "
                       "(expected a 2D mesh in the plane z = 0)")
    X, inv = np.unique(P[:, :dim] + 0.0, axis=0, return_inverse=True)  # exact merge, -0 == 0
    ids = np.full(len(pts), -1, dtype=np.int64)
    ids[used] = inv.reshape(-1)
    use = [ids[d] for d in use]
    if dim == 3:
        faces = []
        for c in use:
            tri = _fan(c)
            if c.shape[1] > 3:  # a fan is right only for convex polygons
                cr = np.cross(X[tri[:, 1]] - X[tri[:, 0]], X[tri[:, 2]] - X[tri[:, 0]])
                cr = cr.reshape(len(c), -1, 3)
                folded = np.any(np.einsum("nkj,nj->nk", cr, cr.sum(axis=1)) < 0, axis=1)
                if np.any(folded):
                    raise fail(f"{folded.sum()} non-convex polygon cell(s) of "
                               f"{c.shape[1]} vertices (expected convex polygons)")
            faces.append(tri)
        faces = np.concatenate(faces)
    elif lines:
        faces = np.concatenate(use)
    else:
        faces = _boundary_2d(use, X, REL_TOL * size * size, fail)
    verts = np.ascontiguousarray(X[faces], dtype=np.float64)
    if dim == 3:
        meas = 0.5 * np.linalg.norm(np.cross(verts[:, 1] - verts[:, 0], verts[:, 2] - verts[:, 0]), axis=1)
        tol, what = REL_TOL * size * size, "triangle(s) of area"
    else:
        meas = np.linalg.norm(verts[:, 1] - verts[:, 0], axis=1)
        tol, what = REL_TOL * size, "segment(s) of length"
    bad = np.flatnonzero(meas <= tol)
    if bad.size:
        raise fail(f"{bad.size} degenerate {what} <= {tol:.3g}, first face {bad[0]} "
                   "(expected faces of positive size)")
    return verts


def _fmt(points) -> str:
    return " -> ".join("(" + ", ".join(f"{v:.9g}" for v in p) + ")" for p in points)


def check_closed(verts: np.ndarray, file, key, case_file) -> None:
    """Check that a wall (a tank, an obstacle) is closed and consistently oriented.

    2D (nf, 2, 2): every vertex (exact coordinates) starts exactly one segment and ends
    exactly one. 3D (nf, 3, 3): every undirected edge is shared by exactly two
    triangles, traversed in opposite directions. ``file`` is the mesh file named in the
    error; ``key``/``case_file`` name the case entry. Raises CaseError otherwise.
    """
    verts = np.asarray(verts, dtype=np.float64)
    nf, dim = verts.shape[0], verts.shape[-1]
    if nf == 0:
        raise _fail(case_file, key, file, "not closed: no faces (expected a closed wall)")
    _, vid = np.unique(verts.reshape(-1, dim) + 0.0, axis=0, return_inverse=True)
    vid = vid.reshape(nf, dim)
    problems = []
    if dim == 2:
        n = vid.max() + 1
        starts, ends = np.bincount(vid[:, 0], minlength=n), np.bincount(vid[:, 1], minlength=n)
        total = starts + ends
        kinds = [("not closed", total == 1), ("non-manifold vertex", total > 2),
                 ("inconsistent orientation", (total == 2) & (starts != 1))]
        for name, bad_v in kinds:
            seg = np.flatnonzero(bad_v[vid[:, 0]] | bad_v[vid[:, 1]])
            if seg.size:
                problems.append(f"{name}: {seg.size} offending segment(s), first "
                                f"{seg[0]} {_fmt(verts[seg[0]])}")
        expect = "a closed polyline set, each vertex starting one segment and ending one"
    else:
        e = np.stack([vid, np.roll(vid, -1, axis=1)], axis=2).reshape(-1, 2)
        _, inv, cnt = np.unique(np.sort(e, axis=1), axis=0, return_inverse=True, return_counts=True)
        inv = inv.reshape(-1)
        turn = np.zeros(cnt.size, dtype=np.int64)
        np.add.at(turn, inv, np.where(e[:, 0] < e[:, 1], 1, -1))
        kinds = [("not closed", cnt == 1), ("non-manifold edge", cnt > 2),
                 ("inconsistent orientation", (cnt == 2) & (turn != 0))]
        for name, bad_u in kinds:
            if bad_u.any():
                first = np.flatnonzero(bad_u[inv])[0]  # first directed edge, in face order
                tri, k = divmod(first, 3)
                problems.append(f"{name}: {bad_u.sum()} offending edge(s), first "
                                f"{_fmt(verts[tri][[k, (k + 1) % 3]])} (triangle {tri})")
        expect = "a closed surface, each edge shared by two triangles in opposite directions"
    if problems:
        raise _fail(case_file, key, file, "; ".join(problems) + f" (expected {expect})")
