"""Rigid bodies on their own: mass properties against closed forms, and the kick-drift-kick
Newton-Euler step against exact motions (free fall, a spring, the torque-free symmetric
top, a pendulum on a hinge), with the invariants that must hold to round-off."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sphcore.geometry import massprops
from sphcore.physics.rigid import Hinge, RigidBody, Spring, quat_axis_angle, quat_matrix

CUBE_TRIANGLES = np.array([[0, 2, 1], [0, 3, 2], [4, 5, 6], [4, 6, 7], [0, 1, 5], [0, 5, 4],
                           [1, 2, 6], [1, 6, 5], [2, 3, 7], [2, 7, 6], [3, 0, 4], [3, 4, 7]])


def _box_points(lo, hi):
    (x0, y0, z0), (x1, y1, z1) = lo, hi
    return np.array([[x0, y0, z0], [x1, y0, z0], [x1, y1, z0], [x0, y1, z0],
                     [x0, y0, z1], [x1, y0, z1], [x1, y1, z1], [x0, y1, z1]], float)


# -- mass properties -----------------------------------------------------------------------------


@settings(max_examples=60, deadline=None)
@given(st.floats(0.05, 3.0), st.floats(0.05, 3.0), st.floats(-5, 5), st.floats(-5, 5), st.booleans())
def test_a_rectangle_as_polygon_has_the_boxs_mass_centre_and_inertia(a, b, x0, y0, clockwise):
    lo, hi = np.array([x0, y0]), np.array([x0 + a, y0 + b])
    verts = np.array([lo, [hi[0], lo[1]], hi, [lo[0], hi[1]]])
    got = massprops.polygon(verts[::-1] if clockwise else verts, 500.0)
    ref = massprops.box(lo, hi, 500.0)
    assert got.mass == pytest.approx(ref.mass, rel=1e-12)
    np.testing.assert_allclose(got.centre, ref.centre, rtol=0, atol=1e-12 * (1 + abs(x0) + abs(y0)))
    assert got.inertia[0, 0] == pytest.approx(ref.inertia[0, 0], rel=1e-9, abs=1e-9 * (1 + x0 * x0 + y0 * y0))


def test_a_regular_polygon_tends_to_the_disc():
    n, r = 2000, 0.3
    t = 2 * np.pi * np.arange(n) / n
    got = massprops.polygon(np.c_[r * np.cos(t) + 1.0, r * np.sin(t) - 2.0], 1000.0)
    m = 1000.0 * np.pi * r * r
    assert got.mass == pytest.approx(m, rel=1e-5)
    assert got.inertia[0, 0] == pytest.approx(m * r * r / 2, rel=1e-5)
    np.testing.assert_allclose(got.centre, [1.0, -2.0], atol=1e-12)


@pytest.mark.parametrize("inward", [False, True])
def test_a_box_mesh_has_the_boxs_mass_centre_and_inertia_and_turns_with_it(inward):
    lo, hi = np.array([0.2, -0.1, 0.5]), np.array([0.6, 0.5, 0.7])
    tri = CUBE_TRIANGLES[:, ::-1] if inward else CUBE_TRIANGLES
    got = massprops.mesh(_box_points(lo, hi), tri, 800.0)
    ref = massprops.box(lo, hi, 800.0)
    assert got.mass == pytest.approx(ref.mass, rel=1e-12)
    np.testing.assert_allclose(got.centre, ref.centre, atol=1e-14)
    np.testing.assert_allclose(got.inertia, ref.inertia, rtol=1e-12, atol=1e-14)
    R = quat_matrix(quat_axis_angle(np.array([1.0, 2.0, 2.0]) / 3.0, 0.7))
    turned = massprops.mesh(_box_points(lo, hi) @ R.T, tri, 800.0)
    np.testing.assert_allclose(turned.inertia, R @ ref.inertia @ R.T, rtol=0, atol=1e-12 * ref.inertia.max())


# -- dynamics ------------------------------------------------------------------------------------


def _body(dim, mass=2.0, inertia=None, **kw):
    inertia = np.eye(dim if dim == 3 else 1) * 0.5 if inertia is None else inertia
    return RigidBody(dim, mass, np.zeros(dim), np.asarray(inertia, float), np.zeros(dim), np.zeros(dim), **kw)


def _step(body, force, dt):
    F, T = force(body)
    body.kick(F, T, 0.5 * dt)
    body.drift(dt)
    F, T = force(body)
    body.kick(F, T, 0.5 * dt)


@pytest.mark.parametrize("dim", [2, 3])
def test_free_fall_and_a_constant_torque_are_exact(dim):
    body = _body(dim)
    body.v = np.full(dim, 0.3)
    g = np.zeros(dim)
    g[-1] = -9.81
    torque = np.array([0.0, 0.0, 0.2])
    dt, n = 1e-3, 1000
    for _ in range(n):
        _step(body, lambda b: (b.mass * g, torque), dt)
    t = n * dt
    np.testing.assert_allclose(body.x, 0.3 * t + 0.5 * g * t * t, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(body.L, torque * t, rtol=1e-12)
    if dim == 2:  # theta = tau t^2 / (2 I)
        assert body.angle == pytest.approx(0.2 * t * t / (2 * 0.5), rel=1e-12)


def test_a_constrained_body_moves_only_along_its_free_axes():
    body = _body(3, free=[0.0, 0.0, 1.0], rotation="fixed")
    for _ in range(100):
        _step(body, lambda b: (np.array([3.0, -2.0, 1.0]), np.array([1.0, 1.0, 1.0])), 1e-2)
    assert body.x[0] == 0.0 and body.x[1] == 0.0 and body.x[2] > 0
    assert not body.L.any() and (body.quat == [1.0, 0.0, 0.0, 0.0]).all()


def test_a_body_on_a_spring_oscillates_at_the_springs_frequency():
    m, k = 2.0, 50.0
    body = _body(2, mass=m, springs=(Spring(np.zeros(2), np.zeros(2), k),))
    body.x = np.array([0.0, 0.1])
    dt = 1e-3
    ys, n = [], 20000
    for _ in range(n):
        _step(body, lambda b: b.spring_load(), dt)
        ys.append(body.x[1])
    ys = np.array(ys)
    ups = np.nonzero((ys[:-1] < 0) & (ys[1:] >= 0))[0]
    period = (ups[-1] - ups[0]) * dt / (len(ups) - 1)
    assert period == pytest.approx(2 * np.pi * math.sqrt(m / k), rel=1e-4)
    assert np.abs(ys).max() == pytest.approx(0.1, rel=1e-3)  # the leapfrog keeps the energy


@settings(max_examples=25, deadline=None)
@given(st.floats(0.2, 2.0), st.floats(0.2, 2.0), st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3),
       st.floats(0, 3))
def test_the_torque_free_symmetric_top_precesses_exactly(ia, is_, lx, ly, lz, tilt):
    """I = diag(ia, ia, is) turned by tilt: body axis and L follow the closed-form motion
    R(t) = Rot(L, |L| t / I_a) R0 Rot(e_s, (1/I_s - 1/I_a) Pi_s t) to round-off."""
    R0 = quat_matrix(quat_axis_angle(np.array([0.6, 0.0, 0.8]), tilt))
    body = _body(3, inertia=np.diag([ia, ia, is_]))
    body.quat = quat_axis_angle(np.array([0.6, 0.0, 0.8]), tilt)
    L = np.array([lx, ly, lz])
    body.L = L.copy()
    dt, n = 2e-3, 500
    for _ in range(n):
        _step(body, lambda b: (np.zeros(3), np.zeros(3)), dt)
    t = n * dt
    size = np.linalg.norm(L)
    pi_s = (R0.T @ L)[2]
    rot_l = quat_matrix(quat_axis_angle(L / size, size * t / ia)) if size else np.eye(3)
    exact = rot_l @ R0 @ quat_matrix(quat_axis_angle(np.array([0.0, 0.0, 1.0]), (1 / is_ - 1 / ia) * pi_s * t))
    np.testing.assert_allclose(body.R, exact, atol=1e-10)
    np.testing.assert_array_equal(body.L, L)


def test_an_asymmetric_top_keeps_its_energy_to_second_order():
    """I = diag(1, 2, 3) spun near its intermediate axis (the tumbling one): L is kept
    exactly, the energy's error falls 4x when dt halves."""
    errors = []
    for dt in (4e-3, 2e-3):
        body = _body(3, inertia=np.diag([1.0, 2.0, 3.0]))
        body.L = np.array([0.05, 2.0, 0.05])
        e0 = body.kinetic_energy()
        worst = 0.0
        for _ in range(int(10.0 / dt)):
            _step(body, lambda b: (np.zeros(3), np.zeros(3)), dt)
            worst = max(worst, abs(body.kinetic_energy() - e0) / e0)
        np.testing.assert_array_equal(body.L, [0.05, 2.0, 0.05])
        errors.append(worst)
    assert errors[0] < 1e-3
    assert 3.0 < errors[0] / errors[1] < 5.0


