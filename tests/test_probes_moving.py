"""Probes on walls that move: a sensor with ``attach`` rides with its wall group (points,
segment, normal and depth direction carried by the group's pose at every sample), a
wall-mode sensor on it reads with the apparent gravity g - a_w, depth gauges read the
planes where they are, a carried tank reads as the fixed one (Galilean), and a bad attach
is refused naming the key. With nothing attached and no plane moving the samples are
those of fixed walls, bit for bit."""

from __future__ import annotations

import math

import netCDF4
import numpy as np
import pytest

from sphcore import cli
from sphcore.errors import CaseError
from sphcore.run import runner
from sphcore.testing import case_with, context, tiny_case, write_case
from sphcore_plugins.probes import ProbesPlugin

G = 9.81
PADDLE = {"shape": "box", "min": [0.6, 0.0], "max": [0.7, 0.3]}
A, PERIOD = 0.02, 0.5  # m, s: the paddle's and the swaying tank's stroke
SWAY = {"type": "sine_translation", "axis": [1.0, 0.0], "amplitude": A, "period": PERIOD}
ROLL_DEG, ROLL_CENTRE = 10.0, np.array([0.5, 0.0])
ROLL = {"type": "sine_rotation", "centre": ROLL_CENTRE.tolist(), "amplitude": ROLL_DEG, "period": 1.0}


def _plugin(changes):
    """A configured and set-up probes plugin on the tiny case (a 0.2 m block of water in a
    1 m tank, dx = 0.02 m) with ``changes``, and its context (no run)."""
    ctx = context(case_with(tiny_case(), {"plugins.use": ["probes"], **changes}))
    plugin = ProbesPlugin()
    plugin.sph_configure(ctx.case)
    plugin.sph_setup(ctx)
    return plugin, ctx


def _rotation(theta):
    c, s = math.cos(theta), math.sin(theta)
    return np.array([[c, -s], [s, c]])


# ---------------------------------------------------------------------------- where the sensors are


def test_a_sensor_on_a_sine_translating_paddle_follows_it():
    """A line sensor on the paddle's left face, attached to it: at every t its points,
    segment and normal are those of case.toml carried by A sin(omega t) along x, and its
    apparent gravity is g - D'' (D'' = -A omega^2 sin(omega t) x). A fixed sensor drawn
    at the same place stays there."""
    sensor = {"start": [0.6, 0.02], "end": [0.6, 0.08], "points": 3}
    plugin, ctx = _plugin({"domain.walls": [{**PADDLE, "motion": [SWAY]}],
                           "probes.pressure": [{"name": "on", **sensor, "attach": "walls[0]"},
                                               {"name": "off", **sensor}]})
    on, off = plugin.probes
    assert (on.attach, on.group, off.group) == ("walls[0]", "domain.walls[0].motion", None)
    ref = np.array([[0.6, 0.03], [0.6, 0.05], [0.6, 0.07]])
    np.testing.assert_array_equal(on.points, ref)
    omega = 2 * math.pi / PERIOD
    for t in (0.0, 0.05, 0.13, 0.3, 0.41, 0.5 + 1 / 3):
        q_on, q_off = plugin.place(t, ctx.planes_at(t))
        shift = np.array([A * math.sin(omega * t), 0.0])
        np.testing.assert_allclose(q_on.points, ref + shift, rtol=0, atol=1e-15)
        np.testing.assert_allclose([q_on.a, q_on.b], [[0.6 + shift[0], 0.02], [0.6 + shift[0], 0.08]], atol=1e-15)
        np.testing.assert_array_equal(q_on.face_n, [-1.0, 0.0])
        acc = np.array([-A * omega ** 2 * math.sin(omega * t), 0.0])
        np.testing.assert_allclose(q_on.gravity, np.tile([0.0, -G] - acc, (3, 1)), rtol=0, atol=1e-12)
        assert q_off.points is off.points and q_off.gravity is None  # the fixed one keeps its arrays
        np.testing.assert_array_equal([q_off.a, q_off.b], [[0.6, 0.02], [0.6, 0.08]])


