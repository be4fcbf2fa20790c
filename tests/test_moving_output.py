"""What a run with moving walls writes: each moving group's pose in particles.nc at every
frame, the walls where they are beside every VTU frame, and a restart from the middle of a
rolling-tank run that continues bit for bit."""

from __future__ import annotations

import math

import random

import netCDF4
import numpy as np
import pytest
import pyvista as pv
from test_run_lifecycle import checkpoint_by_id
from test_run_survival import kill_and_restart

from sphcore.run import runner
from sphcore.testing import case_with, tiny_case, write_case

ROLL = {"type": "sine_rotation", "centre": [0.5, 0.0], "amplitude": 6.0, "frequency": 2.0, "ramp": 0.02}
PADDLE = {"shape": "box", "min": [0.7, 0.0], "max": [0.75, 0.3],
          "motion": [{"type": "sine_translation", "axis": [1.0, 0.0], "amplitude": 0.05, "frequency": 3.0}]}


def _case(tmp_path, name, changes=None):
    return write_case(tmp_path / name, case_with(tiny_case(), {
        "blocks[0].max": [0.6, 0.15], "time.t_end": 0.08, "plugins.use": ["reflective", "vtu", "netcdf"],
        "vtu.every_dt": 0.02, "netcdf.every_dt": 0.02, "domain.motion": [ROLL], "domain.walls": [PADDLE],
        **(changes or {})}))


def test_poses_and_walls_are_written_at_every_frame(tmp_path):
    out = tmp_path / "out"
    result = runner.run(_case(tmp_path, "case"), output=out, quiet=True)
    assert result["status"] == "completed", result["message"]
    case = result.simulation.case
    with netCDF4.Dataset(out / "particles.nc") as ds:
        assert ds.wall_groups == "domain.motion; domain.walls[0].motion"
        times = ds["time"][:]
        assert len(times) == 5
        for k, t in enumerate(times):
            for g, group in enumerate(case.moving):
                pose = group.motion.pose(float(t))
                assert np.array_equal(ds["wall_shift"][k, g], pose.shift)
                assert np.array_equal(ds["wall_rotation"][k, g], pose.rotation)
                assert np.array_equal(ds["wall_velocity"][k, g], pose.velocity)
        assert ds["wall_shift"].units == "m" and ds["wall_angular_velocity"].units == "rad s-1"
    frames = pv.read(out / "case_walls.pvd")
    assert frames.n_blocks == 1  # the collection reads (ParaView steps through it)
    for k, t in enumerate(times):
        walls = pv.read(out / "vtu" / f"case_walls_{k:06d}.vtu")
        assert walls.n_cells == 4 + 4  # the paddle's box and the tank's outline
        # the paddle's faces where its motion puts them (the first four cells)
        x = 0.7 + 0.05 * math.sin(2 * math.pi * 3.0 * float(t))
        assert abs(walls.points[:8, 0].min() - x) < 1e-12
        # the tank's corner at the floor's right end, rolled about (0.5, 0)
        theta = case.moving[0].motion.pose(float(t))
        corner = theta.to_world(np.array([1.0, 0.0]))
        assert np.abs(walls.points[8:, :2] - corner).sum(axis=1).min() < 1e-12


@pytest.mark.slow
def test_sigkill_in_the_middle_of_a_moving_run_then_restart_is_bit_for_bit(tmp_path):
    """The rolling tank with its swinging paddle, killed (SIGKILL) at random moments and
    restarted: the particles, the frames and the walls' poses are those of the run that
    was never stopped (a prescribed motion is a function of time: the checkpoint's clock
    is all it needs)."""
    case_dir = _case(tmp_path, "case", {"time.t_end": 0.3, "output.checkpoint_every_dt": 0.02})
    ref = tmp_path / "ref"
    whole = runner.run(case_dir, output=ref, quiet=True)
    assert whole["status"] == "completed"
    out = tmp_path / "out"
    hit = kill_and_restart(case_dir, out, kills=2, rng=random.Random(37), stepping_s=whole["wall_time_s"])
    assert hit >= 1
    (meta, final), (ref_meta, want) = checkpoint_by_id(out), checkpoint_by_id(ref)
    assert meta["t"] == ref_meta["t"] and meta["step"] == ref_meta["step"]
    for key in ("id", "pos", "vel", "rho", "p"):
        assert np.array_equal(final[key], want[key]), key
    with netCDF4.Dataset(ref / "particles.nc") as x, netCDF4.Dataset(out / "particles.nc") as y:
        for name in ("time", "step", "wall_shift", "wall_rotation", "wall_velocity", "position", "velocity"):
            assert np.array_equal(x[name][:], y[name][:]), name


