"""Reflective walls that move (plugins/reflective/moving.py): a piston gives a particle at
rest (1 + CR) times its speed; a tank carried at constant velocity is the fixed tank seen
from a moving frame; and no particle ever ends a step outside a moving tank or on the wrong
side of a moving obstacle, whatever the motion, CR, time step and wall speed (up to many
times the particles')."""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sphcore.geometry.faces import box, closed_wall
from sphcore.geometry.motion import ConstantVelocity, Motion, SineRotation, SineTranslation
from sphcore.geometry.planes import Planes
from sphcore_plugins.reflective.collision import Response, Tally
from sphcore_plugins.reflective.corner import scratch
from sphcore_plugins.reflective.moving import Group, reflect_moving

R = 0.005  # particle radius (m)


def _reflect(groups, t, dt, pos0, pos, vel, acc=None, cr=1.0):
    n = pos.shape[0]
    for g in groups:
        g.build_grid(R)
    tally = Tally(np.zeros(n, np.int8), np.zeros(n, np.int32))
    acc = np.zeros_like(pos) if acc is None else acc
    return reflect_moving(groups, t, dt, pos0, pos, vel, acc, np.full(n, R), Response(cr, 1000, True), tally,
                          scratch())


def _no_planes(dim):
    return np.zeros((0, dim)), np.zeros(0)


@pytest.mark.parametrize("cr", [0.0, 0.5, 1.0])
def test_a_piston_gives_a_particle_at_rest_one_plus_cr_times_its_speed(cr):
    """An elastic wall of infinite mass at speed V sends a particle at rest off at 2 V;
    with CR the relative normal velocity -V becomes +CR V: (1 + CR) V."""
    V, dt = 2.0, 1e-3
    piston = Group("piston", *_no_planes(2), closed_wall(box(np.array([-0.1, 0.0]), np.array([0.0, 1.0])), False),
                   Motion(2, (ConstantVelocity(np.array([V, 0.0])),)))
    x = 0.0 + R + 0.5 * V * dt  # the piston's face reaches it half-way through the step
    pos0 = np.array([[x, 0.5]])
    pos, vel = pos0.copy(), np.zeros((1, 2))
    guarded, hit, events, pinched = _reflect([piston], 0.0, dt, pos0, pos, vel, cr=cr)
    assert (guarded, hit, events, pinched) == (0, 1, 1, 0)
    np.testing.assert_allclose(vel[0], [(1.0 + cr) * V, 0.0], rtol=1e-12, atol=1e-12)
    face = V * dt  # where the face is at the end of the step
    # relative path: from x to x - V dt; mirrored about the contact distance R with CR
    expected = face + R + cr * (R - (x - V * dt))
    assert pos[0, 0] == pytest.approx(expected, abs=1e-12)
    assert pos[0, 0] - face >= R * (1 - 1e-9)


def test_a_particle_the_wall_does_not_reach_keeps_its_bits():
    V, dt = 2.0, 1e-3
    piston = Group("piston", *_no_planes(2), closed_wall(box(np.array([-0.1, 0.0]), np.array([0.0, 1.0])), False),
                   Motion(2, (ConstantVelocity(np.array([V, 0.0])),)))
    pos0 = np.array([[0.3, 0.5], [0.2, 0.1]])
    pos = pos0 + np.array([[0.001, 0.0], [0.0, 0.002]])
    vel = np.array([[1.0, 0.0], [0.0, 2.0]])
    before = (pos.copy(), vel.copy())
    assert _reflect([piston], 0.0, dt, pos0, pos, vel)[:3] == (0, 0, 0)
    assert np.array_equal(pos, before[0]) and np.array_equal(vel, before[1])


def _tank_planes(dim, size=1.0):
    lo, hi = np.zeros(dim), np.full(dim, size)
    normals = np.concatenate([np.eye(dim), -np.eye(dim)])
    points = np.concatenate([np.tile(lo, (dim, 1)), np.tile(hi, (dim, 1))])
    p = Planes.from_lists(normals, points)
    return np.ascontiguousarray(p.normals), np.ascontiguousarray(p.offsets)