def test_sensors_and_a_gauge_on_a_rolling_tank_turn_with_it():
    """A tank rolled theta = 10 deg sin(2 pi t) about (0.5, 0): a sensor on its right wall
    attached as "tank", the same sensor named through a wall that moves with the tank
    ("walls[0]", tank = true), and a depth gauge on its floor: points c + R (X - c), normal
    R (-1, 0), apparent gravity g - (alpha x r - Omega^2 r), the gauge along R (0, 1) up to
    the tank's top 1 m away (its planes where they are at t)."""
    sensor = {"start": [1.0, 0.02], "end": [1.0, 0.1], "points": 3}
    plugin, ctx = _plugin({"domain.motion": [ROLL], "domain.walls": [{**PADDLE, "tank": True}],
                           "probes.pressure": [{"name": "tank", **sensor, "attach": "tank"},
                                               {"name": "wall", **sensor, "attach": "walls[0]"}],
                           "probes.depth": [{"name": "d", "point": [0.3, 0.0], "attach": "tank"},
                                            {"name": "d_fixed", "point": [0.3, 0.0]}]})
    assert [p.group for p in plugin.probes] == ["domain.motion"] * 3 + [None]
    ref = np.column_stack([np.ones(3), 0.02 + (np.arange(3) + 0.5) / 3 * 0.08])
    w = 2 * math.pi
    amp = math.radians(ROLL_DEG)
    for t in (0.0, 0.1, 0.37, 0.62, 0.9):
        theta, dtheta, ddtheta = amp * math.sin(w * t), amp * w * math.cos(w * t), -amp * w * w * math.sin(w * t)
        R = _rotation(theta)
        q_tank, q_wall, q_d, q_fixed = plugin.place(t, ctx.planes_at(t))
        x = ROLL_CENTRE + (ref - ROLL_CENTRE) @ R.T
        r = x - ROLL_CENTRE
        a_w = ddtheta * np.column_stack([-r[:, 1], r[:, 0]]) - dtheta ** 2 * r
        for q in (q_tank, q_wall):
            np.testing.assert_allclose(q.points, x, rtol=0, atol=1e-15)
            np.testing.assert_allclose(q.face_n, R @ [-1.0, 0.0], rtol=0, atol=1e-15)
            np.testing.assert_allclose(q.gravity, np.array([0.0, -G]) - a_w, rtol=0, atol=1e-12)
        x0 = ROLL_CENTRE + R @ (np.array([0.3, 0.0]) - ROLL_CENTRE)
        up = R @ [0.0, 1.0]
        np.testing.assert_allclose(q_d.points[0], x0, atol=1e-15)
        np.testing.assert_allclose(q_d.up, up, atol=1e-15)
        np.testing.assert_allclose(q_d.b, x0 + 1.0 * up, atol=1e-12)
        # the fixed gauge: along -g from where it is drawn, up to the tilted lid
        np.testing.assert_array_equal(q_fixed.up, [0.0, 1.0])
        lid_n, lid_x = R @ [0.0, -1.0], ROLL_CENTRE + R @ (np.array([0.3, 1.0]) - ROLL_CENTRE)
        np.testing.assert_allclose(q_fixed.b[1], lid_n @ (lid_x - [0.3, 0.0]) / lid_n[1], rtol=1e-12)
        np.testing.assert_allclose(q_fixed.normals, ctx.planes_at(t).normals, atol=0)


# ---------------------------------------------------------------------------- what they read


