"""Physics of the reflective boundary with finite wall faces (segments, triangles).

Property tests on random domains built as in ``benchmarks/fuzz/fuzz_faces.py``: box tanks with
box obstacles (turned at random), non-convex tanks given by faces only (a star polygon in
2D, a step- or L-shaped triangle mesh in 3D), tanks split by a closed plate exactly 2r
thick and by an open sheet; steps up to 100 domain lengths, CR in [0, 1]. Then exact cases
worked out by hand (a segment's interior and end point, a triangle's interior), a plate hit
at 100 domain lengths per step, particles at rest or sliding at distance r, and a closed
face box against the same box of planes.

Start points of the property tests lie strictly inside the admissible region, and their
examples are derandomized (the same on every run). Steps that start touching a slanted face (distance
r up to round-off) are covered by the deterministic tests at the end.
"""

import importlib.util
import math
import sys
from pathlib import Path

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sphcore.geometry.facegeom import face_distance
from sphcore.geometry.faces import Faces, box, closed_wall, polygon, polyline
from sphcore.geometry.planes import Planes
from sphcore_plugins.reflective.entry import reflect_particles


def _load_benchmark(name):
    """The module benchmarks/fuzz/<name>.py, registered under its name (so that fuzz_faces finds
    fuzz_domains already loaded)."""
    path = Path(__file__).resolve().parents[1] / "benchmarks" / "fuzz" / f"{name}.py"
    spec = importlib.util.spec_from_file_location(name, path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[name] = module  # dataclasses look their module up while it runs
    spec.loader.exec_module(module)
    return module


fd = _load_benchmark("fuzz_domains")  # the random domains (first: fuzz_faces imports it)
ff = _load_benchmark("fuzz_faces")  # the escape / crossing check

M = 60  # trajectories per example
# derandomized: the same examples on every run (see the module docstring)
SETTINGS = settings(max_examples=100, deadline=None, derandomize=True, database=None)
KINDS = st.sampled_from(fd.KINDS)


def kernel(pos0, pos1, vel, acc, radius, planes, faces, cr, **kw):
    """reflect_particles on copies; returns pos, vel, guard count, flags, counts."""
    pos0 = np.ascontiguousarray(pos0, dtype=float)
    pos = np.array(pos1, dtype=float, order="C")
    v = np.array(vel, dtype=float, order="C")
    n = len(pos)
    flags, counts = np.empty(n, np.int8), np.empty(n, np.int32)
    g = reflect_particles(pos0, pos, v, acc, radius, planes, cr, guarded_flags=flags,
                          reflection_counts=counts, faces=faces, **kw)
    return pos, v, g, flags, counts


def run(scene):
    return kernel(scene.pos0, scene.pos1, scene.vel, scene.acc, scene.radius, scene.dom.planes,
                  scene.dom.faces, scene.cr, velocity_at_contact=scene.contact)


@st.composite
def scenes(draw, cr=None, accelerate=None, max_step=100.0):
    """(kind, seed, cr, accelerate, contact, max_step): a random domain of a random kind
    with M trajectories (``fuzz_domains.make_scene``, see :func:`build`), started strictly
    inside the admissible region. Drawn as numbers so that a failing example prints
    short and can be rebuilt."""
    kind = draw(KINDS)
    seed = draw(st.integers(0, 2**32 - 1))
    if cr is None:
        cr = draw(st.one_of(st.just(0.0), st.just(1.0), st.floats(0.0, 1.0)))
    if accelerate is None:
        accelerate = draw(st.booleans())
    return kind, seed, cr, accelerate, draw(st.booleans()), max_step


def build(kind, seed, cr, accelerate, contact, max_step):
    return fd.make_scene(kind, np.random.default_rng(seed), M, cr=cr, accelerate=accelerate,
                         contact=contact, max_step=max_step, on_wall=0.0)


def assert_no_escape(scene, pos, vel):
    esc, cro, bad = ff.check(scene, pos, vel)
    assert not bad.any(), "non-finite position or velocity"
    assert not esc.any(), f"escaped: {np.nonzero(esc)[0]}"
    assert not cro.any(), f"crossed the plate: {np.nonzero(cro)[0]}"


# -- properties on random domains ------------------------------------------------------

@SETTINGS
@given(scenes())
def test_no_escape_no_crossing_finite(params):
    scene = build(*params)
    assert fd.admissible(scene.dom, scene.pos0, scene.radius).all()  # the precondition
    pos, v, g, flags, counts = run(scene)
    assert_no_escape(scene, pos, v)
    assert g == int(flags.sum()) and set(np.unique(flags)) <= {0, 1}
    assert np.array_equal(pos[flags == 1], scene.pos0[flags == 1])
    # particles no wall touched are left bit for bit
    free = counts == 0
    assert np.array_equal(pos[free], scene.pos1[free]) and np.array_equal(v[free], scene.vel[free])
    # a step shorter than 1e-3 r that ends 2e-3 r clear of every wall never comes within
    # r of one: untouched
    short = np.linalg.norm(scene.pos1 - scene.pos0, axis=1) < 1e-3 * scene.radius
    short &= fd.admissible(scene.dom, scene.pos1, scene.radius * (1 + 2e-3))
    assert not counts[short].any()


@pytest.mark.slow
@SETTINGS
@given(scenes(accelerate=False))
def test_restitution_never_adds_energy(params):
    scene = build(*params)
    pos, v, g, flags, counts = run(scene)
    speed0, speed = np.linalg.norm(scene.vel, axis=1), np.linalg.norm(v, axis=1)
    assert np.all(speed <= speed0 * (1 + 1e-12))
    assert np.isfinite(pos).all() and np.isfinite(v).all()


@pytest.mark.slow
@SETTINGS
@given(scenes(cr=1.0, accelerate=False))
def test_elastic_walls_keep_the_speed(params):
    scene = build(*params)
    pos, v, g, flags, counts = run(scene)
    speed0, speed = np.linalg.norm(scene.vel, axis=1), np.linalg.norm(v, axis=1)
    ok = flags == 0
    assert np.allclose(speed[ok], speed0[ok], rtol=1e-9, atol=0)
    assert np.isfinite(pos).all() and np.isfinite(v).all()


@settings(max_examples=50, deadline=None, derandomize=True, database=None)
@given(st.sampled_from([2, 3]), st.integers(0, 2**32 - 1), st.sampled_from([1.0, 0.5]))
def test_closed_face_box_tank_equals_the_box_of_planes(dim, seed, cr):
    # a tank given as a closed face box (fluid inside) reflects exactly as its 2 dim planes
    rng = np.random.default_rng(seed)
    lo = rng.uniform(-2.0, 2.0, dim)
    hi = lo + rng.uniform(0.5, 1.5, dim)
    r = float(rng.uniform(0.01, 0.1))
    n = 200
    pos0 = rng.uniform(lo + r, hi - r, (n, dim))
    step = fd.random_directions(rng, n, dim) * rng.uniform(0.0, (hi - lo).min(), (n, 1))
    vel = step / 1e-3
    acc = fd.random_directions(rng, n, dim) * 10.0 if rng.uniform() < 0.5 else None
    with_planes = kernel(pos0, pos0 + step, vel, acc, r, Planes.box(lo, hi), None, cr)
    with_faces = kernel(pos0, pos0 + step, vel, acc, r, None, closed_wall(box(lo, hi), True), cr)
    assert np.array_equal(with_planes[4], with_faces[4])  # the same reflections
    assert np.allclose(with_faces[0], with_planes[0], rtol=0, atol=1e-12 * (hi - lo).max())
    scale = np.linalg.norm(vel, axis=1, keepdims=True)
    assert np.all(np.abs(with_faces[1] - with_planes[1]) <= 1e-12 * scale)
    assert with_planes[4].any()  # the walls were hit


# -- exact cases -----------------------------------------------------------------------

def turn2(angle):
    c, s = math.cos(angle), math.sin(angle)
    return np.array([[c, -s], [s, c]])


@pytest.mark.parametrize("cr", [1.0, 0.5])
@pytest.mark.parametrize("angle", [0.0, 0.7])
def test_segment_interior_head_on(cr, angle):
    # the segment y = 0, -1 <= x <= 1 (turned by angle); a particle of radius 0.1 falls on
    # it from (0.2, 0.5) to (0.2, -0.3) with v = (0, -4): contact at y = r, normal (0, 1),
    # d_B = -0.3, B' = B + (1 + CR)(r - d_B) n (Eq. 1), v_n -> -CR u (Eq. 2)
    rot = turn2(angle)
    seg = polyline(np.array([[-1.0, 0.0], [1.0, 0.0]]) @ rot.T)
    a, b, v = np.array([0.2, 0.5]), np.array([0.2, -0.3]), np.array([0.0, -4.0])
    r = 0.1
    pos, vel, g, flags, counts = kernel([a @ rot.T], [b @ rot.T], [v @ rot.T], None, r, None,
                                        Faces(seg), cr)
    want_b = np.array([0.2, -0.3 + (1 + cr) * (r + 0.3)]) @ rot.T
    want_v = np.array([0.0, 4.0 * cr]) @ rot.T
    assert counts[0] == 1 and g == 0
    assert np.allclose(pos[0], want_b, rtol=0, atol=1e-14)
    assert np.allclose(vel[0], want_v, rtol=0, atol=1e-13)


@pytest.mark.parametrize("cr", [1.0, 0.5])
def test_segment_end_point_contact_is_radial(cr):
    # a particle passing the end V = (0, 0) of the segment (0, 0)-(1, 0) touches it first
    # at the vertex: at C = A + t D with |C - V| = r, and reflects off the tangent plane
    # there, normal n = (C - V) / r, radial from the vertex (not the segment's normal)
    r = 0.1
    seg = Faces(polyline([[0.0, 0.0], [1.0, 0.0]]))
    a, b = np.array([-0.4, 0.3]), np.array([0.35, -0.2])
    d = b - a
    v = d / 0.01
    # |A + t D - V|^2 = r^2: (D.D) t^2 + 2 (A.D) t + A.A - r^2 = 0, smaller root
    qa, qb, qc = d @ d, a @ d, a @ a - r * r
    t = (-qb - math.sqrt(qb * qb - qa * qc)) / qa
    c = a + t * d
    assert c[0] < 0.0 and 0.0 < t < 1.0  # in the vertex's region: not the flat part
    n = c / np.linalg.norm(c)
    d_b = n @ b  # n . (B - V); the tangent plane at the contact is n . (X - V) = r
    want_b = b + (1 + cr) * (r - d_b) * n
    u = v @ n
    want_v = v + (-cr * u - u) * n
    pos, vel, g, flags, counts = kernel([a], [b], [v], None, r, None, seg, cr)
    assert counts[0] == 1 and g == 0
    assert np.allclose(pos[0], want_b, rtol=0, atol=1e-14)
    assert np.allclose(vel[0], want_v, rtol=1e-13, atol=0)
    assert face_distance(seg.verts, 0, pos[0, 0], pos[0, 1], 0.0) >= r


@pytest.mark.parametrize("cr", [1.0, 0.5, 0.0])
def test_triangle_interior_3d(cr):
    # a slanted triangle; the particle hits its interior: contact normal = face normal
    tri = np.array([[[0.0, 0.0, 0.0], [2.0, 0.0, 0.5], [0.0, 2.0, 0.3]]])
    n = np.cross(tri[0, 1] - tri[0, 0], tri[0, 2] - tri[0, 0])
    n /= np.linalg.norm(n)
    r = 0.05
    foot = tri[0, 0] + 0.3 * (tri[0, 1] - tri[0, 0]) + 0.3 * (tri[0, 2] - tri[0, 0])
    a = foot + 0.4 * n + np.array([0.05, -0.02, 0.0])
    b = foot - 0.2 * n + np.array([0.1, 0.03, 0.0])
    v = (b - a) / 0.02
    d_b = (b - foot) @ n
    want_b = b + (1 + cr) * (r - d_b) * n
    u = v @ n
    want_v = v - (1 + cr) * u * n
    pos, vel, g, flags, counts = kernel([a], [b], [v], None, r, None, Faces(tri), cr)
    assert counts[0] == 1 and g == 0
    assert np.allclose(pos[0], want_b, rtol=0, atol=1e-14)
    assert np.allclose(vel[0], want_v, rtol=1e-13, atol=1e-13)


def plate_tank(dim, r, turned):
    """The unit box tank (planes) split at x = 0.5 by a closed plate 2r thick (faces),
    optionally turned by 30 degrees about the tank's centre, reaching 0.5 beyond the tank
    (the face grid, and the cost of a step, grow with the plate); returns planes, faces,
    the plate's mid-point and normal."""
    c = np.full(dim, 0.5)
    rot = np.eye(dim)
    if turned:
        rot = np.eye(dim)
        rot[:2, :2] = turn2(math.radians(30.0))
    half = np.full(dim, 1.0)
    half[0] = r
    faces = closed_wall(fd.turned_box(-half, half, rot, np.zeros(dim)) + c, fluid_inside=False)
    return Planes.box(np.zeros(dim), np.ones(dim)), faces, c, rot[:, 0]


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("turned", [False, True])
@pytest.mark.parametrize("cr", [0.0, 0.5, 1.0])
def test_thin_plate_hit_at_100_domain_lengths_per_step(dim, turned, cr):
    r = 0.02
    planes, faces, c, normal = plate_tank(dim, r, turned)
    rng = np.random.default_rng(dim * 10 + int(turned) + int(4 * cr))
    dom = fd.Domain(dim, planes, faces, np.zeros(dim), np.ones(dim), 1.0, c, normal)
    n = 200 if dim == 2 else 60
    pos0 = fd.sample_starts(rng, dom, np.full(n, r), on_wall=0.0)
    # towards the plate, 100 domain lengths in one step (a few 1 to 100)
    u = fd.random_directions(rng, n, dim)
    side = np.sign((pos0 - c) @ normal)
    u *= np.where((u @ normal) * side > 0, -1.0, 1.0)[:, None]
    length = np.where(np.arange(n) < n // 4, rng.uniform(1.0, 100.0, n), 100.0)[:, None]
    step = u * length
    scene = fd.Scene(dom, np.full(n, r), pos0, pos0 + step, step / 1e-3, np.zeros((n, dim)), cr, True)
    pos, vel, g, flags, counts = run(scene)
    assert_no_escape(scene, pos, vel)
    assert (counts > 0).all()


def touching(verts, f, bary, r):
    """A centre at distance r from face f (its normal side), over the point with
    barycentric weights ``bary``."""
    n = Faces(verts[f:f + 1]).normals()[0]
    return np.einsum("j,jd->d", np.asarray(bary, float), verts[f]) + r * n


WALLS = {
    "segment": Faces(polyline([[0.1, 0.2], [1.3, 0.9]])),
    "obstacle-2d": closed_wall(polygon(fd.star_polygon(np.random.default_rng(3), np.zeros(2), 1.0)), False),
    "triangle": Faces(np.array([[[0.0, 0.1, 0.0], [1.0, 0.2, 0.4], [0.1, 1.0, 0.3]]])),
    "mesh-tank": closed_wall(fd.heightmap_mesh(np.random.default_rng(4), np.zeros(3), 1.0)
                             @ fd.random_rotation(np.random.default_rng(5), 3).T, True),
}


@pytest.mark.parametrize("name", sorted(WALLS))
def test_at_rest_touching_a_face_is_bit_for_bit_unchanged(name):
    faces = WALLS[name]
    dim = faces.dim
    rng = np.random.default_rng(7)
    r = 0.02
    pts = []
    for f in range(faces.count):
        w = rng.dirichlet(np.ones(dim), 5)
        pts += [touching(faces.verts, f, wf, r) for wf in w]
    pos0 = np.array(pts)
    pos0 = pos0[fd.admissible(fd.Domain(dim, None, faces, None, None, 1.0), pos0, np.full(len(pos0), r))]
    assert len(pos0) >= 5
    vel = rng.standard_normal(pos0.shape)  # also pushing into the wall
    acc = rng.standard_normal(pos0.shape) * 100.0
    for cr in (0.0, 0.5, 1.0):
        pos, v, g, flags, counts = kernel(pos0, pos0, vel, acc, r, None, faces, cr)
        assert np.array_equal(pos, pos0) and np.array_equal(v, vel)
        assert g == 0 and not counts.any()


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("slanted", [False, True])
def test_moving_parallel_to_a_face_at_distance_r_is_unchanged(dim, slanted):
    r = 0.05
    if dim == 2:
        verts = np.array([[[0.0, 0.0], [1.0, 0.0]]])
        if slanted:
            verts = np.ascontiguousarray(verts @ turn2(0.6).T + 0.3)
    else:
        verts = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.0], [0.0, 1.0, 0.0]]])
        if slanted:
            verts = np.ascontiguousarray(verts @ fd.random_rotation(np.random.default_rng(1), 3).T + 0.3)
    faces = Faces(verts)
    w = np.linspace(0.05, 0.9, 12)
    if dim == 2:
        bary = np.stack([1 - w, w], axis=1)
        # along the segment, and past its end (over the end vertex, still at r)
        a = np.array([touching(verts, 0, [0.9, 0.1], r)] * 12)
        b = np.array([touching(verts, 0, wb, r) for wb in bary])
        b[-3:] = a[-3:] + 3.0 * (b[-3:] - a[-3:])
    else:
        bary = np.stack([1 - w, w * 0.5, w * 0.5], axis=1)
        a = np.array([touching(verts, 0, [0.8, 0.1, 0.1], r)] * 12)
        b = np.array([touching(verts, 0, wb, r) for wb in bary])
    vel = (b - a) / 1e-3
    for cr in (0.0, 0.5, 1.0):
        pos, v, g, flags, counts = kernel(a, b, vel, None, r, None, faces, cr)
        assert np.array_equal(pos, b) and np.array_equal(v, vel)
        assert not counts.any()


