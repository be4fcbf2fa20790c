"""Wall meshes read from files: formats, orientation, closure and the errors a user sees.

Every mesh is written with meshio into pytest's ``tmp_path`` and read back.
"""

from __future__ import annotations

import numpy as np
import pytest

meshio = pytest.importorskip("meshio")

from sphcore.errors import CaseError  # noqa: E402
from sphcore.geometry.faces import signed_measure  # noqa: E402
from sphcore.geometry.meshfile import check_closed, read_wall_mesh  # noqa: E402

KEY = "walls[0].mesh"

# unit cube: point i = (x, y, z) with i = x + 2 y + 4 z; quads counter-clockwise seen from outside
CUBE_POINTS = np.array([[i & 1, (i >> 1) & 1, (i >> 2) & 1] for i in range(8)], dtype=float)
CUBE_QUADS = np.array([[0, 2, 3, 1], [4, 5, 7, 6], [0, 1, 5, 4],
                       [2, 6, 7, 3], [0, 4, 6, 2], [1, 3, 7, 5]], dtype=np.int32)
CUBE_TRIS = np.concatenate([CUBE_QUADS[:, [0, 1, 2]], CUBE_QUADS[:, [0, 2, 3]]])


@pytest.fixture
def case_file(tmp_path):
    return tmp_path / "case.toml"


def write(path, points, cells, **kw):
    meshio.write(path, meshio.Mesh(np.asarray(points, float), cells), **kw)
    return path


def expect_error(case_file, path, *words, dim=3, closed=False):
    """Read (and with ``closed`` check) ``path``; the CaseError must name file, key and words."""
    with pytest.raises(CaseError) as info:
        verts = read_wall_mesh(path, dim, KEY, case_file)
        if closed:
            check_closed(verts, path, KEY, case_file)
    msg = str(info.value)
    assert info.value.file == str(case_file) and info.value.key == KEY
    assert path.name in msg and KEY in msg and str(case_file) in msg
    for w in words:
        assert w in msg, msg
    return msg


@pytest.mark.parametrize("name, kw", [("cube.stl", {"binary": False}), ("cube.stl", {"binary": True}),
                                      ("cube.obj", {}), ("cube.vtu", {}), ("cube.ply", {}),
                                      ("cube.vtk", {})])
def test_cube_of_triangles_in_every_format(tmp_path, case_file, name, kw):
    path = write(tmp_path / name, CUBE_POINTS, [("triangle", CUBE_TRIS)], **kw)
    if name == "cube.stl":
        assert path.read_bytes().startswith(b"solid") != kw["binary"]
    verts = read_wall_mesh(path, 3, KEY, case_file)
    assert verts.shape == (12, 3, 3) and verts.dtype == np.float64 and verts.flags.c_contiguous
    assert abs(signed_measure(verts) - 1.0) < 1e-12
    check_closed(verts, path, KEY, case_file)
    assert len(np.unique(verts.reshape(-1, 3), axis=0)) == 8
    normals = np.cross(verts[:, 1] - verts[:, 0], verts[:, 2] - verts[:, 0])
    outward = np.einsum("ij,ij->i", normals, verts.mean(axis=1) - 0.5)
    assert np.all(outward > 0)


def test_cube_of_quads_is_split_into_twelve_triangles(tmp_path, case_file):
    path = write(tmp_path / "quads.vtu", CUBE_POINTS, [("quad", CUBE_QUADS)])
    verts = read_wall_mesh(path, 3, KEY, case_file)
    assert verts.shape == (12, 3, 3)
    assert abs(signed_measure(verts) - 1.0) < 1e-12
    area = 0.5 * np.linalg.norm(np.cross(verts[:, 1] - verts[:, 0], verts[:, 2] - verts[:, 0]), axis=1)
    assert np.allclose(area, 0.5)
    check_closed(verts, path, KEY, case_file)


def test_unshared_points_are_merged_before_the_closure_check(tmp_path, case_file):
    soup = CUBE_POINTS[CUBE_TRIS].reshape(-1, 3)  # 36 points, three per triangle
    path = write(tmp_path / "soup.vtu", soup, [("triangle", np.arange(36).reshape(12, 3))])
    verts = read_wall_mesh(path, 3, KEY, case_file)
    check_closed(verts, path, KEY, case_file)
    assert abs(signed_measure(verts) - 1.0) < 1e-12