def test_an_attached_sensor_reads_the_apparent_hydrostatic_field_exactly():
    """Water at rest in a swaying tank at the instant of its largest acceleration a = -A
    omega^2 x (3.16 m/s^2): relative to the tank the water is hydrostatic in g - a,
    p_j = rho0 (g - a).(x_j - x_s), x_s a point of its surface. A wall-mode sensor attached
    to the tank's left wall reads rho0 (g - a).(x - x_s) to round-off; carried with plain g
    it would be rho0 a_x 0.1 m = 316 Pa off."""
    plugin, ctx = _plugin({"domain.motion": [SWAY], "blocks[0].max": [0.4, 0.2],
                           "probes.pressure": [{"name": "P", "point": [0.0, 0.05], "attach": "tank"}]})
    t = PERIOD / 4
    pose = ctx.case.moving[0].motion.pose(t)
    a = pose.acceleration
    assert a[0] == pytest.approx(-A * (2 * math.pi / PERIOD) ** 2) and a[1] == 0.0
    st, rho0 = ctx.state, float(ctx.params.rho0)
    st.pos[:] = pose.to_world(st.pos)
    st.rho[:] = rho0
    g_app = np.array([0.0, -G]) - a
    top = pose.to_world(np.array([0.1, 0.2]))
    st.p[:] = rho0 * (st.pos - top) @ g_app
    ctx.t = t
    values, dry = plugin.sample(st, t, ctx.planes)
    x = pose.to_world(np.array([0.0, 0.05]))
    exact = rho0 * g_app @ (x - top)
    assert dry[0] == 0 and exact == pytest.approx(rho0 * (G * 0.15 + a[0] * 0.1))
    assert values[0] == pytest.approx(exact, rel=1e-12)
    assert abs(exact - rho0 * np.array([0.0, -G]) @ (x - top)) > 300.0


def test_an_attached_depth_gauge_reads_the_height_of_the_water_in_a_rolled_tank():
    """The 0.2 m block of water carried with a tank rolled by 10 deg sin(2 pi t) (at t = 0.2:
    9.5 deg): a gauge attached to the floor reads 0.2 m within half a spacing (the known
    answer of the fixed tank, test_probes_sampling), scanning along the tank's up with the
    floor's mirror images taken from the planes where they are."""
    plugin, ctx = _plugin({"domain.motion": [ROLL], "probes.depth": [{"name": "d", "point": [0.1, 0.0],
                                                                      "attach": "tank"}]})
    t = 0.2
    pose = ctx.case.moving[0].motion.pose(t)
    ctx.state.pos[:] = pose.to_world(ctx.state.pos)
    ctx.t = t
    values, dry = plugin.sample(ctx.state, t, ctx.planes)
    assert dry[0] == 0 and abs(values[0] - 0.2) < 0.01, values[0]


def test_the_moving_path_with_nothing_moving_gives_the_fixed_samples_bit_for_bit():
    """The per-sample placement (taken where probes or planes move) on a fixed case: the
    same numbers, to the bit, as the set-up arrays of fixed walls."""
    plugin, ctx = _plugin({"probes.pressure": [{"name": "a", "start": [0.0, 0.01], "end": [0.0, 0.1], "points": 4},
                                               {"name": "b", "point": [0.1, 0.05], "mode": "particle"}],
                           "probes.depth": [{"name": "d", "point": [0.1, 0.0]}]})
    assert not plugin.moves
    st = ctx.state
    st.p[:] = st.rho * G * (0.2 - st.pos[:, 1])  # the column at rest
    fixed = plugin.sample(st)
    plugin.moves = True
    moving = plugin.sample(st, 0.0, ctx.planes)
    assert fixed[0][0] > 1000 and fixed[0][1] > 1000 and fixed[0][2] > 0.15
    np.testing.assert_array_equal(fixed[0], moving[0])
    np.testing.assert_array_equal(fixed[1], moving[1])


# ---------------------------------------------------------------------------- a run


