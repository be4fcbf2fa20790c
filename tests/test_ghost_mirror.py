"""Geometry and state of ghost (mirror) particles: plugins/ghost/mirror.py.

Properties over random planes and points (hypothesis), corner images in 2D and 3D boxes,
the hydrostatic pressure and inverse Tait density, and the buffer handling.
"""

from itertools import combinations

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st

from sphcore.geometry.planes import Planes
from sphcore.physics.eos import fill_pressure as tait_pressure
from sphcore.physics.eos import tait_b
from sphcore.physics.particles import FLUID, SPHERE, Fields
from sphcore_plugins.ghost.images import MirrorImages, inverse_tait
from sphcore_plugins.ghost.mirror import (
    TAIT_BASE_MIN,
    count_images,
    count_images_serial,
    exclusive_scan,
    fill_images,
    fill_images_serial,
)
from sphcore_plugins.ghost.records import FluidConstants, GhostPressure, Images, MirrorRule, Passes, PlaneGroup

H = 0.013  # smoothing length (m); support 2h
SUPPORT = 2 * H
RHO0, C0, GAMMA = 1000.0, 20.0, 7.0
G = np.array([0.0, -9.81, 0.0])

settings.register_profile("ghost", max_examples=60, deadline=None)
settings.load_profile("ghost")


def generate(planes_or_pair, pos, vel=None, p=None, rho=None, kind=None, wall="free_slip", hydrostatic=False,
             gravity=G):
    normals, offsets = planes_or_pair if isinstance(planes_or_pair, tuple) else (
        planes_or_pair.normals, planes_or_pair.offsets)
    pos = np.ascontiguousarray(pos, float)
    n = pos.shape[0]
    vel = np.zeros_like(pos) if vel is None else np.ascontiguousarray(vel, float)
    p = np.zeros(n) if p is None else np.asarray(p, float)
    rho = np.full(n, RHO0) if rho is None else np.asarray(rho, float)
    kind = np.full(n, FLUID, np.int8) if kind is None else kind
    m = MirrorImages(normals, offsets, free_slip=wall == "free_slip", hydrostatic=hydrostatic)
    src = m.generate(Fields(pos, vel, rho, p, np.arange(1.0, n + 1)), kind,
                     FluidConstants(SUPPORT, gravity, RHO0, C0, GAMMA))
    return m, src


def reference_images(normals, offsets, pos, support, max_order, tol):
    """Plain numpy statement of the rule: (source index, image position) for every kept image."""
    out = []
    for i, x in enumerate(pos):
        d = normals @ x - offsets
        near = [k for k in range(len(offsets)) if tol < d[k] < support]
        for r in range(1, max_order + 1):
            for sub in combinations(near, r):
                y = x.copy()
                for k in sub:  # index order, as the kernel
                    y = y - 2.0 * (normals[k] @ y - offsets[k]) * normals[k]
                if (normals @ y - offsets).min() < -tol:
                    out.append((i, y))
    return out


def sorted_rows(src_idx, pos):
    rows = np.column_stack([np.asarray(src_idx, float), np.asarray(pos, float)])
    return rows[np.lexsort(rows.T[::-1])] if rows.size else rows


unit = st.floats(-1.0, 1.0, allow_nan=False)


@st.composite
def plane_and_point(draw):
    dim = draw(st.sampled_from([2, 3]))
    n = np.array([draw(unit) for _ in range(dim)])
    assume(np.linalg.norm(n) > 0.1)
    n /= np.linalg.norm(n)
    x0 = np.array([draw(st.floats(-1.0, 1.0)) for _ in range(dim)])
    d = draw(st.floats(1e-6, SUPPORT * (1 - 1e-9)))
    t = np.array([draw(st.floats(-0.1, 0.1)) for _ in range(dim)])
    t -= (t @ n) * n  # tangential offset along the plane
    v = np.array([draw(st.floats(-5.0, 5.0)) for _ in range(dim)])
    return n, x0, x0 + t + d * n, d, v