def test_inward_cube_has_negative_volume(tmp_path, case_file):
    path = write(tmp_path / "inward.obj", CUBE_POINTS, [("triangle", CUBE_TRIS[:, ::-1])])
    verts = read_wall_mesh(path, 3, KEY, case_file)
    check_closed(verts, path, KEY, case_file)
    assert abs(signed_measure(verts) + 1.0) < 1e-12


def test_cube_with_a_missing_triangle_is_not_closed(tmp_path, case_file):
    path = write(tmp_path / "open.stl", CUBE_POINTS, [("triangle", CUBE_TRIS[1:])])
    assert read_wall_mesh(path, 3, KEY, case_file).shape == (11, 3, 3)
    expect_error(case_file, path, "not closed", "3 offending edge", closed=True)


def test_cube_with_a_flipped_triangle_is_inconsistent(tmp_path, case_file):
    tris = CUBE_TRIS.copy()
    tris[4] = tris[4, ::-1]
    path = write(tmp_path / "flipped.vtu", CUBE_POINTS, [("triangle", tris)])
    msg = expect_error(case_file, path, "inconsistent orientation", "3 offending edge", closed=True)
    assert "not closed" not in msg


def test_fin_on_a_cube_is_non_manifold(tmp_path, case_file):
    pts = np.vstack([CUBE_POINTS, [[0.5, -1.0, 0.0]]])
    tris = np.vstack([CUBE_TRIS, [[0, 1, 8]]])
    path = write(tmp_path / "fin.vtu", pts, [("triangle", tris)])
    expect_error(case_file, path, "non-manifold edge", "1 offending edge", closed=True)


def test_degenerate_triangle(tmp_path, case_file):
    pts = np.vstack([CUBE_POINTS, [[0.5, 0.0, 0.0]]])
    tris = np.vstack([CUBE_TRIS, [[0, 8, 1]]])  # three points on one line
    path = write(tmp_path / "degenerate.vtu", pts, [("triangle", tris)])
    expect_error(case_file, path, "1 degenerate triangle", "first face 12")


def test_non_convex_polygon_is_refused(tmp_path, case_file):
    pts = [[0, 0, 0], [2, 0, 0], [1, 0.5, 0], [2, 2, 0], [0, 2, 0]]  # dart: vertex 2 is reflex
    path = write(tmp_path / "dart.vtu", pts, [("polygon", np.array([[1, 2, 3, 4, 0]]))])
    expect_error(case_file, path, "non-convex polygon")
    pts.append([1, -0.5, 0])
    path = write(tmp_path / "pentagon.vtu", pts, [("polygon", np.array([[0, 5, 1, 3, 4]]))])
    verts = read_wall_mesh(path, 3, KEY, case_file)
    area = 0.5 * np.cross(verts[:, 1] - verts[:, 0], verts[:, 2] - verts[:, 0])
    assert verts.shape == (3, 3, 3) and np.allclose(area.sum(axis=0), [0, 0, 4.5])


def test_missing_file(tmp_path, case_file):
    expect_error(case_file, tmp_path / "nowhere.stl", "no such file")


@pytest.mark.parametrize("name, data, words", [
    ("garbage.stl", bytes(range(256)) * 3, "cannot be read"),
    ("garbage.vtu", bytes(range(256)) * 3, "cannot be read"),  # meshio calls sys.exit here
    ("garbage.obj", bytes(range(256)) * 3, "cannot be read"),
    ("oneline.stl", b"\x80" * 300, "no points and no cells"),  # meshio: an empty mesh
    ("empty.stl", b"", "no points and no cells"),
])
def test_garbage_bytes(tmp_path, case_file, capsys, name, data, words):
    path = tmp_path / name
    path.write_bytes(data)
    expect_error(case_file, path, words)
    out = capsys.readouterr()
    assert out.out == "" and out.err == ""  # meshio's own prints are swallowed


def test_unknown_extension(tmp_path, case_file):
    path = tmp_path / "wall.xyz"
    path.write_text("0 0 0\n")
    expect_error(case_file, path, "unknown mesh format", ".xyz")