def _run(tmp_path, name, changes):
    """Water at rest 0.1 m deep filling a 0.3 m tank (dx = 0.01 m), 50 steps of 2e-4 s, probes
    every step: the pressure sensor on the right wall 0.02-0.04 m up and a depth gauge."""
    base = {"domain.max": [0.3, 0.3], "blocks[0].max": [0.3, 0.1], "particles.dx": 0.01, "time.t_end": 0.01,
            "time.dt": 2e-4, "plugins.use": ["reflective", "probes"], "physics.hydrostatic_init": True}
    case_dir = write_case(tmp_path / name, case_with(tiny_case(), {**base, **changes}))
    result = runner.run(case_dir, output=tmp_path / name / "out", quiet=True)
    assert result["status"] == "completed", result["message"]
    data = np.loadtxt(tmp_path / name / "out" / "probes.csv", delimiter=",", skiprows=1)
    return result, data, tmp_path / name / "out" / "probes.nc"


def _probes(attach=None):
    extra = {} if attach is None else {"attach": attach}
    return {"probes.pressure": [{"name": "P", "start": [0.3, 0.02], "end": [0.3, 0.04], "points": 3, **extra}],
            "probes.depth": [{"name": "d", "point": [0.15, 0.0], **extra}]}


def test_a_tank_carried_at_constant_velocity_reads_as_the_fixed_tank(tmp_path):
    """Galilean invariance: the tank and its water carried at U = (0.8, 0) m/s (8 mm over
    the run, nearly a particle spacing) with the sensor and gauge attached to it read the
    fixed tank's series. The particles of the two runs differ by U t to 1e-8 m
    (test_reflective_moving), so a reading may differ by about rho g 1e-8 m = 1e-4 Pa
    (measured: 4e-6 Pa) and a depth by 1e-8 m (measured: 0). The fixed tank itself reads
    the hydrostatic rho g (0.1 - 0.03) = 687 Pa to within 20 % (the column's first acoustic
    settling lifts it by up to 16 % in these 10 ms) and the depth 0.1 m within 5 mm."""
    U = [0.8, 0.0]
    fixed, f, f_nc = _run(tmp_path, "fixed", _probes())
    moving, m, m_nc = _run(tmp_path, "moving", {**_probes("tank"), "blocks[0].velocity": U,
                                                "domain.motion": [{"type": "constant_velocity", "velocity": U}]})
    assert fixed["steps"] == moving["steps"] == 50 and f.shape == m.shape == (51, 3)
    np.testing.assert_array_equal(f[:, 0], m[:, 0])
    dp, dd = np.abs(m[:, 1] - f[:, 1]).max(), np.abs(m[:, 2] - f[:, 2]).max()
    print(f"max |dp| {dp:.3g} Pa, max |d depth| {dd:.3g} m, p {f[:, 1].min():.1f}..{f[:, 1].max():.1f} Pa")
    assert dp < 1e-4 and dd < 1e-8
    assert np.abs(f[:, 1] / (1000.0 * G * 0.07) - 1).max() < 0.2
    assert np.abs(f[:, 2] - 0.1).max() < 0.005
    with netCDF4.Dataset(m_nc) as ds:
        assert netCDF4.chartostring(ds["probe_attach"][:]).tolist() == ["tank", "tank"]
    with netCDF4.Dataset(f_nc) as ds:
        assert "probe_attach" not in ds.variables