@pytest.mark.slow
@pytest.mark.parametrize("use", [["reflective", "wall_integral"], ["ghost", "reflective"]])
def test_a_wall_model_or_ghost_run_with_moving_planes_restarts_bit_for_bit(tmp_path, use):
    """The rolling tank with a piston plane of its own, with the wall model or ghosts and the
    walls' loads written, killed (SIGKILL) at random moments and restarted: the particles
    and the loads are those of the run that was never stopped (the loads of the evaluation
    a step starts from are kept in the checkpoint)."""
    piston = {"normal": [-1.0, 0.0], "point": [0.75, 0.0],
              "motion": [{"type": "sine_translation", "axis": [1.0, 0.0], "amplitude": 0.05, "frequency": 3.0}]}
    case_dir = _case(tmp_path, "case", {"time.t_end": 0.3, "output.checkpoint_every_dt": 0.02,
                                        "domain.walls": None, "domain.planes": [piston],
                                        "plugins.use": [*use, "wall_loads", "netcdf"], "wall_loads.every_dt": 0.01})
    ref = tmp_path / "ref"
    whole = runner.run(case_dir, output=ref, quiet=True)
    assert whole["status"] == "completed"
    out = tmp_path / "out"
    hit = kill_and_restart(case_dir, out, kills=2, rng=random.Random(41), stepping_s=whole["wall_time_s"])
    assert hit >= 1
    (meta, final), (ref_meta, want) = checkpoint_by_id(out), checkpoint_by_id(ref)
    assert meta["t"] == ref_meta["t"] and meta["step"] == ref_meta["step"]
    for key in ("id", "pos", "vel", "rho", "p"):
        assert np.array_equal(final[key], want[key]), key
    with netCDF4.Dataset(ref / "wall_loads.nc") as x, netCDF4.Dataset(out / "wall_loads.nc") as y:
        assert len(x["time"][:]) == 31  # t = 0, then every 0.01 s
        for name in x.variables:  # the first row has no interval: NaN in both
            assert np.array_equal(np.asarray(x[name][:]), np.asarray(y[name][:]), equal_nan=True), name


def test_the_loads_on_a_carried_tank_balance_the_momentum_of_its_water(tmp_path):
    """Water released in a tank carried at 0.5 m/s, reflective walls: the only forces on
    the water are gravity and the walls', so the wall loads integrated over the run
    (wall_loads rows times their intervals) equal M g T minus the water's change of
    momentum, in both directions, to round-off; and once settled the mean vertical load
    is about the weight (the column still rings: within 5 %)."""
    out = tmp_path / "out"
    U = np.array([0.5, 0.0])
    case_dir = write_case(tmp_path / "carried", case_with(tiny_case(), {
        "blocks[0].min": [0.3, 0.0], "blocks[0].max": [0.7, 0.2], "blocks[0].velocity": U.tolist(),
        "time.t_end": 0.2, "plugins.use": ["reflective", "wall_loads"], "wall_loads.every_dt": 0.01,
        "domain.motion": [{"type": "constant_velocity", "velocity": U.tolist()}]}))
    result = runner.run(case_dir, output=out, quiet=True)
    assert result["status"] == "completed", result["message"]
    st = result.simulation.state
    mass = float(st.m.sum())
    g = np.array([0.0, -9.81])
    from sphcore_plugins.wall_loads import read_loads

    t, loads = read_loads(out / "wall_loads.nc")
    assert t[0] == 0.0 and t[-1] == pytest.approx(0.2, abs=1e-12)
    integral = (loads[1:, 0, :2] * np.diff(t)[:, None]).sum(axis=0)
    change = (st.m[:, None] * st.vel).sum(axis=0) - mass * U
    expected = mass * g * t[-1] - change
    np.testing.assert_allclose(integral, expected, rtol=0, atol=1e-9 * mass * 9.81 * t[-1])
    late = t > 0.1
    assert loads[late, 0, 1].mean() == pytest.approx(-mass * 9.81, rel=0.05)
    s = result["wall_loads"]["domain.motion"]
    assert s["max_force"] >= 0.95 * mass * 9.81
    text = (out / "wall_loads.csv").read_text().splitlines()
    assert text[1].startswith("t,domain.motion.Fx") and len(text) == 2 + len(t)