@pytest.mark.parametrize("dim", [2, 3])
def test_a_pendulum_on_a_hinge_swings_at_its_period(dim):
    """A body hanging d below a hinge: T = 2 pi sqrt(I_h / (m g d)), I_h = I_c + m d^2,
    the centre kept at distance d from the pivot."""
    m, d, ic, g = 3.0, 0.4, 0.02, 9.81
    axis = np.array([0.0, 0.0, 1.0]) if dim == 2 else np.array([1.0, 0.0, 0.0])
    pivot = np.zeros(dim)
    inertia = np.array([[ic]]) if dim == 2 else np.eye(3) * ic
    body = RigidBody(dim, m, np.zeros(dim), inertia, np.zeros(dim), np.zeros(dim), rotation="hinge",
                     hinge=Hinge(axis, pivot))
    body.x = np.array([0.0, -d]) if dim == 2 else np.array([0.0, 0.0, -d])
    gravity = np.zeros(dim)
    gravity[-1] = -g
    body.kick(np.zeros(dim), np.zeros(3), 0.0)
    # a small start: swing by the angular momentum of a 0.02 rad amplitude
    ih = ic + m * d * d
    w0 = 0.02 * math.sqrt(m * g * d / ih)
    body.L = w0 * ih * axis
    dt, angles = 1e-3, []
    up = 1 if dim == 2 else 2
    for _ in range(10000):
        _step(body, lambda b: (b.mass * gravity, np.zeros(3)), dt)
        angles.append(math.atan2(body.x[0] if dim == 2 else body.x[1], -body.x[up]))
        assert np.linalg.norm(body.x - pivot) == pytest.approx(d, rel=1e-12)
    a = np.array(angles)
    ups = np.nonzero((a[:-1] < 0) & (a[1:] >= 0))[0]
    period = (ups[-1] - ups[0]) * dt / (len(ups) - 1)
    assert period == pytest.approx(2 * np.pi * math.sqrt(ih / (m * g * d)), rel=2e-4)