@given(plane_and_point(), st.sampled_from(["free_slip", "no_slip"]))
def test_single_plane_image_lies_d_behind_with_mirrored_velocity(case, wall):
    n, x0, x, d, v = case
    m, src = generate((n[None, :], np.array([n @ x0])), x[None, :], v[None, :], p=[123.0], wall=wall)
    assert src.n == 1
    g = src.pos[0]
    assert n @ (g - x0) == pytest.approx(-d, abs=1e-12)  # d behind the plane
    np.testing.assert_allclose(g, x - 2 * d * n, atol=1e-12)  # straight across it
    vg = src.vel[0]
    if wall == "free_slip":
        assert vg @ n == pytest.approx(-(v @ n), abs=1e-12)
        np.testing.assert_allclose(vg - (vg @ n) * n, v - (v @ n) * n, atol=1e-12)
    else:
        np.testing.assert_allclose(vg, -v, atol=0)
    assert src.m[0] == 1.0 and src.p[0] == 123.0 and src.rho[0] == RHO0  # no correction asked
    assert m.source_index.tolist() == [0]


@given(plane_and_point(), st.floats(1.0 + 1e-6, 3.0))
def test_no_image_beyond_support_or_on_the_plane(case, factor):
    n, x0, x, d, _ = case
    far = x0 + (x - x0) - d * n + factor * SUPPORT * n  # d >= support
    on = x0 + (x - x0) - d * n  # d = 0
    _, src = generate((n[None, :], np.array([n @ x0])), np.array([far, on]))
    assert src.n == 0


@st.composite
def polytope_and_points(draw):
    """The unit box cut by up to two random planes through its inside, and points in it."""
    dim = draw(st.sampled_from([2, 3]))
    box = Planes.box(np.zeros(dim), np.ones(dim))
    normals, points = list(box.normals), list(box.points)
    for _ in range(draw(st.integers(0, 2))):
        n = np.array([draw(unit) for _ in range(dim)])
        assume(np.linalg.norm(n) > 0.1)
        n /= np.linalg.norm(n)
        c = np.array([draw(st.floats(0.3, 0.7)) for _ in range(dim)])
        if n @ (0.5 - c) < 0:  # keep the box centre inside
            n = -n
        normals.append(n)
        points.append(c)
    planes = Planes.from_lists(normals, points)
    # points near walls and corners: a fine random cloud, kept where inside
    rng = np.random.default_rng(draw(st.integers(0, 2**31)))
    pts = rng.random((400, dim))
    pts = pts[(planes.distances(pts) > 0).all(axis=1)]
    assume(len(pts) > 0)
    return planes, pts


@given(polytope_and_points())
@settings(max_examples=40)
def test_images_match_reference_and_none_is_inside(case):
    planes, pts = case
    support = 0.15  # a large support relative to the box, so corners and slanted planes interact
    m = MirrorImages(planes.normals, planes.offsets)
    n = len(pts)
    src = m.generate(Fields(pts, np.zeros_like(pts), np.full(n, RHO0), np.zeros(n), np.ones(n)),
                     np.zeros(n, np.int8), FluidConstants(support, G, RHO0, C0, GAMMA))
    ref = reference_images(planes.normals, planes.offsets, pts, support, pts.shape[1], 1e-9 * support)
    assert src.n == len(ref)
    assert np.bincount(m.source_index, minlength=n).tolist() == np.bincount(
        [i for i, _ in ref], minlength=n).tolist()
    for i, y in ref:  # each reference image is among the kernel's images of that particle
        assert np.min(np.linalg.norm(src.pos[m.source_index == i] - y, axis=1)) < 1e-12
    # no image inside the domain
    if src.n:
        assert (planes.distances(src.pos).min(axis=1) < 0).all()
    # every plane within support of a particle gives that particle its single image
    d = planes.distances(pts)
    for i, k in zip(*np.nonzero((d > 1e-9 * support) & (d < support))):
        want_img = pts[i] - 2 * d[i, k] * planes.normals[k]
        mine = src.pos[m.source_index == i]
        assert np.min(np.linalg.norm(mine - want_img, axis=1)) < 1e-12