def _inside_planes(group, t, pos):
    b = group.to_body(pos, t)
    return (b @ group.normals.T - group.offsets).min(axis=1)


@given(dim=st.sampled_from([2, 3]), seed=st.integers(0, 2**32 - 1), cr=st.floats(0.0, 1.0),
       speed_ratio=st.floats(0.1, 10.0), dt=st.floats(1e-5, 4e-3), t=st.floats(0.0, 3.0))
@settings(max_examples=150, deadline=None)  # the first example compiles the kernels
def test_no_particle_ends_a_step_outside_a_rolling_swaying_tank(dim, seed, cr, speed_ratio, dt, t):
    """A 1 m tank rolling +-20 deg about its floor's centre and swaying +-0.2 m; particles
    start inside where the tank is at t, move freely by up to a CFL-limited step, with
    speeds 1/speed_ratio of the wall's: every one ends inside where the tank is at t + dt."""
    rng = np.random.default_rng(seed)
    omega = 2 * math.pi / 1.0
    axis = np.array([0.0, 0.0, 1.0]) if dim == 3 else None
    centre = np.array([0.5, 0.0, 0.5][:dim])
    motion = Motion(dim, (SineTranslation(np.eye(dim)[0], 0.2, omega, 0.0),),
                    SineRotation(math.radians(20.0), omega * 1.3, 0.0), centre, axis)
    tank = Group("tank", *_tank_planes(dim), None, motion)
    wall_speed = 0.2 * omega + math.radians(20) * omega * 1.3 * 1.2  # |V| + |Omega| reach
    n = 400
    body = rng.uniform(R, 1.0 - R, (n, dim))  # inside the tank's own frame at t
    pos0 = motion.pose(t).to_world(body)
    vel = rng.normal(0, wall_speed / speed_ratio, (n, dim))
    acc = rng.normal(0, 20.0, (n, dim))
    pos = pos0 + dt * vel + 0.5 * dt * dt * acc
    vel = vel + dt * acc
    guarded, hit, events, pinched = _reflect([tank], t, dt, pos0, pos, vel, acc, cr)
    assert pinched == 0
    clear = _inside_planes(tank, t + dt, pos)
    assert clear.min() >= R * (1 - 1e-9) - 1e-15, (clear.min(), R)


@given(seed=st.integers(0, 2**32 - 1), cr=st.floats(0.0, 1.0), dt=st.floats(1e-5, 2e-3), t=st.floats(0.0, 2.0))
@settings(max_examples=100, deadline=None)
def test_no_particle_ends_in_a_moving_paddle_or_outside_the_fixed_tank(seed, cr, dt, t):
    """A paddle (a closed box of faces, through the floor) swings +-0.3 m at up to 1.9 m/s
    inside a fixed tank of planes; particles start in the water (outside the paddle, inside the tank) and
    end there: the two groups are swept in turn."""
    rng = np.random.default_rng(seed)
    dim = 2
    paddle_motion = Motion(dim, (SineTranslation(np.array([1.0, 0.0]), 0.3, 2 * math.pi, 0.0),))
    paddle = Group("paddle", *_no_planes(dim), closed_wall(box(np.array([0.4, -0.1]), np.array([0.5, 0.6])), False),
                   paddle_motion)
    tank = Group("tank", *_tank_planes(dim), None, None)
    groups = [tank, paddle]
    for g in groups:
        g.build_grid(R)
    n = 600
    pos0 = rng.uniform(R, 1.0 - R, (n, dim))
    keep = paddle.faces.distances(paddle.to_body(pos0, t)) >= R * 1.001
    keep &= paddle.faces.in_fluid(paddle.to_body(pos0, t))
    pos0 = pos0[keep]
    n = pos0.shape[0]
    vel = rng.normal(0, 0.5, (n, dim))
    pos = pos0 + dt * vel
    guarded, hit, events, pinched = _reflect(groups, t, dt, pos0, pos, vel, cr=cr)
    b = paddle.to_body(pos, t + dt)
    assert paddle.faces.in_fluid(b).all()
    gap = paddle.faces.distances(b)
    tank_clear = _inside_planes(tank, t + dt, pos)
    # the paddle never comes closer than 0.1 m to a side: no particle can be pinched
    assert pinched == 0 and guarded == 0
    assert gap.min() >= R * (1 - 1e-9) - 1e-15
    assert tank_clear.min() >= R * (1 - 1e-9) - 1e-15