def test_in_a_run_a_sensor_on_a_swinging_paddle_samples_where_the_paddle_is(tmp_path, monkeypatch):
    """A paddle (x 0.2 to 0.25 m) swung A sin(omega t) along x beside 0.1 m of water, with a
    line sensor attached to its wet face: at every sample of the run the points the plugin
    reads are those of case.toml shifted by A sin(omega t), t the sample's time, and the
    sensor is wet all along."""
    used = []
    place = ProbesPlugin.place

    def recording(self, t, planes):
        placed = place(self, t, planes)
        used.append((t, placed[0].points.copy()))
        return placed

    monkeypatch.setattr(ProbesPlugin, "place", recording)
    _, data, nc = _run(tmp_path, "paddle", {"blocks[0].max": [0.2, 0.1],
                                           "domain.walls": [{"shape": "box", "min": [0.2, 0.0], "max": [0.25, 0.2],
                                                             "motion": [SWAY]}],
                                           "probes.pressure": [{"name": "P", "start": [0.2, 0.02], "end": [0.2, 0.04],
                                                                "points": 3, "attach": "walls[0]"}],
                                           "probes.depth": []})
    times = np.array([t for t, _ in used])
    np.testing.assert_allclose(times, data[:, 0], rtol=0, atol=1e-12)  # one placement per sample (csv: 10 digits)
    ref = np.array([[0.2, 0.02 + 0.02 * (k + 0.5) / 3] for k in range(3)])
    for t, points in used:
        np.testing.assert_allclose(points, ref + [A * math.sin(2 * math.pi * t / PERIOD), 0.0], rtol=0, atol=1e-15)
    assert len(used) == 51 and used[-1][1][0, 0] - 0.2 > 0.002  # it moved a quarter of a spacing
    with netCDF4.Dataset(nc) as ds:
        assert not np.asarray(ds["dry"][:]).any()


# ---------------------------------------------------------------------------- refused


GOOD_WALL = {**PADDLE, "motion": [SWAY]}
#: (changes, the key named, words of the message)
BAD = {
    "tank that does not move": ({"probes.pressure": [{"name": "a", "point": [0.0, 0.05], "attach": "tank"}]},
                                "probes.pressure[0].attach", "no wall moves in this case"),
    "tank without motion, a wall moving": ({"domain.walls": [GOOD_WALL],
                                            "probes.pressure": [{"name": "a", "point": [0.0, 0.05],
                                                                 "attach": "tank"}]},
                                           "probes.pressure[0].attach", "'walls[0]'"),
    "unknown name": ({"domain.motion": [SWAY], "probes.pressure": [{"name": "a", "point": [0.0, 0.05],
                                                                    "attach": "paddle"}]},
                     "probes.pressure[0].attach", 'expected "tank" or "walls[k]"'),
    "wall out of range": ({"domain.walls": [GOOD_WALL], "probes.depth": [{"name": "a", "point": [0.1, 0.0],
                                                                          "attach": "walls[1]"}]},
                          "probes.depth[0].attach", "k < 1"),
    "fixed wall": ({"domain.motion": [SWAY], "domain.walls": [PADDLE],
                    "probes.pressure": [{"name": "a", "point": [0.6, 0.05], "attach": "walls[0]"}]},
                   "probes.pressure[0].attach", "has no motion"),
    "tank wall, tank fixed": ({"domain.walls": [{**PADDLE, "tank": True}, GOOD_WALL],
                               "probes.pressure": [{"name": "a", "point": [0.6, 0.05], "attach": "walls[0]"}]},
                              "probes.pressure[0].attach", "moves with the tank"),
    "not a string": ({"domain.motion": [SWAY], "probes.pressure": [{"name": "a", "point": [0.0, 0.05],
                                                                    "attach": 0}]},
                     "probes.pressure[0].attach", "a string"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_a_bad_attach_is_refused_naming_the_key(tmp_path, name):
    changes, key, words = BAD[name]
    case_dir = write_case(tmp_path / "case", case_with(tiny_case(), {"plugins.use": ["probes"], **changes}))
    with pytest.raises(CaseError) as err:
        runner.load(case_dir)
    assert err.value.key == key, str(err.value)
    assert words in str(err.value), str(err.value)


def test_a_bad_attach_exits_2_and_writes_nothing(tmp_path, capsys):
    case_dir = write_case(tmp_path / "case", case_with(tiny_case(), {
        "plugins.use": ["reflective", "probes"], "domain.motion": [SWAY],
        "probes.pressure": [{"name": "a", "point": [0.0, 0.05], "attach": "walls[0]"}]}))
    out = tmp_path / "out"
    assert cli.main(["run", str(case_dir), "--output", str(out)]) == 2
    err = capsys.readouterr().err
    assert "case.toml" in err and "probes.pressure[0].attach" in err and "walls[0]" in err
    assert not out.exists()
