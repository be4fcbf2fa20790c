"""The geometry object of finite walls (``sphcore.geometry.faces.Faces``): signed distance, nearest
point and normal against the closed form of a box (turned by a random rotation), for an
obstacle and for a tank, in 2D and 3D (hypothesis)."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sphcore.geometry.faces import Faces, box, closed_wall, polyline


def _rotation(dim, angles):
    if dim == 2:
        c, s = np.cos(angles[0]), np.sin(angles[0])
        return np.array([[c, -s], [s, c]])
    out = np.eye(3)
    for k, a in enumerate(angles):
        i, j = [(0, 1), (1, 2), (0, 2)][k]
        r = np.eye(3)
        r[i, i] = r[j, j] = np.cos(a)
        r[i, j], r[j, i] = -np.sin(a), np.sin(a)
        out = out @ r
    return out


def _box_sdf(y, half):
    """Signed distance of points y (box frame, centred) to the box, negative inside; the
    nearest boundary point and the outward unit normal there (outside points only)."""
    q = np.abs(y) - half
    outside = np.linalg.norm(np.maximum(q, 0.0), axis=1)
    inside = np.minimum(q.max(axis=1), 0.0)
    near = np.clip(y, -half, half)
    return outside + inside, near


@settings(max_examples=40, deadline=None)
@given(dim=st.sampled_from([2, 3]), fluid_inside=st.booleans(), seed=st.integers(0, 2**31 - 1))
def test_signed_distance_nearest_point_and_normal_of_a_turned_box(dim, fluid_inside, seed):
    rng = np.random.default_rng(seed)
    half = rng.uniform(0.05, 1.0, dim)
    centre = rng.uniform(-10.0, 10.0, dim)
    rot = _rotation(dim, rng.uniform(0.0, 2.0 * np.pi, 3))
    verts = box(-half, half) @ rot.T + centre
    faces = closed_wall(verts, fluid_inside)
    y = rng.uniform(-3.0, 3.0, (200, dim)) * half.max()  # box frame
    x = y @ rot.T + centre
    sdf, near = _box_sdf(y, half)
    sign = -1.0 if fluid_inside else 1.0  # an obstacle's fluid is outside
    got = faces.signed_distance(x)
    assert np.allclose(got, sign * sdf, atol=1e-12 * (1.0 + np.abs(centre).max()))
    q, f, dist = faces.nearest(x)
    assert np.allclose(dist, np.abs(sdf), atol=1e-12 * (1.0 + np.abs(centre).max()))
    out = sdf > 1e-9
    assert np.allclose(q[out], near[out] @ rot.T + centre, atol=1e-9)
    normal = faces.normal_at(x)
    assert np.allclose(np.linalg.norm(normal, axis=1), 1.0)
    # outside the box the outward direction is (y - near) / |y - near|; it points into the
    # fluid for an obstacle and out of it (towards the tank's water) for a tank
    outward = (y[out] - near[out]) / sdf[out, None]
    assert np.allclose(normal[out], sign * outward @ rot.T, atol=1e-9)
    # a step along the normal moves into the fluid: the signed distance grows. Inside the
    # box a step away from the nearest face (a tank's normal) gains that step only where
    # the next face is farther by more than the step: points near the medial axis (where
    # two faces' distances tie) are left out. Outside the convex box, and inside towards
    # the nearest face (an obstacle's normal), the property holds everywhere.
    step = 1e-3 * half.min()
    depths = np.sort(np.hstack([half - y, half + y]), axis=1)  # to each face's plane, inside
    clear = (sdf > 0) | (depths[:, 1] - depths[:, 0] > 4 * step) | (not fluid_inside)
    far = (np.abs(sdf) > 2 * step) & clear
    assert np.all(faces.signed_distance(x[far] + step * normal[far]) > got[far])


def test_a_point_on_a_face_gets_the_face_normal_and_zero_distance():
    faces = closed_wall(box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]), fluid_inside=False)
    x = np.array([[0.25, 0.5, 1.0], [0.0, 0.3, 0.6]])
    assert np.all(faces.nearest(x)[2] < 1e-15)
    assert np.allclose(faces.normal_at(x), [[0.0, 0.0, 1.0], [-1.0, 0.0, 0.0]])


def test_an_open_plate_has_no_inside():
    plate = Faces(polyline([[0.0, 0.0], [1.0, 0.0]])[None, ...].reshape(1, 2, 2))
    x = np.array([[0.5, 0.2], [0.5, -0.2], [2.0, 0.0]])
    assert np.allclose(plate.signed_distance(x), [0.2, 0.2, 1.0])
    assert np.allclose(plate.normal_at(x), [[0.0, 1.0], [0.0, -1.0], [1.0, 0.0]])
    with pytest.raises(ValueError):
        Faces.empty(2).nearest(x)