# -- a segment that starts touching a face --------------------------------------------
# A sub-segment A -> B of a step may start touching a face: a start on the wall, or the
# contact point of a reflection that also touches a second wall (CR = 0 sliding into a
# concave corner). There face_distance(A) can round to r plus an ulp while n . (A - P), the
# distance to the face's line or plane, rounds to r or just below: first_contact(..., r)
# then returned inf (neither "already touching", <= r, nor the flat part's entry, > r) and
# earliest_face dropped the face, letting the particle through (about 1 in 1,000 starts on
# slanted walls, in the fuzz benchmark before the fix in facecontact.earliest_face).

def test_touching_start_moving_into_a_slanted_segment():
    # minimal case: segment (0, 0)-(1, 0.3), r = 0.01, A at distance r from it (computed
    # r + 1.7e-17, n . A - r = -1.9e-17), moving 0.05 straight into it; the kernel left B
    # untouched, beyond the segment
    faces = Faces(polyline([[0.0, 0.0], [1.0, 0.3]]))
    n = np.array([-0.3, 1.0]) / math.hypot(0.3, 1.0)
    r = 0.01
    a = np.array([0.8451844601745512, 0.2639956445612759])
    b = np.array([0.8595518544528684, 0.2161043303002183])  # a - 0.05 n
    assert face_distance(faces.verts, 0, a[0], a[1], 0.0) > r
    pos, vel, g, flags, counts = kernel([a], [b], [-n], None, r, None, faces, 1.0)
    # expected: reflected at A, B' = A + 0.05 n (clearance 0.06), v = +n
    assert n @ (pos[0] - faces.verts[0, 0]) > 0, f"crossed the segment: {pos[0]}"
    assert np.allclose(pos[0], a + 0.05 * n, rtol=0, atol=1e-12)
    assert np.allclose(vel[0], n, rtol=0, atol=1e-12)


