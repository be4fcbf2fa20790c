"""Reflective boundary kernel: degenerate cases, corners, wedges, exactness (paper sections 2-3)."""

import numpy as np
import pytest
from domains import box, random_directions, random_rotation, sample_inside, wedge

from sphcore.geometry.planes import Planes
from sphcore.physics.particles import lattice
from sphcore_plugins.reflective.collision import TOL_REL
from sphcore_plugins.reflective.entry import clearance, outside, reflect_particles


def run(pos0, pos, vel, planes, r, cr, acc=None, **kw):
    """Reflect copies; return (pos, vel, guard count, guard flags, reflection counts)."""
    pos, vel = np.array(pos, float), np.array(vel, float)
    n = pos.shape[0]
    flags, counts = np.empty(n, np.int8), np.empty(n, np.int32)
    g = reflect_particles(np.array(pos0, float), pos, vel, acc, r, planes, cr,
                          guarded_flags=flags, reflection_counts=counts, **kw)
    return pos, vel, g, flags, counts


def assert_inside(pos, r, planes):
    r = np.broadcast_to(np.asarray(r, float), (len(pos),))
    assert np.all(np.isfinite(pos))
    assert not outside(pos, r, planes).any()


def rotated_box_lattice(rng, dim, dx=0.02):
    """The paper's spheres at rest (section 4.1): a unit box filled on a lattice of
    spacing dx, radius dx/2, the outer particles touching the walls; optionally turned."""
    lo, hi = np.zeros(dim), np.ones(dim)
    pts = lattice(lo, hi, dx)
    if rng is None:
        return pts, Planes.box(lo, hi)
    rot = random_rotation(rng, dim)
    dom = box(lo, hi, rot)
    c = dom.centre
    return np.ascontiguousarray((pts - c) @ rot.T + c), dom.planes


# --------------------------------------------------------------------------------------
# Particles at rest (paper section 4.1): untouched bit for bit
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("turned", [False, True])
@pytest.mark.parametrize("cr", [0.0, 1.0])
def test_spheres_at_rest_in_box_untouched(dim, turned, cr):
    rng = np.random.default_rng(7) if turned else None
    pts, planes = rotated_box_lattice(rng, dim, dx=0.02 if dim == 2 else 0.05)
    r = (0.02 if dim == 2 else 0.05) / 2
    vel = np.zeros_like(pts)
    # the outermost layer touches the walls (d == r up to an ulp), as in Fig. 8
    c = clearance(pts, r, planes)
    assert np.abs(c).min() < 1e-13 and not outside(pts, r, planes).any()
    gravity = np.zeros_like(pts)
    gravity[:, 1] = -9.81
    pos, v, g, flags, counts = run(pts, pts, vel, planes, r, cr, acc=gravity)
    assert np.array_equal(pos, pts) and np.array_equal(v, vel)
    assert g == 0 and not flags.any() and not counts.any()


def test_rest_exactly_at_contact_single_slanted_planes():
    rng = np.random.default_rng(3)
    for dim in (2, 3):
        for _ in range(50):
            n = random_directions(rng, 1, dim)[0]
            x0 = rng.uniform(-1, 1, dim)
            tang = rng.uniform(-1, 1, (20, dim))
            tang -= np.outer(tang @ n, n)
            r = rng.uniform(1e-3, 1.0, 20)
            c = x0 + tang + r[:, None] * n  # d = r exactly, r +- an ulp in floating point
            planes = Planes.from_lists([n], [x0])
            pos, v, g, _, counts = run(c, c, np.zeros((20, dim)), planes, r, 0.0)
            assert np.array_equal(pos, c) and not v.any() and g == 0 and not counts.any()


# --------------------------------------------------------------------------------------
# Degenerate trajectories
# --------------------------------------------------------------------------------------


def test_parallel_trajectory_along_wall_untouched():
    r = 0.05
    planes = Planes.box([0, 0], [1, 1])
    pos0 = np.array([[0.3, r], [r, 0.4]])
    pos1 = pos0 + np.array([[0.4, 0.0], [0.0, 0.5]])
    pos, v, g, _, counts = run(pos0, pos1, [[1.0, 0.0], [0.0, 1.0]], planes, r, 1.0)
    assert np.array_equal(pos, pos1) and g == 0 and not counts.any()