# -- contacts with the fixed walls ------------------------------------------------------------


@pytest.mark.parametrize("restitution", [0.0, 0.5, 1.0])
def test_a_box_dropped_on_the_floor_stays_above_it_and_bounces_with_its_restitution(restitution):
    """No fluid: a 2D box (0.2 x 0.1, heave only) falls 0.1 m onto the plane y = 0; its
    vertices never end below the floor, and it leaves the first contact with -e times the
    speed it hit at."""
    from sphcore.geometry import massprops
    from sphcore.physics.bodymotion import BodyMotion

    props = massprops.box([0.4, 0.1], [0.6, 0.2], 500.0)
    body = RigidBody(2, props.mass, props.centre, props.inertia, props.centre.copy(), np.zeros(2),
                     free=[0.0, 1.0], rotation="fixed")
    corners = np.array([[0.4, 0.1], [0.6, 0.1], [0.6, 0.2], [0.4, 0.2]])
    floor = (np.array([[0.0, 1.0]]), np.array([[0.0, 0.0]]))
    motion = BodyMotion(body, np.array([0.0, -9.81]), restitution, corners, floor)
    dt, vs = 1e-4, []
    for k in range(4000):
        motion.begin_step(k * dt, dt, np.zeros(2), np.zeros(3))
        motion.end_step(np.zeros(2), np.zeros(3))
        assert body.x[1] - 0.05 >= -1e-12
        vs.append(body.v[1])
    hit = math.sqrt(2 * 9.81 * 0.1)
    first = next(k for k in range(1, len(vs)) if vs[k] > vs[k - 1])  # the first contact's step
    assert vs[first - 1] == pytest.approx(-hit, rel=2e-3)
    assert vs[first] == pytest.approx(restitution * hit, rel=2e-3, abs=2 * 9.81 * dt)
    assert motion.contacts >= 1