def test_touching_start_moving_into_a_slanted_triangle():
    tri = np.array([[[0.0, 0.0, 0.0], [1.0, 0.0, 0.3], [0.0, 1.0, 0.2]]])
    n = Faces(tri).normals()[0]
    r = 0.01
    a = np.array([0.18709140455606466, 0.22492472462253038, 0.11174251210406012])
    b = np.array([0.2012022175818186, 0.23433193330636637, 0.06470646868488025])  # a - 0.05 n
    assert face_distance(tri, 0, *a) > r
    pos, vel, g, flags, counts = kernel([a], [b], [-n], None, r, None, Faces(tri), 1.0)
    assert n @ pos[0] > 0, f"crossed the triangle: {pos[0]}"
    assert np.allclose(pos[0], a + 0.05 * n, rtol=0, atol=1e-12)


def test_touching_starts_in_random_domains():
    # every kind of the benchmark, starts touching a wall (fixed seeds; about 1 in 1,000
    # escaped or crossed before the fix)
    rng = np.random.default_rng(11)
    failures = 0
    for kind in fd.KINDS:
        for _ in range(2):
            scene = fd.make_scene(kind, rng, 400, on_wall=1.0, max_step=1.0)
            pos, v, g, flags, counts = run(scene)
            esc, cro, bad = ff.check(scene, pos, v)
            failures += int((esc | cro | bad).sum())
    assert failures == 0, f"{failures} of {len(fd.KINDS) * 800} touching starts escaped or crossed"