def test_non_perpendicular_double_images_that_fall_inside_are_dropped():
    # a floor and a wall leaning out at 45 degrees (interior angle 135 degrees): the
    # double image (a rotation by -90 degrees about the corner) of a particle at polar
    # angle between 90 and 135 degrees comes back into the fluid
    planes = Planes.from_lists([[0.0, 1.0], [1.0, 1.0]], [[0.0, 0.0], [0.0, 0.0]])
    x = np.array([[-0.002, 0.006]])  # at 108 degrees
    support = 0.03
    ref_all = []
    for sub in ([0], [1], [0, 1]):
        y = x[0].copy()
        for k in sub:
            y = y - 2.0 * (planes.normals[k] @ y - planes.offsets[k]) * planes.normals[k]
        ref_all.append(y)
    inside = (planes.distances(np.array(ref_all)) >= 0).all(axis=1)
    assert inside.tolist() == [False, False, True]  # the setting does exercise the rule
    m = MirrorImages(planes.normals, planes.offsets)
    src = m.generate(Fields(x, np.zeros_like(x), np.full(1, RHO0), np.zeros(1), np.ones(1)), np.zeros(1, np.int8),
                     FluidConstants(support, G, RHO0, C0, GAMMA))
    assert src.n == 2
    np.testing.assert_allclose(sorted_rows([0, 0], src.pos), sorted_rows([0, 0], ref_all[:2]), atol=1e-15)


@pytest.mark.parametrize("dim", [2, 3])
def test_box_corner_gets_every_image(dim):
    lo, hi = np.zeros(dim), np.ones(dim)
    x = np.full(dim, 0.01)  # within support of dim planes at the lower corner
    _, src = generate(Planes.box(lo, hi), x[None, :], vel=np.arange(1.0, dim + 1)[None, :])
    assert src.n == 2**dim - 1  # 3 in 2D; 7 in 3D: faces, edges, vertex
    want = {tuple(np.round(np.where(np.array(s), -x, x), 12)) for s in np.ndindex(*(2,) * dim) if any(s)}
    assert {tuple(np.round(g, 12)) for g in src.pos} == want
    for g, v in zip(src.pos, src.vel):  # free slip: each component reversed where mirrored
        np.testing.assert_allclose(v, np.where(g < 0, -1.0, 1.0) * np.arange(1.0, dim + 1))


def test_3d_edge_and_face_counts():
    box = Planes.box(np.zeros(3), np.ones(3))
    pts = np.array([[0.01, 0.01, 0.5],   # an edge: 2 faces + 1 double
                    [0.5, 0.01, 0.5],    # a face
                    [0.5, 0.5, 0.5]])    # the middle: nothing
    m, src = generate(box, pts)
    assert np.bincount(m.source_index, minlength=3).tolist() == [3, 1, 0]


def test_hydrostatic_ghost_pressure_and_inverse_tait_density():
    floor = Planes.box([0.0, 0.0], [1.0, 1.0])
    x = np.array([[0.5, 0.004]])  # 4 mm above the floor: ghost 8 mm lower
    p, rho = np.array([1500.0]), np.array([1000.5])
    _, src = generate(floor, x, p=p, rho=rho, hydrostatic=True)
    assert src.n == 1
    pg = 1500.0 + 1000.5 * 9.81 * 0.008
    assert src.p[0] == pytest.approx(pg, rel=1e-12)
    # the density is the one whose Tait pressure is the ghost pressure
    back = np.zeros(1)
    tait_pressure(src.rho, RHO0, C0, GAMMA, 0.0, back)
    assert back[0] == pytest.approx(pg, rel=1e-9)
    # along a side wall gravity does no work: pressure unchanged
    _, side = generate(floor, np.array([[0.004, 0.5]]), p=p, rho=rho, hydrostatic=True)
    assert side.p[0] == pytest.approx(1500.0, rel=1e-12)