def test_a_dfsph_run_s_loads_on_a_rolling_tank_and_its_paddle_continue_bit_for_bit_after_a_restart(tmp_path):
    """The rolling tank with its swinging paddle (two groups: the tank's planes and the
    paddle's faces, so each takes its share of the solves' wall kicks), dfsph with the wall
    model and a fixed step, stopped after 27 steps and restarted from its checkpoint: the
    particles and every row of wall_loads.nc that the stop did not cut are those of the run
    that went through, bit for bit (the groups' parts of the wall gradient are taken again
    at the restart's first listing, at the same positions), and the row it cut in two (the
    stopped run writes its last row at step 27) holds the same impulse over the same time."""
    dt = 2.0 ** -10
    case_dir = _case(tmp_path, "case", {"scheme.name": "dfsph", "time.dt": dt, "time.t_end": 40 * dt,
                                        "blocks[0].max": [0.7, 0.15],  # the water against the paddle
                                        "plugins.use": ["reflective", "wall_integral", "wall_loads"],
                                        "wall_loads.every_steps": 4, "neighbours.sort_every": 9})
    full = runner.run(case_dir, output=tmp_path / "full", quiet=True)
    assert full["status"] == "completed", full["message"]
    runner.run(case_dir, output=tmp_path / "part", t_end=27 * dt, quiet=True)
    rest = runner.run(case_dir, output=tmp_path / "part", t_end=40 * dt, restart=True, quiet=True)
    assert rest["status"] == "completed", rest["message"]
    assert full.simulation.step == rest.simulation.step == 40
    (_, final), (_, want) = checkpoint_by_id(tmp_path / "part"), checkpoint_by_id(tmp_path / "full")
    for key in ("id", "pos", "vel", "rho", "p"):
        assert np.array_equal(final[key], want[key]), key
    with netCDF4.Dataset(tmp_path / "full" / "wall_loads.nc") as x, \
            netCDF4.Dataset(tmp_path / "part" / "wall_loads.nc") as y:
        steps, rows = np.asarray(x["step"][:]), np.asarray(y["step"][:])
        assert steps.tolist() == list(range(0, 41, 4))  # step 0, then every 4 steps
        assert rows.tolist() == [0, 4, 8, 12, 16, 20, 24, 27, 28, 32, 36, 40]  # the stopped run's last row, at 27
        loads = {v: (np.asarray(x[v][:]), np.asarray(y[v][:])) for v in ("force", "moment")}
        assert np.all(np.abs(loads["force"][0][1:, :, :2]) > 0.0)  # both groups loaded, along both axes
        same = [k for k, s in enumerate(rows) if s != 27 and s != 28]
        for name in x.variables:  # the rows the stop did not cut: bit for bit (the first is NaN in both)
            assert np.array_equal(np.asarray(x[name][:])[[steps.tolist().index(rows[k]) for k in same]],
                                  np.asarray(y[name][:])[same], equal_nan=True), name
        # the row the stop cut in two: the same impulse over the same time
        t, u = np.asarray(x["time"][:]), np.asarray(y["time"][:])
        for a, b in loads.values():
            whole = a[7] * (t[7] - t[6])
            cut = b[7] * (u[7] - u[6]) + b[8] * (u[8] - u[7])
            np.testing.assert_allclose(cut, whole, rtol=1e-12, atol=1e-12 * np.abs(whole).max())