def test_nan_coordinates(tmp_path, case_file):
    path = tmp_path / "nan.obj"
    path.write_text("v 0 0 nan\nv 1 0 0\nv 0 1 0\nf 1 2 3\n")
    expect_error(case_file, path, "NaN or infinite", "first point 0")


def test_no_usable_cells(tmp_path, case_file):
    path = write(tmp_path / "points.vtu", CUBE_POINTS, [("vertex", np.arange(8).reshape(-1, 1))])
    expect_error(case_file, path, "no usable cells", "vertex")


SQUARE = np.array([[0, 0, 0], [1, 0, 0], [1, 1, 0], [0, 1, 0]], dtype=float)
LOOP = np.array([[0, 1], [1, 2], [2, 3], [3, 0]])


def test_2d_square_of_lines(tmp_path, case_file):
    path = write(tmp_path / "square.vtu", SQUARE, [("line", LOOP)])
    verts = read_wall_mesh(path, 2, KEY, case_file)
    assert verts.shape == (4, 2, 2) and verts.dtype == np.float64 and verts.flags.c_contiguous
    assert abs(signed_measure(verts) - 1.0) < 1e-12
    check_closed(verts, path, KEY, case_file)
    path = write(tmp_path / "clockwise.vtk", SQUARE, [("line", LOOP[::-1, ::-1])])
    assert abs(signed_measure(read_wall_mesh(path, 2, KEY, case_file)) + 1.0) < 1e-12


@pytest.mark.parametrize("tris", [[[0, 1, 2], [0, 2, 3]], [[0, 1, 2], [0, 3, 2]]])  # 2nd: one clockwise
def test_2d_triangulated_square_gives_its_boundary(tmp_path, case_file, tris):
    path = write(tmp_path / "region.vtu", SQUARE, [("triangle", np.array(tris))])
    verts = read_wall_mesh(path, 2, KEY, case_file)
    assert verts.shape == (4, 2, 2)
    assert abs(signed_measure(verts) - 1.0) < 1e-12
    check_closed(verts, path, KEY, case_file)
    t = verts[:, 1] - verts[:, 0]
    left = np.stack([-t[:, 1], t[:, 0]], axis=1)  # the region lies on this side
    assert np.all(np.einsum("ij,ij->i", left, 0.5 - verts.mean(axis=1)) > 0)


def test_2d_quads_region(tmp_path, case_file):
    pts = [[0, 0], [1, 0], [2, 0], [0, 1], [1, 1], [2, 1]]
    quads = np.array([[0, 1, 4, 3], [1, 2, 5, 4]])
    path = write(tmp_path / "quads.vtu", np.c_[pts, np.zeros(6)], [("quad", quads)])
    verts = read_wall_mesh(path, 2, KEY, case_file)
    assert verts.shape == (6, 2, 2)
    assert abs(signed_measure(verts) - 2.0) < 1e-12
    check_closed(verts, path, KEY, case_file)


def test_2d_mesh_off_the_plane(tmp_path, case_file):
    pts = SQUARE.copy()
    pts[2, 2] = 1e-3
    path = write(tmp_path / "tilted.vtu", pts, [("line", LOOP)])
    expect_error(case_file, path, "z != 0", dim=2)


def test_2d_open_polyline(tmp_path, case_file):
    path = write(tmp_path / "open.vtu", SQUARE, [("line", LOOP[:3])])
    assert read_wall_mesh(path, 2, KEY, case_file).shape == (3, 2, 2)
    expect_error(case_file, path, "not closed", "2 offending segment", dim=2, closed=True)


def test_2d_reversed_segment(tmp_path, case_file):
    lines = LOOP.copy()
    lines[1] = lines[1, ::-1]
    path = write(tmp_path / "reversed.vtu", SQUARE, [("line", lines)])
    expect_error(case_file, path, "inconsistent orientation", dim=2, closed=True)


def test_2d_zero_length_segment(tmp_path, case_file):
    lines = np.vstack([LOOP, [[0, 4]]])  # point 4 repeats point 0: merged, so length 0
    path = write(tmp_path / "zero.vtu", np.vstack([SQUARE, SQUARE[:1]]), [("line", lines)])
    expect_error(case_file, path, "1 degenerate segment", "first face 4", dim=2)