@settings(max_examples=50, deadline=None)
@given(st.floats(-1, 1), st.floats(-1, 1), st.floats(-1, 1), st.floats(0.0, 3.14159))
def test_the_rotation_vector_gives_back_the_axis_and_angle(ax, ay, az, angle):
    from sphcore.physics.rigid import rotation_vector

    axis = np.array([ax, ay, az])
    if np.linalg.norm(axis) < 0.1:
        axis = np.array([0.0, 0.0, 1.0])
    axis /= np.linalg.norm(axis)
    got = rotation_vector(quat_matrix(quat_axis_angle(axis, angle)))
    want = angle * axis
    # at a half turn the axis's sign is arbitrary
    assert np.allclose(got, want, atol=1e-6) or (angle > 3.1 and np.allclose(got, -want, atol=1e-3))
    assert rotation_vector(np.array([[math.cos(0.3), -math.sin(0.3)], [math.sin(0.3), math.cos(0.3)]]))[2] == \
        pytest.approx(0.3)


def _box_faces(lo, hi):
    """The 2D box [lo, hi] as a closed wall with the fluid outside."""
    from sphcore.geometry.faces import closed_wall

    c = np.array([[lo[0], lo[1]], [hi[0], lo[1]], [hi[0], hi[1]], [lo[0], hi[1]]])
    return closed_wall(np.stack([c, np.roll(c, -1, axis=0)], axis=1), fluid_inside=False)


def _box_body(lo, hi, density, velocity, rotation="fixed", free=(1.0, 1.0), restitution=0.5, gravity=(0.0, 0.0)):
    from sphcore.geometry import massprops
    from sphcore.physics.bodymotion import BodyMotion

    props = massprops.box(lo, hi, density)
    body = RigidBody(2, props.mass, props.centre, props.inertia, props.centre.copy(), np.array(velocity, float),
                     free=list(free), rotation=rotation)
    faces = _box_faces(lo, hi).verts
    corners = np.unique(faces.reshape(-1, 2), axis=0)
    return BodyMotion(body, np.array(gravity), restitution, corners, None, 0.0, faces)


