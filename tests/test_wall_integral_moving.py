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

from test_ghost_moving import DX, L, accelerating_tank

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


@pytest.mark.slow
def test_water_in_an_accelerating_tank_tilts_to_the_slope_a_over_g(tmp_path):
    """A 0.3 m tank with 0.1 m of water (dx = 0.01 m) accelerates along +x, its acceleration
    rising over 1.5 s to a = g / 2 (tests/test_ghost_moving.py's tank, with the wall model).
    Over the next 0.8 s (more than a slosh period, 0.65 s) the water stands at rest in the
    tank: the surface falls towards the front at the slope a/g = 0.5 and the pressure rises
    along the tilted normal at rho |g - a|; the load on the tank over the window (the wall
    model's, from the fluid's momentum balance, and the reflective contacts') is the force
    that accelerates the water and holds it up, -M (a - g).

    Measured (2 cores, 40 s for both runs): surface slope -0.510, pressure-gradient slope
    -0.501, |G| 10943 Pa/m against rho |g - a| = 10968 (-0.2 %); load (-147.55, -295.03) N/m
    against (-147.51, -295.03). The same tank at rest: surface slope 0.0012 (0.3 mm over the
    tank, from the start's small asymmetries). Tolerances: the surface to dx / 0.26 m (a
    column's top is known to a particle spacing), the gradient's direction to 5 % of a/g and
    its magnitude to 2 %, the load to 0.5 %; the tank at rest level to 2 % of the tilt. The
    wall pressure's own estimate of the load (phi = 1, the exact first moment: what a piston
    among fixed walls takes) reads (-142.2, -293.2) here."""
    a, ramp, t_end, window = 9.81 / 2, 1.5, 2.3, 0.8
    (surface, slope_p, grad), n, load, mass = accelerating_tank(tmp_path, "accelerating", a, ramp, t_end, window,
                                                                PLUGINS)
    (surface0, slope0, _), _, _, _ = accelerating_tank(tmp_path, "rest", 0.0, ramp, t_end, window, PLUGINS)
    assert n >= 30
    assert abs(surface0) < 0.02 * a / 9.81 and abs(slope0) < 0.02 * a / 9.81  # the tank at rest stays level
    assert surface == pytest.approx(-a / 9.81, abs=DX / (L - 4 * DX))
    assert slope_p == pytest.approx(-a / 9.81, abs=0.05 * a / 9.81)
    assert grad == pytest.approx(1000.0 * math.hypot(9.81, a), rel=0.02)
    # the fluid pushes the tank: -M (a - g) = (-M a, -M g) per metre of width
    assert load[0] == pytest.approx(-mass * a, rel=0.005)
    assert load[1] == pytest.approx(-mass * 9.81, rel=0.005)