def _run(tmp_path, name, changes):
    from sphcore.run import runner
    from sphcore.testing import case_with, tiny_case, write_case

    base = {"blocks[0].max": [0.3, 0.2], "time.t_end": 0.06, "time.dt": 2e-4, "plugins.use": ["reflective"],
            "physics.hydrostatic_init": True}
    case_dir = write_case(tmp_path / name, case_with(tiny_case(), {**base, **changes}))
    result = runner.run(case_dir, output=tmp_path / name / "out", quiet=True)
    assert result["status"] == "completed", result["message"]
    st = result.simulation.state
    order = np.argsort(st.id)
    return result, st.pos[order], st.vel[order]


def test_a_tank_carried_at_constant_velocity_is_the_fixed_tank_seen_from_a_moving_frame(tmp_path):
    """Water released in a tank, and the same tank and water carried at U = (0.8, 0) m/s
    (Galilean invariance: SPH sees only differences of positions and velocities, the walls
    only the relative path and velocity): same steps, positions differing by U t and
    velocities by U to round-off, over 50 steps with 427 reflections. (Later the splash
    amplifies round-off: the fixed tank shifted by 0.5 m differs from itself by 6e-6 m at
    0.02 s and 1.4e-4 m at 0.06 s, as much as the carried tank does.)"""
    U, t_end = np.array([0.8, 0.0]), 0.01
    fixed, x_f, v_f = _run(tmp_path, "fixed", {"time.t_end": t_end})
    moving, x_m, v_m = _run(tmp_path, "moving", {"time.t_end": t_end,
                                                  "domain.motion": [{"type": "constant_velocity",
                                                                     "velocity": U.tolist()}],
                                                  "blocks[0].velocity": U.tolist()})
    assert fixed["steps"] == moving["steps"] == round(t_end / 2e-4)
    events = fixed["reflective"]["reflection_events"]
    assert events > 100 and moving["reflective"]["reflection_events"] == events  # the walls act all along
    np.testing.assert_allclose(x_m - U * t_end, x_f, rtol=0, atol=1e-8)
    np.testing.assert_allclose(v_m - U, v_f, rtol=0, atol=1e-5)


def test_water_in_a_rolling_tank_never_leaves_it(tmp_path):
    """A tank rolled +-10 deg at 1.5 Hz about its floor's centre and swayed: zero particles
    outside at the end of every step (the core's check after each step would stop the run),
    no guard return, the reflective walls acting every step."""
    result, x, _ = _run(tmp_path, "roll", {"time.t_end": 0.4, "time.dt": None, "blocks[0].max": [1.0, 0.15],
                                           "domain.motion": [
                                               {"type": "sine_rotation", "centre": [0.5, 0.0], "amplitude": 10.0,
                                                "frequency": 1.5, "ramp": 0.1},
                                               {"type": "sine_translation", "axis": [1.0, 0.0], "amplitude": 0.05,
                                                "frequency": 1.5}]})
    assert result["status"] == "completed"
    assert result["reflective"]["guard_returns"] == 0 and result["reflective"]["pinched"] == 0
    sim = result.simulation
    planes = sim.ctx.planes_at(sim.t)
    radius = sim.state.radius.min()
    assert (x @ planes.normals.T - planes.offsets).min() >= radius * (1 - 1e-9)