@pytest.mark.parametrize("restitution", [0.0, 0.5, 1.0])
def test_a_box_dropped_on_a_fixed_obstacle_never_enters_it_and_bounces_with_its_restitution(restitution):
    """No fluid: a 2D box (heave only) falls 0.1 m onto the top face (y = 0.05) of a fixed
    box wall: none of its vertices ever ends inside the obstacle, and it leaves the first
    contact with -e times the speed it hit at."""
    motion = _box_body([0.4, 0.15], [0.6, 0.25], 500.0, [0.0, 0.0], free=(0.0, 1.0), restitution=restitution,
                       gravity=(0.0, -9.81))
    motion.solids = _box_faces([0.3, 0.0], [0.7, 0.05])
    dt, vs = 1e-4, []
    for k in range(4000):
        motion.begin_step(k * dt, dt, np.zeros(2), np.zeros(3))
        motion.end_step(np.zeros(2), np.zeros(3))
        assert motion.solids.signed_distance(motion.world_vertices()).min() >= -1e-12
        vs.append(motion.body.v[1])
    hit = math.sqrt(2 * 9.81 * 0.1)
    first = next(k for k in range(1, len(vs)) if vs[k] > vs[k - 1])
    assert vs[first - 1] == pytest.approx(-hit, rel=2e-3)
    assert vs[first] == pytest.approx(restitution * hit, rel=2e-3, abs=2 * 9.81 * dt)
    assert motion.contacts >= 1


@pytest.mark.parametrize("restitution", [0.0, 0.5, 1.0])
@pytest.mark.parametrize("rotation, offset", [("fixed", 0.0), ("free", 0.03)])
def test_two_bodies_that_collide_exchange_momentum_and_never_overlap(restitution, rotation, offset):
    """No fluid, no gravity: two boxes of different masses slide at each other along x
    (the second one offset in y, free to turn: an oblique hit). Their total momentum and
    angular momentum about the origin are the same after the collision as before (the
    impulses are equal and opposite, to round-off), the kinetic energy does not grow, no
    vertex of one ever ends inside the other, and head on the normal relative speed after
    is -e times the speed before. Free to turn, the total angular momentum about the origin
    keeps to the part the overlap's removal moves (each contact moves the two apart by its
    depth, at most one step's approach, about their common centre of mass: at most
    mu |v_rel| dt |v_rel| per contact, mu the reduced mass); head on nothing moves it."""
    a = _box_body([0.1, 0.4], [0.3, 0.5], 500.0, [1.0, 0.0], rotation, restitution=restitution)
    b = _box_body([0.5, 0.42 + offset], [0.6, 0.52 + offset], 900.0, [-0.5, 0.0], rotation, restitution=restitution)
    a.others, b.others = [b], [a]

    def totals():
        p = sum(m.body.mass * m.body.v for m in (a, b))
        ang = sum(m.body.mass * (m.body.x[0] * m.body.v[1] - m.body.x[1] * m.body.v[0]) + m.body.L[2]
                  for m in (a, b))
        ke = sum(0.5 * m.body.mass * m.body.v @ m.body.v + 0.5 * m.body.omega()[2] * m.body.L[2] for m in (a, b))
        return p, ang, ke

    p0, l0, e0 = totals()
    dt = 1e-4
    for k in range(3000):
        for m in (a, b):
            m.begin_step(k * dt, dt, np.zeros(2), np.zeros(3))
        for m in (a, b):
            m.end_step(np.zeros(2), np.zeros(3))
        assert a.world_faces().signed_distance(b.world_vertices()).min() >= -1e-12
        assert b.world_faces().signed_distance(a.world_vertices()).min() >= -1e-12
    p1, l1, e1 = totals()
    assert a.contacts + b.contacts >= 1
    np.testing.assert_allclose(p1, p0, rtol=0, atol=1e-12)
    mu = a.body.mass * b.body.mass / (a.body.mass + b.body.mass)
    bound = 1e-12 if offset == 0.0 else (a.contacts + b.contacts) * mu * 1.5 * dt * 1.5
    if rotation == "free":
        assert abs(l1 - l0) <= bound
    assert e1 <= e0 * (1 + 1e-12)
    if rotation == "fixed":
        assert b.body.v[0] - a.body.v[0] == pytest.approx(restitution * 1.5, rel=1e-9, abs=1e-12)