def test_modified_pressure_ghost_carries_only_the_non_hydrostatic_part():
    # with the core's modified pressure the fluid hands over P = p - rho0 g (z_s - z): the
    # ghost's P differs from the particle's only by (rho_i - rho0) g . (x_g - x_i)
    floor = Planes.box([0.0, 0.0], [1.0, 1.0])
    x, P, rho = np.array([[0.5, 0.004]]), np.array([20.0]), np.array([1000.5])
    m = MirrorImages(floor.normals, floor.offsets, hydrostatic=True)
    src = m.generate(Fields(x, np.zeros_like(x), rho, P, np.ones(1)), np.zeros(1, np.int8),
                     FluidConstants(SUPPORT, G, RHO0, C0, GAMMA, rho_ref=RHO0))
    assert src.p[0] == pytest.approx(20.0 + 0.5 * 9.81 * 0.008, rel=1e-12)
    assert src.rho[0] == pytest.approx(inverse_tait(src.p, RHO0, C0, GAMMA)[0], rel=1e-12)


def test_inverse_tait_clamps_under_strong_tension():
    rho = inverse_tait(np.array([-1e9, 0.0]), RHO0, C0, GAMMA)
    assert rho[0] == pytest.approx(RHO0 * TAIT_BASE_MIN ** (1 / GAMMA)) and rho[1] == RHO0
    _, src = generate(Planes.box([0.0, 0.0], [1.0, 1.0]), np.array([[0.5, 0.004]]), p=[-1e9], hydrostatic=True)
    assert np.isfinite(src.rho).all() and src.rho[0] > 0


def test_only_fluid_particles_are_mirrored():
    box = Planes.box([0.0, 0.0], [1.0, 1.0])
    pts = np.array([[0.5, 0.004], [0.5, 0.005]])
    m, src = generate(box, pts, kind=np.array([SPHERE, FLUID], np.int8))
    assert m.source_index.tolist() == [1]


def test_buffers_grow_and_are_reused():
    box = Planes.box([0.0, 0.0], [1.0, 1.0])
    m = MirrorImages(box.normals, box.offsets)
    small = np.array([[0.5, 0.004]])
    big = np.column_stack([np.linspace(0.1, 0.9, 300), np.full(300, 0.004)])
    constants = FluidConstants(SUPPORT, G, RHO0, C0, GAMMA)

    def run(x):
        n = len(x)
        fluid = Fields(x, np.zeros_like(x), np.full(n, RHO0), np.zeros(n), np.ones(n))
        return m.generate(fluid, np.zeros(n, np.int8), constants)

    assert run(small).n == 1
    cap = m.capacity
    assert run(big).n == 300 and m.capacity >= 300 and m.capacity > cap
    cap, realloc = m.capacity, m.reallocations
    out = run(small)
    assert out.n == 1 and m.capacity == cap and m.reallocations == realloc  # no new allocation
    np.testing.assert_allclose(out.pos, [[0.5, -0.004]])


@pytest.mark.slow
def test_serial_and_parallel_kernels_agree():
    box = Planes.box(np.zeros(3), np.ones(3))
    rng = np.random.default_rng(1)
    pos = rng.random((3000, 3))
    n = len(pos)
    fluid = Fields(pos, rng.normal(size=(n, 3)), np.full(n, RHO0), rng.random(n), np.ones(n))
    kind = np.zeros(n, np.int8)
    walls = PlaneGroup(box.normals, box.offsets)
    rule = MirrorRule(0.1, 1e-10, 3, True)
    ghost = GhostPressure(True, G, 0.0, RHO0, tait_b(C0, RHO0, GAMMA), 1.0 / GAMMA, 0.0, C0, GAMMA)
    outs = []
    for count, fill in ((count_images, fill_images), (count_images_serial, fill_images_serial)):
        passes = Passes(np.zeros(n, np.int64), np.zeros(n, np.int64), np.zeros(n + 1, np.int64))
        count(fluid, kind, walls, rule, passes)
        total = exclusive_scan(passes.counts, passes.start)
        bufs = Images(np.zeros((total, 3)), np.zeros((total, 3)), np.zeros(total), np.zeros(total), np.zeros(total),
                      np.zeros(total, np.int64))
        fill(fluid, walls, rule, ghost, passes, bufs)
        outs.append(bufs)
    assert outs[0][0].shape[0] > 1000
    for a, b in zip(*outs):
        np.testing.assert_array_equal(a, b)