def test_parallel_trajectory_starting_too_deep_never_divides_by_zero():
    # start and end both at d = r/2 (d_A == d_B): f = 0, pushed out by (1 + CR)(r - d)
    r = 0.1
    planes = Planes.from_lists([[0.0, 1.0]], [[0.0, 0.0]])
    for cr in (0.0, 0.5, 1.0):
        pos, v, g, _, counts = run([[0.0, 0.05]], [[0.3, 0.05]], [[1.0, 0.0]], planes, r, cr)
        assert np.allclose(pos, [[0.3, 0.05 + (1 + cr) * 0.05]], rtol=0, atol=1e-15)
        assert np.array_equal(v, [[1.0, 0.0]]) and counts[0] == 1 and g == 0
    # the same start, now also through the wall x = 1: floor first (f = 0), then the wall
    box_planes = Planes.box([0.0, 0.0], [1.0, 1.0])
    for cr in (0.0, 1.0):
        pos, v, g, _, counts = run([[0.5, 0.05]], [[1.3, 0.05]], [[1.0, 0.0]], box_planes, r, cr)
        want = [[1.3 - (1 + cr) * (r + 0.3), 0.05 + (1 + cr) * 0.05]]
        assert counts[0] == 2 and np.allclose(pos, want, rtol=0, atol=1e-15)
        assert np.array_equal(v, [[-cr, 0.0]])


def test_end_point_exactly_at_contact_is_not_a_collision():
    r = 0.125
    planes = Planes.box([0.0, 0.0], [1.0, 1.0])
    pos, v, g, _, counts = run([[0.5, 0.5]], [[0.5, r]], [[0.0, -3.0]], planes, r, 1.0)
    assert np.array_equal(pos, [[0.5, r]]) and np.array_equal(v, [[0.0, -3.0]]) and counts[0] == 0
    # just beyond the allowance it is a collision
    y = r - 2 * TOL_REL * r
    pos, v, g, _, counts = run([[0.5, 0.5]], [[0.5, y]], [[0.0, -3.0]], planes, r, 1.0)
    assert counts[0] == 1 and pos[0, 1] == y + 2 * (r - y) and np.array_equal(v, [[0.0, 3.0]])


def test_already_moving_back_in_keeps_velocity():
    # position outside, velocity pointing into the domain: position reflected, velocity kept
    planes = Planes.from_lists([[0.0, 1.0]], [[0.0, 0.0]])
    pos, v, g, _, counts = run([[0.0, 0.2]], [[0.0, -0.1]], [[0.5, 2.0]], planes, 0.1, 0.5)
    assert np.allclose(pos, [[0.0, -0.1 + 1.5 * 0.2]]) and np.array_equal(v, [[0.5, 2.0]])


# --------------------------------------------------------------------------------------
# Corners and large displacements in boxes: the exact (unfolded) answer
# --------------------------------------------------------------------------------------


def fold(x, lo, hi):
    """Billiard unfolding on [lo, hi]: the elastic end position and the velocity sign."""
    w = hi - lo
    y = np.mod(x - lo, 2 * w)
    back = y > w
    return np.where(back, lo + 2 * w - y, lo + y), np.where(back, -1.0, 1.0)


