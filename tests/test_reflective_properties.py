"""Property tests of the reflective kernel on random bounded convex domains.

Boxes (turned at random), wedges down to 5 degrees and random polygons / polyhedra made
of tangent planes about a centre; start points inside the admissible region {d >= r};
displacements up to 100 domain lengths in one step; CR in [0, 1].
"""

import numpy as np
from domains import box, random_directions, random_polytope, random_rotation, sample_inside, wedge
from hypothesis import given, settings
from hypothesis import strategies as st

from sphcore_plugins.reflective.entry import outside, reflect_particles

SETTINGS = settings(max_examples=150, deadline=None)
M = 300  # particles per example


@st.composite
def scenes(draw, cr=None, accelerate=True):
    """A domain, radii, start and end points, velocities, accelerations and CR."""
    dim = draw(st.sampled_from([2, 3]))
    kind = draw(st.sampled_from(["box", "wedge", "polytope"]))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    if kind == "box":
        dom = box(np.zeros(dim), rng.uniform(0.2, 2.0, dim), random_rotation(rng, dim))
    elif kind == "wedge":
        angle = draw(st.sampled_from([5.0, 7.5, 15.0, 45.0, 90.0, 150.0]))
        dom = wedge(angle, 1.0, dim, height=rng.uniform(0.2, 1.0))
    else:
        dom = random_polytope(rng, dim, draw(st.integers(dim + 1, 12)))
    r = dom.inradius * draw(st.floats(0.01, 0.9))
    radius = r * rng.uniform(0.3, 1.0, M)  # one r per particle; all fit around the centre
    pos0 = sample_inside(rng, dom, r, M)
    scale = dom.size * 10.0 ** draw(st.floats(-4.0, 2.0))  # up to 100 domain lengths
    step = random_directions(rng, M, dim) * rng.uniform(0.0, 1.0, (M, 1)) * scale
    step[: M // 10] = 0.0  # some at rest (C1 = C0)
    dt = 10.0 ** rng.uniform(-5, 0)
    vel = step / dt
    vel[M // 10: M // 5] = rng.standard_normal((M // 5 - M // 10, dim))  # unrelated velocities
    acc = np.zeros((M, dim))
    if accelerate and draw(st.booleans()):
        acc = rng.standard_normal((M, dim)) * 10.0 ** rng.uniform(-2, 3)
    if cr is None:
        cr = draw(st.one_of(st.just(0.0), st.just(1.0), st.floats(0.0, 1.0)))
    return dom, radius, pos0, pos0 + step, vel, acc, cr


def kernel(pos0, pos1, vel, acc, radius, planes, cr, **kw):
    pos, v = pos1.copy(), vel.copy()
    flags, counts = np.empty(len(pos), np.int8), np.empty(len(pos), np.int32)
    g = reflect_particles(pos0, pos, v, acc, radius, planes, cr, guarded_flags=flags,
                          reflection_counts=counts, **kw)
    return pos, v, g, flags, counts


@SETTINGS
@given(scenes(), st.booleans())
def test_no_particle_ever_escapes(scene, contact):
    dom, radius, pos0, pos1, vel, acc, cr = scene
    assert not outside(pos0, radius, dom.planes).any()  # the precondition
    pos, v, g, flags, counts = kernel(pos0, pos1, vel, acc, radius, dom.planes, cr,
                                      velocity_at_contact=contact)
    assert np.all(np.isfinite(pos)) and np.all(np.isfinite(v))
    assert not outside(pos, radius, dom.planes).any()
    # the guard count is reported, and guarded particles sit at their start
    assert g == int(flags.sum()) and set(np.unique(flags)) <= {0, 1}
    assert np.array_equal(pos[flags == 1], pos0[flags == 1])
    # particles that ended inside were not touched at all, bit for bit
    inside = ~outside(pos1, radius, dom.planes)
    assert np.all(counts[inside] == 0) and np.all(counts[~inside] >= 1)
    assert np.array_equal(pos[inside], pos1[inside]) and np.array_equal(v[inside], vel[inside])


@SETTINGS
@given(scenes(cr=1.0, accelerate=False), st.booleans())
def test_elastic_reflection_keeps_speed(scene, contact):
    dom, radius, pos0, pos1, vel, acc, cr = scene
    pos, v, g, flags, counts = kernel(pos0, pos1, vel, acc, radius, dom.planes, 1.0,
                                      velocity_at_contact=contact)
    speed0, speed = np.linalg.norm(vel, axis=1), np.linalg.norm(v, axis=1)
    # an elastic reflection v - 2 (v . n) n is an isometry up to round-off: the dot
    # product (dim eps |v|, doubled), the update (3 eps |v|) and the unit normal's own
    # |n|^2 - 1 (2 (dim + 2) eps): at most (4 dim + 7) eps |v| per reflection, added up over
    # the particle's reflections (up to max_reflections = 1000 in one step)
    eps = np.finfo(float).eps
    dim = pos0.shape[1]
    assert np.all(np.abs(speed - speed0) <= (4 * dim + 7) * eps * np.maximum(counts, 1) * speed0)
    assert not outside(pos, radius, dom.planes).any()


@SETTINGS
@given(scenes())
def test_at_rest_anywhere_inside_is_untouched(scene):
    # C1 = C0 inside (also touching a wall, d = r up to an ulp): nothing changes, any CR
    dom, radius, pos0, _, vel, acc, cr = scene
    pos, v, g, flags, counts = kernel(pos0, pos0, vel, acc, radius, dom.planes, cr)
    assert np.array_equal(pos, pos0) and np.array_equal(v, vel)
    assert g == 0 and not counts.any()


@SETTINGS
@given(scenes(cr=0.0, accelerate=False))
def test_inelastic_walls_never_speed_particles_up(scene):
    # CR = 0 removes the outward normal velocity: the speed can only drop
    dom, radius, pos0, pos1, vel, acc, cr = scene
    pos, v, g, flags, counts = kernel(pos0, pos1, vel, acc, radius, dom.planes, 0.0)
    # each reflection removes a normal component: a projection, up to round-off
    assert np.all(np.linalg.norm(v, axis=1) <= np.linalg.norm(vel, axis=1) * (1 + 1e-12))
    assert not outside(pos, radius, dom.planes).any()


def billiard(p, w, normals, offsets, r, max_hits=1000):
    """Reference for CR = 1 and no acceleration: trace the centre from p along w (the whole
    step), mirroring the remaining path at the first plane {d = r} it reaches. Returns the
    end point, the unit-speed direction changes applied to a velocity, and the hit count."""
    p, w = p.copy(), w.copy()
    mirrors = []
    for _ in range(max_hits + 1):
        d = normals @ p - offsets
        nw = normals @ w
        with np.errstate(divide="ignore", invalid="ignore"):
            t = np.where(nw < 0, np.maximum(d - r, 0.0) / -nw, np.inf)
        k = int(np.argmin(t))
        if not t[k] < 1.0:
            return p + w, mirrors
        p = p + t[k] * w
        w = (1.0 - t[k]) * w
        w = w - 2 * (w @ normals[k]) * normals[k]
        mirrors.append(k)
    return None, mirrors  # too many hits: the kernel's guard case


@settings(max_examples=80, deadline=None)
@given(scenes(cr=1.0, accelerate=False))
def test_elastic_result_is_the_billiard(scene):
    # with CR = 1 mirroring the end point (Eq. 8) across the first plane reached (Eqs. 5-7)
    # and restarting from the contact point (Fig. 6) is exactly the billiard trajectory
    dom, radius, pos0, pos1, vel, acc, _ = scene
    m = 20
    sl = slice(M // 5, M // 5 + m)  # moving particles (the first M // 10 rest)
    pos0, radius = pos0[sl], radius[sl]
    step = pos1[sl] - pos0
    # up to 3 domain lengths: the pure-Python reference is slow
    step *= np.minimum(1.0, 3 * dom.size / np.maximum(np.linalg.norm(step, axis=1), 1e-300))[:, None]
    vel = step / 1e-2
    pos, v, g, flags, counts = kernel(pos0, pos0 + step, vel, None, radius, dom.planes, 1.0)
    nrm, off = dom.planes.normals, dom.planes.offsets
    for i in range(m):
        want, mirrors = billiard(pos0[i], step[i], nrm, off, radius[i])
        if want is None or flags[i]:
            continue
        assert counts[i] == len(mirrors)
        assert np.allclose(pos[i], want, rtol=0, atol=1e-9 * dom.size)
        u = vel[i].copy()
        for k in mirrors:
            u -= 2 * (u @ nrm[k]) * nrm[k]
        assert np.allclose(v[i], u, rtol=1e-9, atol=0)