def test_sliding_into_a_concave_corner_with_cr_0():
    # an open V of two segments meeting at the origin (fluid above); with CR = 0 the particle
    # hits the right arm, slides to the left arm, and the contact there lies r + 2e-18 from
    # the right arm with n . (A - P) = r exactly: the kernel moved it into the right arm and
    # stopped there (end 0.0032 closer than r to it)
    a1, a2 = 1.0598610546209364, 0.9506438382654405
    faces = Faces(polyline([[-1.0, a1], [0.0, 0.0], [1.0, a2]]))
    r = 0.01
    a = np.array([-0.026129089120069948, 0.16868125496229094])
    b = np.array([0.4125129584092545, -1.6575885021314947])
    pos, vel, g, flags, counts = kernel([a], [b], [(b - a) / 1e-3], None, r, None, faces, 0.0)
    clearance = faces.distances(pos)[0] - r
    assert clearance >= -1e-9 * r, f"ends {-clearance} closer than r to the wall: {pos[0]}"


# --------------------------------------------------------------------------------------
# Found in review: an overlapping start leaving, a step to 1e18 m, a box corner under gravity
# --------------------------------------------------------------------------------------


@pytest.mark.parametrize("cr", [0.0, 0.5, 1.0])
def test_a_start_overlapping_a_face_and_leaving_it_is_left_alone(cr):
    # A at 0.5 from a segment, r = 1 (an overlap left by an earlier bad state), moving
    # away: the path never comes closer, so no contact (it used to be pinned by the guard)
    faces = Faces(polyline([[-10.0, 0.0], [10.0, 0.0]]))
    pos, vel, g, flags, counts = kernel([[0.0, 0.5]], [[0.0, 2.0]], [[0.0, 1.5]], None, 1.0, None, faces, cr)
    assert g == 0 and counts[0] == 0
    assert np.array_equal(pos, [[0.0, 2.0]]) and np.array_equal(vel, [[0.0, 1.5]])