@pytest.mark.parametrize("dim", [2, 3])
def test_corner_cr1_and_cr0(dim):
    r = 0.05
    planes = Planes.box(np.zeros(dim), np.ones(dim))
    pos0 = np.full((1, dim), 0.2)
    step = -np.linspace(0.3, 0.4, dim)[None, :]  # into the corner through all walls at once
    vel = step / 0.1
    pos, v, g, _, counts = run(pos0, pos0 + step, vel, planes, r, 1.0)
    assert np.allclose(pos, 2 * r - (pos0 + step), rtol=0, atol=1e-15)
    assert np.array_equal(v, -vel) and counts[0] == dim and g == 0
    pos, v, g, _, counts = run(pos0, pos0 + step, vel, planes, r, 0.0)
    assert np.allclose(pos, r, rtol=0, atol=1e-15) and np.array_equal(v, np.zeros_like(v))
    # exactly through the corner point: ties in f are harmless
    step = np.full((1, dim), -0.3)
    pos, v, g, _, counts = run(pos0, pos0 + step, step, planes, r, 1.0)
    assert np.allclose(pos, 2 * r - (pos0 + step), rtol=0, atol=1e-15) and np.array_equal(v, -step)


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("cr", [0.0, 1.0])
def test_hundred_domain_lengths_in_one_step(dim, cr):
    rng = np.random.default_rng(11 + dim)
    r, m = 0.01, 2000
    lo, hi = np.zeros(dim), np.ones(dim)
    planes = Planes.box(lo, hi)
    pos0 = rng.uniform(r, 1 - r, (m, dim))
    step = random_directions(rng, m, dim) * rng.uniform(1.0, 100.0, (m, 1))
    step[0] = 100.0 * np.eye(dim)[0] + 37.3 * np.eye(dim)[1]
    vel = step / 1e-3
    pos, v, g, flags, counts = run(pos0, pos0 + step, vel, planes, r, cr)
    assert g == 0 and not flags.any()
    if cr == 1.0:
        want, sign = fold(pos0 + step, r, 1 - r)
        assert np.allclose(pos, want, rtol=0, atol=1e-11)
        assert np.array_equal(v, sign * vel)
        assert counts[0] >= 100
    else:
        # CR = 0: each wall stops the normal motion; the end point is clamped into the box
        # (to the round-off of coordinates up to 100 m)
        assert np.allclose(pos, np.clip(pos0 + step, r, 1 - r), rtol=0, atol=1e-12)
        assert np.array_equal(v, np.where((pos0 + step > r) & (pos0 + step < 1 - r), vel, 0.0))
    assert_inside(pos, r, planes)


def test_first_plane_reached_wins_on_a_slanted_corner():
    # floor y = 0 and a 45-degree wall through (1, 0) (interior angle 135 degrees).
    # C0 = (0.5, 0.5) -> C1 = (1.5, -0.3), r = 0.1: the sphere reaches the wall at
    # f = (1/sqrt2 - 0.1) / (1.2/sqrt2 + 0.8/sqrt2) = 0.477 before the floor at f = 0.5,
    # so it is mirrored across the wall only: C1 + 2 (r - d_B) n, d_B = -0.8/sqrt2.
    s2 = np.sqrt(2.0)
    planes = Planes.from_lists([[0.0, 1.0], [-1.0, 1.0]], [[0.0, 0.0], [1.0, 0.0]])
    n2 = np.array([-1.0, 1.0]) / s2
    want = np.array([1.5, -0.3]) + 2 * (0.1 + 0.8 / s2) * n2
    assert want[1] > 0.1  # and then clear of the floor
    vel = np.array([[1.0, -0.8]])
    pos, v, g, _, counts = run([[0.5, 0.5]], [[1.5, -0.3]], vel, planes, 0.1, 1.0)
    assert counts[0] == 1 and np.allclose(pos[0], want, rtol=0, atol=1e-15)
    assert np.allclose(v[0], vel[0] - 2 * (vel[0] @ n2) * n2, rtol=0, atol=1e-15)
    # CR = 0.5, C0 = (0.5, 0.3) -> C1 = (1.6, -0.5): the floor first (f = 0.25 < 0.347),
    # to (1.6, 0.4), which is still beyond the wall: then the wall
    pos, v, g, _, counts = run([[0.5, 0.3]], [[1.6, -0.5]], [[1.1, -0.8]], planes, 0.1, 0.5)
    b1 = np.array([1.6, -0.5 + 1.5 * (0.1 + 0.5)])
    d_wall = (1.0 - b1[0] + b1[1]) / s2
    want = b1 + 1.5 * (0.1 - d_wall) * n2
    assert d_wall < 0.1 and want[1] > 0.1
    assert counts[0] == 2 and np.allclose(pos[0], want, rtol=0, atol=1e-15)
    v1 = np.array([1.1, 0.5 * 0.8])  # floor: normal component -0.8 -> +0.4
    assert np.allclose(v[0], v1 - 1.5 * (v1 @ n2) * n2, rtol=0, atol=1e-15)


