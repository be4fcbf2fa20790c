"""A flat wall's terms do not depend on how its faces triangulate it.

The wall model's projector (the directions in which a particle's missing support is wall)
takes, from each face near the particle, the direction from the face's nearest point. Where
that point lies on an edge or vertex the face shares only with faces of its own plane (a
box's side split along a diagonal), the wall does not turn there: the face adds its normal,
not the radial direction, which would lie partly along the wall. These tests hold the share,
gradient, moment and projector of a box equal for three triangulations of its sides, and
check which parts of a mesh ``flat_parts`` calls flat.
"""

from __future__ import annotations

import numpy as np
import pytest

from sphcore.api import build_grid
from sphcore.geometry.faces import box
from sphcore_plugins.wall_integral.facewalls import flat_parts, point_terms, stamps_for

LO, HI = np.array([0.3, 0.3, 0.2]), np.array([0.5, 0.5, 0.3])
H = 0.02  # m: smoothing length (support 2h = 0.04 m)
KERNEL = 1  # Wendland C2
GRAVITY = np.array([0.0, 0.0, -9.81])


def _corners():
    return np.array([[LO[0] if i & 1 == 0 else HI[0], LO[1] if i & 2 == 0 else HI[1],
                      LO[2] if i & 4 == 0 else HI[2]] for i in range(8)])


QUADS = [(0, 2, 3, 1), (4, 5, 7, 6), (0, 1, 5, 4), (2, 6, 7, 3), (0, 4, 6, 2), (1, 3, 7, 5)]  # outward


def other_diagonal():
    """The box with each side split along its other diagonal."""
    c = _corners()
    tris = []
    for a, b, cc, d in QUADS:
        tris += [(a, b, d), (b, cc, d)]
    return np.ascontiguousarray(c[np.array(tris)])


def fans():
    """The box with each side split into four triangles about its centre."""
    c = _corners()
    tris = []
    for quad in QUADS:
        centre = c[list(quad)].mean(axis=0)
        for j in range(4):
            tris.append([c[quad[j]], c[quad[(j + 1) % 4]], centre])
    return np.ascontiguousarray(np.array(tris))


def terms(verts, x):
    """(s, G, T g, projector) of the faces at the point x."""
    grid = build_grid(verts, 2.0 * H).arrays()
    near, s, g0, g1, g2, t0, t1, t2, basis, count = point_terms(
        x[0], x[1], x[2], 3, verts, flat_parts(verts), *grid, stamps_for(verts.shape[0])[:1], 0, 1, KERNEL, H,
        GRAVITY, np.zeros((3, 3)))
    e = np.array(basis).reshape(3, 3)[:count]
    return near, s, np.array([g0, g1, g2]), np.array([t0, t1, t2]), e.T @ e


#: points round the box within the support of its faces: over the middle of a side, over a
#: side near its diagonal, beside an edge, by a corner, and outside near the top's centre
POINTS = [(0.4, 0.4, 0.31), (0.37, 0.36, 0.305), (0.42, 0.29, 0.25), (0.51, 0.4, 0.22), (0.29, 0.29, 0.31),
          (0.52, 0.52, 0.32), (0.4, 0.51, 0.25), (0.33, 0.45, 0.315), (0.45, 0.35, 0.19)]


@pytest.mark.parametrize("x", POINTS)
def test_a_boxs_terms_are_the_same_for_every_split_of_its_sides(x):
    """The integrals add over a side's triangles (to round-off, and to 1e-7 where the foot
    point falls on a vertex: it is moved 1e-9 h into the triangle); the projector is the same
    span: the side's normal over a side, the normals of the sides that meet at an edge or
    corner near one."""
    x = np.array(x)
    ref = terms(np.ascontiguousarray(box(LO, HI)), x)
    assert ref[0] > 0
    for verts in (other_diagonal(), fans()):
        got = terms(verts, x)
        assert got[1] == pytest.approx(ref[1], rel=1e-7, abs=1e-12)
        np.testing.assert_allclose(got[2], ref[2], atol=1e-7 * max(1.0, np.abs(ref[2]).max()))
        np.testing.assert_allclose(got[3], ref[3], atol=1e-7 * max(1.0, np.abs(ref[3]).max()))
        np.testing.assert_allclose(got[4], ref[4], atol=1e-9)


def test_over_the_middle_of_a_side_the_wall_is_its_normal_alone():
    """Above the top side, within the support of its diagonal: the projector is n n^T."""
    for verts in (np.ascontiguousarray(box(LO, HI)), other_diagonal(), fans()):
        p = terms(verts, np.array([0.37, 0.36, 0.305]))[4]
        np.testing.assert_allclose(p, np.diag([0.0, 0.0, 1.0]), atol=1e-12)


def test_flat_parts_are_the_diagonals_and_the_centres_of_the_sides_not_the_boxs_edges_and_corners():
    flat = flat_parts(box(LO, HI))
    # each side (a, b, c), (a, c, d): its diagonal a-c is edge 0-2 of the first, 0-1 of the second
    assert flat[0::2, 5].all() and flat[1::2, 4].all() and flat[:, 4:].sum() == 12
    assert not flat[:, 1:4].any()  # every vertex is a corner of the box
    f = flat_parts(fans())
    # (corner j, corner j + 1, centre): edges to the centre flat, the side's edge not; the centre flat
    assert f[:, 5].all() and f[:, 6].all() and not f[:, 4].any()
    assert f[:, 3].all() and not f[:, 1].any() and not f[:, 2].any()


def test_in_2d_a_vertex_between_two_segments_in_line_is_flat_and_an_open_end_is_not():
    square = np.array([[[0, 0], [0.5, 0]], [[0.5, 0], [1, 0]], [[1, 0], [1, 1]], [[1, 1], [0, 1]], [[0, 1], [0, 0]]],
                      float)
    flat = flat_parts(square)
    assert flat[0, 2] and flat[1, 1]  # the bottom's midpoint
    assert flat[:, 1:3].sum() == 2  # and no other vertex
    line = np.array([[[0, 0], [0.5, 0]], [[0.5, 0], [1, 0]]], float)  # an open polyline
    f = flat_parts(line)
    assert f[0, 2] and f[1, 1] and not f[0, 1] and not f[1, 2]
