"""A ball bouncing under gravity: why Eq. 2 is applied at the contact point.

The ball is stepped exactly as the core's leapfrog steps a constant acceleration a:
pos0 = x; x = x + dt (v + dt/2 a); v_end = v + dt a; reflect(pos0, x, v_end, a); v = v_end.
Free flight then keeps E = |v|^2/2 - a . x exactly (up to round-off), so any change of E
is the wall's doing.
"""

import numpy as np
import pytest

from sphcore.geometry.planes import Planes
from sphcore_plugins.reflective.entry import reflect_particles

G = 9.81


def bounce(planes, x, v, a, r, dt, cr, steps, contact=True):
    """Step balls (rows of x, v; a and dt per row); return per-step E, normal energy,
    reflection counts, heights above contact and |v|^2/2 + |a . x| (the size of E's terms,
    for round-off), each (steps + 1, n)."""
    x, v = np.array(x, float), np.array(v, float)
    a = np.ascontiguousarray(np.broadcast_to(np.asarray(a, float), x.shape))
    dt = np.asarray(dt, float).reshape(-1, 1)
    xs, vs = np.empty((steps + 1,) + x.shape), np.empty((steps + 1,) + x.shape)
    hits = np.zeros((steps + 1, len(x)), np.int32)
    flags = np.zeros(len(x), np.int8)
    xs[0], vs[0] = x, v
    for k in range(1, steps + 1):
        pos0 = x
        x = x + dt * (v + dt / 2 * a)
        v = v + dt * a
        g = reflect_particles(pos0, x, v, a, r, planes, cr, velocity_at_contact=contact,
                              guarded_flags=flags, reflection_counts=hits[k])
        assert g == 0
        xs[k], vs[k] = x, v
    n_hat = planes.normals[0]
    z = xs @ n_hat - planes.offsets[0] - r  # height of the ball above contact (m)
    u, an = vs @ n_hat, a @ n_hat
    energy = 0.5 * np.sum(vs * vs, axis=2) - np.sum(a * xs, axis=2)
    normal = 0.5 * u * u - an * z
    terms = 0.5 * np.sum(vs * vs, axis=2) + np.abs(np.sum(a * xs, axis=2))
    return energy, normal, hits, z, terms


FLOOR = Planes.from_lists([[0.0, 1.0]], [[0.0, 0.0]])
R = 0.01


def drop_2d(h0, dt):
    """Balls dropped from rest at heights h0 (contact point), drifting sideways."""
    n = len(h0)
    x = np.stack([np.zeros(n), np.asarray(h0) + R], axis=1)
    v = np.stack([np.full(n, 0.3), np.zeros(n)], axis=1)
    return x, v, np.array([0.0, -G]), np.asarray(dt, float)


def test_elastic_bounces_keep_mechanical_energy():
    h0, dt = [0.25, 0.5, 1.0], [4e-3, 5e-3, 8e-3]
    x, v, a, dt = drop_2d(h0, dt)
    steps = 13500  # >= 100 bounces for every ball (period 2 sqrt(2 h / g))
    energy, _, hits, _, _ = bounce(FLOOR, x, v, a, R, dt, 1.0, steps)
    assert np.all((hits > 0).sum(axis=0) >= 100)
    rel = np.abs(energy - energy[0]) / energy[0]
    assert rel.max() < 1e-12, rel.max()


def test_elastic_bounces_on_a_slanted_floor_3d():
    # gravity has a tangential part: the ball slides while it bounces; E is still kept
    planes = Planes.from_lists([[0.1, 0.05, 1.0]], [[0.0, 0.0, -1.0]])
    n_hat = planes.normals[0]
    x = np.array([[0.0, 0.0, 0.0]]) + R * n_hat
    x[0, 2] += 1.0
    v = np.array([[0.5, -0.2, 0.0]])
    a = np.array([0.0, 0.0, -G])
    energy, normal, hits, _, terms = bounce(planes, x, v, a, R, 4e-3, 1.0, 8000)
    assert (hits > 0).sum() >= 20
    # round-off relative to the terms of E: |v|^2/2 and |a . x| grow as the ball slides
    assert np.abs(energy - energy[0]).max() < 1e-12 * terms.max()
    assert np.abs(normal - normal[0]).max() / normal[0] < 1e-11


@pytest.mark.parametrize("e", [0.9, 0.6])
def test_inelastic_bounce_scales_normal_energy_by_cr_squared(e):
    dt = 1e-3
    x, v, a, _ = drop_2d([1.0], [dt])
    # stop while the bounces are much higher than one step's travel (see collision.py)
    bounces = 20 if e == 0.9 else 8
    steps = int(2.2 * np.sqrt(2 * 1.0 / G) / (1 - e) / dt)
    energy, normal, hits, height, _ = bounce(FLOOR, x, v, a, R, dt, e, steps)
    hit = np.flatnonzero(hits[:, 0] > 0)[:bounces]
    assert len(hit) == bounces
    before, after = normal[hit - 1, 0], normal[hit, 0]
    # free flight keeps the normal energy; each bounce multiplies it by e^2 (Eq. 2)
    assert np.allclose(after, e**2 * before, rtol=1e-12, atol=0)
    assert np.allclose(before[1:], after[:-1], rtol=1e-12, atol=0)
    # tangential motion is untouched
    assert np.all(np.abs(energy[:, 0] - normal[:, 0] - (0.5 * 0.3**2 + G * R)) < 1e-13)
    # so the apex heights follow e^2: sampled apex within g dt^2 / 8 of E / g
    apex = np.array([height[h0:h1 + 1, 0].max() for h0, h1 in zip(hit[:-1], hit[1:])])
    assert np.allclose(apex, after[:-1] / G, rtol=0, atol=G * dt**2 / 8 + 1e-15)
    # ratio of sampled apexes: |ratio - e^2| <= (g dt^2 / 8) / apex_k
    assert np.all(np.abs(apex[1:] / apex[:-1] - e**2) <= G * dt**2 / 8 / apex[:-1] + 1e-12)


def test_literal_end_point_eq2_gains_energy_every_bounce():
    # Eq. 2 applied at the end point mirrors the position but not the work of gravity:
    # every elastic bounce gains 2 g (r - d_B) = O(g |v| dt)
    dt = 2e-3
    x, v, a, _ = drop_2d([1.0], [dt])
    energy, _, hits, height, _ = bounce(FLOOR, x, v, a, R, dt, 1.0, 4600, contact=False)
    hit = np.flatnonzero(hits[:, 0] > 0)
    assert len(hit) >= 5
    gain = energy[hit, 0] - energy[hit - 1, 0]
    depth = height[hit, 0]  # after the mirror the ball sits r - d_B above contact
    assert np.allclose(gain, 2 * G * depth, rtol=1e-9, atol=0)
    assert np.all(gain > 0)
    assert (energy[-1, 0] - energy[0, 0]) / energy[0, 0] > 1e-2
    # the contact form on the same drop keeps it
    energy_c, *_ = bounce(FLOOR, x, v, a, R, dt, 1.0, 4600, contact=True)
    assert np.abs(energy_c[:, 0] - energy_c[0, 0]).max() / energy_c[0, 0] < 1e-12