# --------------------------------------------------------------------------------------
# Acute wedges: many reflections, CR = 0 never finishes (the guard)
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("angle", [5.0, 10.0, 30.0, 60.0])
@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("cr", [0.0, 0.5, 1.0])
def test_acute_wedges(angle, dim, cr):
    rng = np.random.default_rng(int(angle) * 10 + dim)
    dom = wedge(angle, 1.0, dim)
    r, m = 0.3 * dom.inradius, 3000
    pos0 = sample_inside(rng, dom, r, m)
    step = random_directions(rng, m, dim) * np.exp(rng.uniform(np.log(1e-3), np.log(100.0), (m, 1)))
    vel = step.copy()
    pos, v, g, flags, counts = run(pos0, pos0 + step, vel, dom.planes, r, cr)
    assert_inside(pos, r, dom.planes)
    assert g == flags.sum()
    assert np.array_equal(pos[flags == 1], pos0[flags == 1])
    if cr == 1.0:
        # speed kept to the round-off of up to max_reflections updates
        assert np.allclose(np.linalg.norm(v, axis=1), np.linalg.norm(vel, axis=1), rtol=1e-12, atol=0)


@pytest.mark.parametrize("angle", [5.0, 7.0, 30.0])
@pytest.mark.parametrize("cr", [0.0, 0.5])
def test_wedge_apex_is_one_contact_not_ping_pong(angle, cr):
    # driven into the apex of an acute wedge, the paper's one-wall-at-a-time rule bounces
    # between the walls (alternating projections; with CR = 0 it never finishes and the
    # guard used to put the particle back). The corner contact is resolved as one: a few
    # reflections, no guard, the particle at rest against both walls (CR = 0) or slower.
    dom = wedge(angle, 1.0, 2)
    r = 0.01
    pos0 = np.array([[0.8, 0.0]])
    vel = np.array([[-50.0, 0.1]])
    pos, v, g, flags, counts = run(pos0, [[-5.0, 0.01]], vel, dom.planes, r, cr)
    assert g == 0 and counts[0] <= (3 if cr == 0.0 else 20)
    assert_inside(pos, r, dom.planes)
    if cr == 0.0:
        # touching both walls, no velocity into either
        assert np.allclose(dom.planes.distances(pos)[0, :2], r, rtol=0, atol=1e-12)
        assert np.all(v @ dom.planes.normals[:2].T >= -1e-12 * 50)
    assert np.linalg.norm(v) <= np.linalg.norm(vel) * (1 + 1e-12)
    pos, v, g, flags, counts = run(pos0, [[-5.0, 0.01]], vel, dom.planes, r, 0.0,
                                   max_reflections=0)
    assert g == 1 and counts[0] == 0 and np.array_equal(v, vel) and np.array_equal(pos, pos0)


def test_an_elastic_corner_contact_keeps_the_speed():
    """A joint contact with two walls of a 30-degree corner, velocity 40 degrees below the
    floor: its reflection across the floor, 40 degrees up, enters the upper wall, so
    w + CR (w - v) (w: v projected onto the cone of admissible velocities) leaves the cone.
    With CR = 1 the walls' own sequence follows, floor then upper wall: the velocity leaves
    at 20 degrees with its speed (the projection w, used before, kept cos 40 = 0.77 of it
    and lost 41 % of the kinetic energy). CR = 0.5 leaves it slower and admissible, CR = 0
    at the projection onto the floor."""
    from sphcore_plugins.reflective.corner import respond, scratch

    a, b = np.radians(30.0), np.radians(-40.0)
    nrm = np.array([[0.0, 1.0], [np.sin(a), -np.cos(a)]])  # floor y >= 0, wall below y = x tan 30
    c = np.zeros(2)
    for cr in (1.0, 0.5, 0.0):
        ws, wi = scratch()
        pos = np.array([[0.5, 0.01]])
        vel = np.array([[np.cos(b), np.sin(b)]])
        assert respond(nrm, c, 2, pos, vel, 0, cr, 1e-12, ws[0], wi[0])
        assert np.all(nrm @ vel[0] >= -1e-12)  # no velocity into either wall
        if cr == 1.0:
            np.testing.assert_allclose(vel[0], [np.cos(np.radians(20.0)), np.sin(np.radians(20.0))],
                                       rtol=0, atol=1e-15)
        elif cr == 0.5:
            assert 0.5 < np.linalg.norm(vel[0]) < 1.0
        else:
            np.testing.assert_allclose(vel[0], [np.cos(b), 0.0], rtol=0, atol=1e-15)


