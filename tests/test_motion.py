"""Prescribed wall motion (sphcore.geometry.motion): the velocity and the acceleration of
every wall point are the time derivatives of its position, for every kind of part, ramped
or not, in 2D and 3D; the pose's inverse is its inverse; a spline passes through its
samples and reproduces a cubic; the ramp is C2 and its integral is its integral."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sphcore.geometry.motion import (ConstantVelocity, Motion, Pose, Ramp, RotationSeries, SineRotation,
                                     SineTranslation, Spline, TranslationSeries, rotation_matrix)


def _unit(v):
    v = np.asarray(v, float)
    return v / np.linalg.norm(v)


def _motions(dim):
    """Every kind of part, alone and summed, ramped and not."""
    rng = np.random.default_rng(7)
    ts = np.linspace(-0.1, 3.0, 40)
    series = Spline(ts, np.stack([0.02 * np.sin(2.1 * ts + k) for k in range(dim)], axis=1))
    angles = Spline(ts, 0.07 * np.sin(3.3 * ts) + 0.01 * ts ** 2)
    axis = _unit([0.3, -0.5, 0.8]) if dim == 3 else None
    centre = rng.normal(0, 0.3, dim)
    ramp = Ramp(0.2, 0.6)
    out = []
    for r in (Ramp(), ramp):
        parts = {
            "velocity": ConstantVelocity(rng.normal(0, 1.0, dim), r),
            "sine": SineTranslation(_unit(rng.normal(0, 1, dim)), 0.05, 2 * math.pi / 1.63, 0.4, r),
            "series": TranslationSeries(series, r),
        }
        rots = {"sine": SineRotation(math.radians(4.0), 2 * math.pi / 1.63, 0.3, r), "series": RotationSeries(angles, r)}
        for name, part in parts.items():
            out.append((f"{name} {r}", Motion(dim, (part,))))
        for name, rot in rots.items():
            out.append((f"rotation {name} {r}", Motion(dim, (), rot, centre, axis)))
        out.append((f"all {r}", Motion(dim, tuple(parts.values()), rots["sine"], centre, axis)))
    return out


CASES = [(dim, name, m) for dim in (2, 3) for name, m in _motions(dim)]


@pytest.mark.parametrize("dim,name,motion", CASES, ids=[f"{d}d {n}" for d, n, _ in CASES])
def test_wall_velocity_and_acceleration_are_the_derivatives_of_its_position(dim, name, motion):
    rng = np.random.default_rng(3)
    X = rng.normal(0, 0.5, (6, dim))  # reference points of the wall
    h = 1e-4
    for t in (0.05, 0.35, 0.5, 0.79, 1.3, 2.2):  # before, inside and after the ramp
        p0, pm, pp = motion.pose(t), motion.pose(t - h), motion.pose(t + h)
        x = p0.to_world(X)
        v_fd = (pp.to_world(X) - pm.to_world(X)) / (2 * h)
        a_fd = (pp.to_world(X) - 2 * x + pm.to_world(X)) / (h * h)
        scale_v = max(1.0, np.abs(v_fd).max())
        np.testing.assert_allclose(p0.point_velocity(x), v_fd, rtol=0, atol=2e-6 * scale_v)
        np.testing.assert_allclose(p0.point_acceleration(x), a_fd, rtol=0, atol=2e-3 * max(1.0, np.abs(a_fd).max()))


@given(st.integers(2, 3), st.floats(-3, 3), st.floats(-5, 5))
@settings(max_examples=60)
def test_to_body_inverts_to_world(dim, theta, shift):
    axis = _unit([1.0, 2.0, -0.5])
    R = rotation_matrix(dim, axis, theta)
    np.testing.assert_allclose(R @ R.T, np.eye(dim), atol=1e-14)
    assert np.linalg.det(R) == pytest.approx(1.0, abs=1e-14)
    z = np.zeros(3)
    pose = Pose(R, np.full(dim, 0.3), np.full(dim, shift), np.zeros(dim), np.zeros(dim), z, z)
    X = np.random.default_rng(0).normal(0, 2.0, (20, dim))
    np.testing.assert_allclose(pose.to_body(pose.to_world(X)), X, atol=1e-12 * (1 + abs(shift)))


def test_a_spline_passes_through_its_samples_and_reproduces_a_line():
    t = np.array([0.0, 0.1, 0.35, 0.4, 1.0, 1.7])
    y = np.sin(3 * t)
    s = Spline(t, y)
    for k in range(t.size):
        assert s(t[k])[0][0] == pytest.approx(y[k], abs=1e-14)
    line = Spline(t, 2.0 - 0.5 * t)  # a natural spline reproduces a straight line exactly
    for tt in np.linspace(0, 1.7, 23):
        v, d, dd = line(tt)
        assert v[0] == pytest.approx(2.0 - 0.5 * tt, abs=1e-14)
        assert d[0] == pytest.approx(-0.5, abs=1e-13) and dd[0] == pytest.approx(0.0, abs=1e-12)


def test_a_spline_converges_at_fourth_order_on_a_smooth_record():
    """The SPHERIC roll record is sampled at 20 kHz: the spline is exact to round-off there;
    on coarse samples its error falls as h^4 (interior), as a cubic spline's must."""
    errs = []
    for n in (21, 41, 81):
        t = np.linspace(0.0, 2.0, n)
        s = Spline(t, np.sin(2 * t))
        tt = np.linspace(0.5, 1.5, 101)  # away from the natural ends
        errs.append(max(abs(s(x)[0][0] - math.sin(2 * x)) for x in tt))
    assert errs[0] / errs[1] > 12 and errs[1] / errs[2] > 12, errs


def test_the_ramp_is_smooth_and_its_integral_is_right():
    r = Ramp(0.5, 2.0)
    assert r.value(0.4) == (0.0, 0.0, 0.0) and r.value(2.6) == (1.0, 0.0, 0.0)
    for t in (0.5, 2.5):  # value, slope and curvature continuous at both ends
        lo, hi = r.value(t - 1e-9), r.value(t + 1e-9)
        assert np.allclose(lo, hi, atol=1e-7)
    tt = np.linspace(0.0, 4.0, 40001)
    vals = np.array([r.value(x)[0] for x in tt])
    trap = np.concatenate([[0.0], np.cumsum(0.5 * (vals[1:] + vals[:-1]) * np.diff(tt))])
    for k in (0, 10000, 15000, 25000, 40000):
        assert r.integral(tt[k]) == pytest.approx(trap[k], abs=1e-8)
    step = Ramp(1.0, 0.0)
    assert step.value(0.99)[0] == 0.0 and step.value(1.0)[0] == 1.0 and step.integral(3.0) == 2.0


def test_a_constant_velocity_reaches_its_speed_without_overshoot():
    m = Motion(2, (ConstantVelocity(np.array([0.3, 0.0]), Ramp(0.0, 1.0)),))
    speeds = [m.pose(t).velocity[0] for t in np.linspace(0, 2, 201)]
    assert max(speeds) == pytest.approx(0.3) and np.all(np.diff(speeds) >= -1e-15)
    assert m.pose(2.0).shift[0] == pytest.approx(0.3 * (2.0 - 0.5))
