"""Boundary-integral walls that move (plugins/wall_integral/moving.py): the tank's planes and
a group's faces where they are, continuity with the velocity relative to the walls, the wall
pressure extrapolated with g - a_w, and the wall pressure's load on each moving group.

Known answers: a tank carried at constant velocity is the fixed tank seen from a moving
frame (Galilean invariance), for planes and for faces; water in a tank accelerating at a
tilts to the slope a/g; the load on a tank holding water at rest is the water's weight."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sphcore.run import runner
from sphcore.testing import case_with, tiny_case, write_case
from sphcore_plugins.wall_integral import WallIntegralPlugin

PLUGINS = ["reflective", "wall_integral"]


def _run(tmp_path, name, changes):
    base = {"blocks[0].max": [0.3, 0.2], "time.t_end": 0.01, "time.dt": 2e-4, "plugins.use": PLUGINS,
            "physics.hydrostatic_init": True}
    case_dir = write_case(tmp_path / name, case_with(tiny_case(), {**base, **changes}))
    result = runner.run(case_dir, output=tmp_path / name / "out", quiet=True)
    assert result["status"] == "completed", result["message"]
    st = result.simulation.state
    order = np.argsort(st.id)
    return result, st.pos[order], st.vel[order], st.p[order], st.rho[order]


def test_the_plugin_honours_moving_walls():
    assert WallIntegralPlugin().sph_moving_walls() is True


#: a box of faces holding the water (the domain's planes far away), for the faces' path
FACE_TANK = {"domain.min": [-1.0, -1.0], "domain.max": [2.0, 2.0],
             "domain.walls": [{"shape": "box", "min": [0.0, 0.0], "max": [1.0, 1.0], "fluid": "inside"}]}


#: a wall plane of its own at x = 0.33, within the kernel support of the water, beside the box's four: moving, it is a group apart
WALL = {"normal": [-1.0, 0.0], "point": [0.33, 0.0]}


@pytest.mark.parametrize("walls", ["planes", "faces", "groups"])
def test_a_tank_carried_at_constant_velocity_is_the_fixed_tank_seen_from_a_moving_frame(tmp_path, walls):
    """Water released in a tank, and the same tank and water carried at U = (0.8, 0) m/s:
    50 steps of 2e-4 s give positions differing by U t, velocities by U and densities equal,
    to round-off, whether the tank is the domain's planes, a box of faces taken into its
    own frame, or two groups of planes (the box and a plane of its own at x = 0.33, each
    group's wall velocity on its part of G_w). Measured: planes 7e-12 m, 3e-9 m/s, 1.4e-10 in density; faces 6e-11 m,
    1.8e-7 m/s, 3.7e-9 (round-off at the box's corners, where the nearest face changes,
    grows through the contacts; the water moves at up to 0.18 m/s). Without the walls'
    velocity in continuity (2 rho v_i . G_w instead of 2 rho (v_i - v_w) . G_w) the carried
    water next to the front and back walls compresses and expands: its density departs by
    12% and its velocity by 2.2 m/s in these 50 steps."""
    U, t_end = np.array([0.8, 0.0]), 0.01
    motion = [{"type": "constant_velocity", "velocity": U.tolist()}]
    if walls == "planes":
        fixed_changes, moving_changes = {}, {"domain.motion": motion}
    elif walls == "groups":  # the tank and a plane of its own, both carried: two groups of planes
        fixed_changes = {"domain.planes": [WALL]}
        moving_changes = {"domain.planes": [{**WALL, "motion": motion}], "domain.motion": motion}
    else:
        tank = dict(FACE_TANK["domain.walls"][0])
        fixed_changes = dict(FACE_TANK)
        moving_changes = {**FACE_TANK, "domain.walls": [{**tank, "motion": motion}]}
    fixed, x_f, v_f, p_f, r_f = _run(tmp_path, "fixed", fixed_changes)
    moving, x_m, v_m, p_m, r_m = _run(tmp_path, "moving", {**moving_changes, "blocks[0].velocity": U.tolist()})
    assert fixed["steps"] == moving["steps"] == round(t_end / 2e-4)
    assert fixed["wall_integral"]["near_wall_last"] == moving["wall_integral"]["near_wall_last"] > 20
    assert np.abs(v_f).max() > 0.01  # the water moves
    np.testing.assert_allclose(x_m - U * t_end, x_f, rtol=0, atol=1e-9)
    np.testing.assert_allclose(v_m - U, v_f, rtol=0, atol=1e-5)
    np.testing.assert_allclose(r_m, r_f, rtol=1e-7, atol=0)


#: the accelerating tank: 0.3 m long, 0.1 m of water at dx = 0.01 m (30 x 10 particles)
L, H, DX = 0.3, 0.1, 0.01


def _accelerating_tank(tmp_path, name, a, ramp, t_end, window):
    """Water in the tank accelerating along x at ``a`` (m/s^2) after a quintic ramp of the
    acceleration over ``ramp`` s; the last ``window`` s sampled every 0.025 s in the tank's
    frame: the means of (surface slope, -G_x / G_y, |G|) with G the least-squares pressure
    gradient of the particles 3 h below their column's top and 2 dx off the side walls,
    and the last sample's load on the tank (the wall pressure's force, N/m)."""
    from sphcore.run.build import build

    changes = {"domain.max": [L, 0.3], "blocks[0].max": [L, H], "particles.dx": DX, "time.t_end": t_end,
               "plugins.use": PLUGINS, "physics.hydrostatic_init": True,
               "domain.motion": [{"type": "translation_file", "file": "motion.txt", "axis": [1.0, 0.0]}]}
    case_dir = write_case(tmp_path / name, case_with(tiny_case(), changes))
    # x = a Q(t), Q'' the quintic smooth step from 0 to 1 over the ramp (beyond t_end: a
    # natural spline's ends bend its acceleration to zero)
    t = np.arange(0.0, t_end + 0.05, 1e-3)
    tau = np.clip(t / ramp, 0.0, 1.0)
    q = np.where(t <= ramp, ramp ** 2 * (0.5 * tau ** 5 - 0.5 * tau ** 6 + tau ** 7 / 7),
                 ramp ** 2 / 7 + 0.5 * ramp * (t - ramp) + 0.5 * (t - ramp) ** 2)
    np.savetxt(case_dir / "motion.txt", np.c_[t, a * q], header="t (s)  x (m)")
    case, pm = runner.load(case_dir)
    sim = build(case, pm, None)
    h = sim.params.h
    columns = round(L / DX)
    samples, next_t = [], t_end - window
    while not sim.done():
        sim.advance()
        if sim.t < next_t - 1e-12:
            continue
        next_t += 0.025
        st = sim.state
        x = st.pos - case.moving[0].motion.pose(sim.t).shift  # the tank's frame
        col = np.clip(np.floor(x[:, 0] / DX).astype(int), 0, columns - 1)
        top = np.full(columns, -np.inf)
        np.maximum.at(top, col, x[:, 1])
        centres = (np.arange(columns) + 0.5) * DX
        surface = np.polyfit(centres[2:-2], top[2:-2], 1)[0]
        deep = (top[col] - x[:, 1] > 3 * h) & (x[:, 0] > 2 * DX) & (x[:, 0] < L - 2 * DX)
        coef = np.linalg.lstsq(np.c_[np.ones(deep.sum()), x[deep]], st.p[deep], rcond=None)[0]
        samples.append((surface, -coef[1] / coef[2], math.hypot(coef[1], coef[2])))
    load = np.array(sim.ctx.kept(pm.get_plugin("wall_integral"))["loads"][case.moving[0].name][:2])
    return np.mean(samples, axis=0), len(samples), load, float(sim.state.m.sum())


@pytest.mark.slow
def test_water_in_an_accelerating_tank_tilts_to_the_slope_a_over_g(tmp_path):
    """A 0.3 m tank with 0.1 m of water (dx = 0.01 m) accelerates along +x, its acceleration
    rising over 1.5 s to a = g / 2. Over the next 0.8 s (more than a slosh period, 0.65 s)
    the water stands at rest in the tank: the surface falls towards the front at the slope
    a/g = 0.5 and the pressure rises along the tilted normal at rho |g - a|; the wall
    model's load on the tank is the force that accelerates the water and holds it up,
    -M (a - g) on the tank.

    Measured (2 cores, 40 s for both runs): surface slope -0.510, pressure-gradient slope
    -0.501, |G| 10943 Pa/m against rho |g - a| = 10968 (-0.2%); load (-142.2, -293.2) N/m
    against (-147.5, -295.0) (-3.6%, -0.6%; the load takes the exact first moment and phi = 1
    where the completion takes the discrete complement and the neighbourhood scaling, and
    particles resting on the reflective contacts put the rest on the walls). The same tank
    at rest: surface slope 0.0012 (0.3 mm over the tank, from the start's small
    asymmetries), load -284.3 N/m against -M g = -295.0 (-3.6%). Tolerances: the surface to
    dx / 0.26 m (a column's top is known to a particle spacing), the gradient's direction to
    5% of a/g and its magnitude to 2%, the load to 6% of M |g - a|; the tank at rest level to
    2% of the tilt measured. Without the walls' acceleration in the wall pressure (g instead
    of g - a_w) the load's x component falls to -136.8 N/m (-7.2%)."""
    a, ramp, t_end, window = 9.81 / 2, 1.5, 2.3, 0.8
    (surface, slope_p, grad), n, load, mass = _accelerating_tank(tmp_path, "accelerating", a, ramp, t_end, window)
    (surface0, slope0, _), _, load0, _ = _accelerating_tank(tmp_path, "rest", 0.0, ramp, t_end, window)
    assert n >= 30
    assert abs(surface0) < 0.02 * a / 9.81 and abs(slope0) < 0.02 * a / 9.81  # the tank at rest stays level
    assert surface == pytest.approx(-a / 9.81, abs=DX / (L - 4 * DX))
    assert slope_p == pytest.approx(-a / 9.81, abs=0.05 * a / 9.81)
    assert grad == pytest.approx(1000.0 * math.hypot(9.81, a), rel=0.02)
    # the fluid pushes the tank: -M (a - g) = (-M a, -M g) per metre of width
    weight, total = mass * 9.81, mass * math.hypot(9.81, a)
    assert load0[0] == pytest.approx(0.0, abs=0.01 * weight)
    assert load0[1] == pytest.approx(-weight, abs=0.06 * weight)
    assert load[0] == pytest.approx(-mass * a, abs=0.06 * total)
    assert load[1] == pytest.approx(-weight, abs=0.06 * total)