# --------------------------------------------------------------------------------------
# One plane: exactly the analytic answer (Eqs. 1, 2, 8)
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("contact", [True, False])
def test_single_plane_exact_any_orientation(dim, contact):
    rng = np.random.default_rng(5 + dim + 10 * contact)
    m = 40  # particles per plane orientation
    for trial in range(100):
        nrm = random_directions(rng, 1, dim)[0]
        x0 = rng.uniform(-1, 1, dim)
        planes = Planes.from_lists([nrm], [x0])
        r = rng.uniform(0.01, 0.5, m)
        cr = rng.uniform(0.0, 1.0) if trial > 1 else float(trial)  # CR = 0 and 1 included
        da = r + rng.uniform(0.0, 1.0, m) * (rng.uniform(size=m) < 0.8)  # start on or off the wall
        db = r - np.exp(rng.uniform(np.log(1e-6), np.log(2.0), m))  # end beyond contact
        tang = rng.uniform(-1, 1, (m, dim))
        tang -= np.outer(tang @ nrm, nrm)
        c0 = x0 + da[:, None] * nrm + tang
        c1 = x0 + db[:, None] * nrm + rng.uniform(-1, 1, (m, 1)) * tang
        vel = rng.uniform(-3, 3, (m, dim))
        acc = rng.uniform(-10, 10, (m, dim))
        acc[: m // 4] = 0.0
        pos, v, g, _, counts = run(c0, c1, vel, planes, r, cr, acc=acc, velocity_at_contact=contact)
        depth = r - planes.distances(c1)[:, 0]
        assert np.all(counts == 1) and g == 0
        # Eqs. 1 and 8: moved (1 + CR)(r - d) along n
        assert np.allclose(pos, c1 + ((1 + cr) * depth)[:, None] * nrm, rtol=0, atol=1e-14)
        u, an = vel @ nrm, acc @ nrm
        if contact:
            uc2 = np.maximum(u * u + 2 * an * depth, 0.0)
            uf = np.sqrt(np.maximum(cr**2 * uc2 + 2 * an * cr * depth, 0.0))
        else:
            uf = -cr * u
        uf = np.where(u < 0, uf, u)  # a particle moving back in keeps its velocity
        assert np.allclose(v, vel + (uf - u)[:, None] * nrm, rtol=0, atol=1e-13)
        # tangential velocity untouched
        assert np.allclose(v - np.outer(v @ nrm, nrm), vel - np.outer(u, nrm), rtol=0, atol=1e-14)
        # without acceleration both forms are Eq. 2: u_f = -CR u
        still = (an == 0) | (not contact)
        assert np.allclose((v @ nrm)[still], np.where(u < 0, -cr * u, u)[still], rtol=0, atol=1e-13)


def test_contact_velocity_equals_eq2_without_acceleration():
    rng = np.random.default_rng(1)
    m = 1000
    planes = Planes.from_lists([[0.6, 0.8]], [[0.0, 0.0]])
    n = planes.normals[0]
    pos0 = np.outer(rng.uniform(0.1, 1.0, m), n) + 0.2
    vel = -np.outer(rng.uniform(0.5, 5.0, m), n) + rng.uniform(-1, 1, (m, 2))
    pos1 = pos0 + 1.0 * vel
    for cr in (0.0, 0.3, 1.0):
        a = run(pos0, pos1, vel, planes, 0.1, cr, velocity_at_contact=True)
        b = run(pos0, pos1, vel, planes, 0.1, cr, velocity_at_contact=False)
        assert np.array_equal(a[0], b[0])
        assert np.allclose(a[1], b[1], rtol=1e-15, atol=1e-15)


def test_wrapper_rejects_arrays_it_would_copy():
    planes = Planes.box([0, 0], [1, 1])
    pos = np.full((2, 2), 0.5)
    with pytest.raises(ValueError):
        reflect_particles(pos, pos.astype(np.float32), np.zeros((2, 2)), None, 0.1, planes)
    with pytest.raises(ValueError):
        reflect_particles(pos, pos.copy(), np.zeros((2, 2)), None, 0.1, planes, cr=1.5)
    with pytest.raises(ValueError):  # a strided view
        reflect_particles(pos, np.full((2, 3), 0.5)[:, :2], np.zeros((2, 2)), None, 0.1, planes)