@pytest.mark.parametrize("length", [1e17, 1e18, 1e30])
def test_a_step_of_any_length_stays_in_a_tank_of_faces(length):
    # the grid's cell range must not overflow for a point far outside it (the int of a
    # floor used to wrap and the query saw no cell). Steps whose squares overflow (1e300 m,
    # inf) belong to a run already blown up: the core's checks stop it as unstable.
    tank = closed_wall(box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0]), True)
    a = np.array([[0.5, 0.5, 0.5]])
    b = np.array([[0.5 + length, 0.5, 0.5]])
    pos, vel, g, flags, counts = kernel(a, b, [[1.0, 0.0, 0.0]], None, 0.01, None, tank, 1.0)
    assert np.all(np.isfinite(pos))
    assert tank.in_fluid(pos)[0] and tank.distances(pos)[0] >= 0.01 * (1 - 1e-9)


@pytest.mark.parametrize("cr", [0.5, 1.0])
def test_a_box_corner_under_gravity_keeps_the_contact_form_of_eq2(cr):
    # three walls met once each: the paper's sequence (no joint contact), so Eq. 2 at the
    # contact corrects each wall's normal velocity for gravity's work: the floor's
    # normal velocity comes out below CR |u| (here 0 for the z wall), not -CR u
    planes = Planes.box([0.0, 0.0, 0.0], [1.0, 1.0, 1.0])
    pos, vel, g, flags, counts = kernel([[0.1, 0.1, 0.1]], [[0.05, 0.05, 0.05]], [[-1.0, -1.0, -1.0]],
                                        np.array([[0.0, 0.0, -9.81]]), 0.1, planes, None, cr)
    assert counts[0] == 3 and g == 0
    assert np.allclose(vel[0, :2], cr) and 0.0 <= vel[0, 2] < cr
