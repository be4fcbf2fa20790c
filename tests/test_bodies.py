"""Floating bodies in runs: the fluid and a body exchange momentum and nothing else, a body
holds its place under its buoyancy, and a checkpoint carries the body."""

from __future__ import annotations

import json

import numpy as np
import pytest

from sphcore.testing import run_case

THROWN = """
[case]
name = "thrown"
dim = 2
[domain]
min = [0.0, 0.0]
max = [1.0, 1.0]
[[domain.walls]]
shape = "box"
min = [0.2, 0.45]
max = [0.3, 0.55]
[[bodies]]
wall = 0
density = 1000.0
velocity = [1.0, 0.1]
angular_velocity = [2.0]
[[blocks]]
min = [0.35, 0.3]
max = [0.65, 0.7]
[particles]
dx = 0.02
[physics]
gravity = [0.0, 0.0, 0.0]
[eos]
c0 = 20.0
[kernel]
h_over_dx = 2.0
[viscosity]
alpha = 0.02
[time]
t_end = 0.15
[plugins]
use = PLUGINS
"""


def _momentum(out):
    ck = np.load(out / "checkpoint.npz", allow_pickle=True)
    fluid = (ck["state_m"][:, None] * ck["state_vel"]).sum(axis=0)
    body = json.loads(str(ck["meta"]))["kept"]["bodies"]["bodies[0]"]
    return fluid, 1000.0 * 0.1 * 0.1 * np.asarray(body["v"]), np.asarray(body["x"])


@pytest.mark.parametrize("plugins", ['["reflective"]', '["reflective", "wall_integral"]'])
def test_a_body_thrown_into_free_water_keeps_the_momentum_of_both(tmp_path, plugins):
    """Zero gravity, no fixed wall reached: what the body loses the water gains, with the
    reflective contacts' impulses and with the wall model's pressure (its exact reaction)."""
    run_case(tmp_path, THROWN.replace("PLUGINS", plugins[:-1] + ', "wall_loads"]') + "[wall_loads]\nevery_dt = 0.01\n")
    fluid, body, x = _momentum(tmp_path / "output")
    assert x[0] > 0.27  # it reached the water
    assert np.linalg.norm(fluid) > 1.0  # and gave it a good part of its 10 N s/m
    np.testing.assert_allclose(fluid + body, [10.0, 1.0], rtol=0, atol=1e-9)
    # the loads file reports what the body took: its mean forces times their intervals add
    # up to the body's change of momentum (from 10, 1 N s/m)
    rows = np.loadtxt(tmp_path / "output" / "wall_loads.csv", delimiter=",", skiprows=2, ndmin=2)
    impulse = (rows[1:, 1:3] * np.diff(rows[:, 0])[:, None]).sum(axis=0)
    assert rows[-1, 0] == pytest.approx(0.15)
    np.testing.assert_allclose(impulse, body - [10.0, 1.0], rtol=0, atol=1e-9)


HEAVING = """
[case]
name = "heaving"
dim = 2
[domain]
min = [0.0, 0.0]
max = [0.6, 0.4]
[[domain.walls]]
shape = "box"
min = [0.2, 0.16]
max = [0.4, 0.26]
[[bodies]]
wall = 0
density = 500.0
velocity = [0.0, 0.05]
angular_velocity = [0.3]
[[blocks]]
min = [0.0, 0.0]
max = [0.6, 0.2]
[particles]
dx = 0.02
[kernel]
h_over_dx = 2.0
[viscosity]
alpha = 0.05
[time]
t_end = 3.0
[plugins]
use = ["reflective", "wall_integral", "vtu"]
[vtu]
every_dt = 0.01
"""


def test_a_run_with_a_body_stopped_and_restarted_ends_bit_for_bit(tmp_path):
    """SIGINT once frames are on disk, --restart to the end: every array of the final
    checkpoint and the body's state equal those of the run that was not stopped."""
    import signal
    import subprocess
    import sys
    import time

    case = tmp_path / "case"
    case.mkdir()
    (case / "case.toml").write_text(HEAVING)
    sph = [sys.executable, "-m", "sphcore.cli", "run", str(case), "--progress", "off"]
    whole = subprocess.run(sph + ["--output", str(tmp_path / "whole")], capture_output=True, text=True)
    assert whole.returncode == 0, whole.stderr
    out = tmp_path / "stopped"
    proc = subprocess.Popen(sph + ["--output", str(out)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        while len(list(out.glob("vtu/*.vtu"))) < 5:  # frames on disk: the run is well under way
            assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
            time.sleep(0.01)
        proc.send_signal(signal.SIGINT)
        proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 130
    again = subprocess.run(sph + ["--output", str(out), "--restart"], capture_output=True, text=True)
    assert again.returncode == 0, again.stderr
    a, b = (np.load(d / "checkpoint.npz", allow_pickle=True) for d in (tmp_path / "whole", out))
    for key in a.files:
        if key != "meta":
            assert np.array_equal(a[key], b[key]), key
    kept = [json.loads(str(c["meta"]))["kept"]["bodies"] for c in (a, b)]
    assert kept[0] == kept[1]


HELD_FINE = """
[case]
name = "held_fine"
dim = 2
[domain]
min = [0.0, 0.0]
max = [0.6, 0.3]
[[domain.walls]]
shape = "box"
min = [0.25, 0.125]
max = [0.35, 0.175]
[[bodies]]
wall = 0
density = 500.0
release = 10.0
[[blocks]]
min = [0.0, 0.0]
max = [0.6, 0.15]
[particles]
dx = 0.002
[kernel]
h_over_dx = 2.0
[time]
t_end = 1.0
[plugins]
use = ["reflective", "wall_integral"]
"""


@pytest.mark.slow
def test_a_held_body_takes_its_buoyancy_in_a_run_of_many_particles(tmp_path):
    """Above sphcore.jit.parallel.PARALLEL_MIN particles the wall completion runs in a
    parallel loop: the reaction it records there still carries the body's load. A box held
    at a draft d = 0.025 m takes rho g B d = 24.5 N/m from the water at rest, to within
    dx/d = 8 % (its draft is known to one particle spacing): the mean over t = 0.014-0.105
    s (steps 200-1500), about two periods of the acoustic oscillation the start leaves
    (the load swings 22-29 N/m)."""
    from sphcore.jit.parallel import PARALLEL_MIN
    from sphcore.run import runner
    from sphcore.run.build import build

    case = tmp_path / "case"
    case.mkdir()
    (case / "case.toml").write_text(HELD_FINE)
    config, pm = runner.load(case)
    sim = build(config, pm, None)
    assert sim.state.n >= PARALLEL_MIN
    loads = []
    for step in range(1500):
        sim.advance()
        if step >= 200:
            loads.append(sim.ctx.wall_forces["bodies[0]"][0])
    fx, fy = np.mean(loads, axis=0)
    expected = 1000.0 * 9.81 * 0.1 * 0.025
    assert abs(fy - expected) < 0.002 / 0.025 * expected, fy
    assert abs(fx) < 1e-3 * expected  # the box and the water are symmetric about x = 0.3


@pytest.mark.parametrize("dim, orientation", [(2, [30.0]), (2, [-90.0]), (3, [0.0, 0.0, 90.0]), (3, [20.0, 10.0, 0.0])])
def test_an_oriented_body_is_drawn_turned_about_its_centre_of_mass(dim, orientation):
    """``orientation`` turns the wall about its centre of mass before the fluid is built: the
    mass and centre do not change, every vertex keeps its distance from the centre, the
    angle turned is the one given, and no particle starts inside the turned body."""
    from sphcore.testing import context

    lo, hi = ([0.4, 0.4], [0.7, 0.5]) if dim == 2 else ([0.4, 0.4, 0.4], [0.7, 0.5, 0.55])
    top = [1.0] * dim
    case = (f"[case]\nname = \"turned\"\ndim = {dim}\n[domain]\nmin = {[0.0] * dim}\nmax = {top}\n"
            f"[[domain.walls]]\nshape = \"box\"\nmin = {lo}\nmax = {hi}\n"
            f"[[bodies]]\nwall = 0\ndensity = 500.0\nORIENT\n"
            f"[[blocks]]\nmin = {[0.0] * dim}\nmax = {top}\n[particles]\ndx = 0.02\n[time]\nt_end = 0.1\n"
            "[plugins]\nuse = [\"reflective\"]\n")
    drawn = context(case.replace("ORIENT", ""))
    turned = context(case.replace("ORIENT", f"orientation = {orientation}"))
    a, b = (c.case.moving[0].motion.body for c in (drawn, turned))
    assert a.mass == pytest.approx(b.mass, rel=1e-12)
    np.testing.assert_allclose(a.x, b.x, atol=1e-12)
    va, vb = drawn.case.faces.verts.reshape(-1, dim), turned.case.faces.verts.reshape(-1, dim)
    np.testing.assert_allclose(np.linalg.norm(va - a.x, axis=1), np.linalg.norm(vb - b.x, axis=1), atol=1e-12)
    # about the axis (z in 2D) each vertex's arm keeps its part along the axis and turns its
    # part across it by the angle given, counter-clockwise seen from the axis' tip
    rv = np.radians(np.r_[0.0, 0.0, orientation] if dim == 2 else np.asarray(orientation))
    k = rv / np.linalg.norm(rv)
    arms = [np.c_[v - c.x, np.zeros((len(v), 3 - dim))] for v, c in ((va, a), (vb, b))]
    np.testing.assert_allclose(arms[0] @ k, arms[1] @ k, atol=1e-12)
    across = [arm - np.outer(arm @ k, k) for arm in arms]
    sin = np.cross(across[0], across[1]) @ k
    cos = (across[0] * across[1]).sum(axis=1)
    np.testing.assert_allclose(np.arctan2(sin, cos), np.linalg.norm(rv), atol=1e-12)
    assert turned.case.faces.in_fluid(turned.state.pos).all()
    assert not drawn.case.faces.in_fluid(turned.state.pos).all() or np.allclose(va, vb)


def test_an_orientation_of_the_wrong_length_is_refused():
    from sphcore.errors import CaseError
    from sphcore.testing import context

    with pytest.raises(CaseError, match=r"bodies\[0\]\.orientation"):
        context(HEAVING.replace("velocity = [0.0, 0.05]", "orientation = [0.0, 5.0]"))


def test_each_body_knows_the_fixed_walls_and_the_other_bodies_it_must_not_enter():
    """Two bodies, a fixed obstacle and a wall with a prescribed motion: each body's solids
    are the obstacle's faces alone (not the bodies', not the moving wall's, which is not
    where it is drawn), its others the other body."""
    from sphcore.testing import context

    walls = "".join(f"[[domain.walls]]\nshape = \"box\"\nmin = {lo}\nmax = {hi}\n"
                    for lo, hi in (([0.1, 0.6], [0.2, 0.7]), ([0.4, 0.6], [0.5, 0.7]), ([0.7, 0.05], [0.9, 0.1]),
                                   ([0.7, 0.6], [0.8, 0.7])))
    case = ("[case]\nname = \"two\"\ndim = 2\n[domain]\nmin = [0.0, 0.0]\nmax = [1.0, 1.0]\n" + walls
            + "[[domain.walls.motion]]\ntype = \"sine_translation\"\naxis = [1.0, 0.0]\namplitude = 0.01\n"
            "period = 1.0\n[[bodies]]\nwall = 0\ndensity = 500.0\n[[bodies]]\nwall = 1\ndensity = 800.0\n"
            "[[blocks]]\nmin = [0.0, 0.0]\nmax = [1.0, 0.3]\n[particles]\ndx = 0.02\n[time]\nt_end = 0.1\n"
            "[plugins]\nuse = [\"reflective\"]\n")
    ctx = context(case)
    bodies = [g.motion for g in ctx.case.moving if g.name.startswith("bodies")]
    assert len(bodies) == 2
    obstacle = ctx.case.faces.verts[8:12]
    for k, m in enumerate(bodies):
        np.testing.assert_array_equal(np.sort(m.solids.verts.reshape(-1, 2), axis=0),
                                      np.sort(obstacle.reshape(-1, 2), axis=0))
        assert m.others == [bodies[1 - k]]


@pytest.mark.parametrize("case", ["floating_box", "heave_decay", "heeled_box", "floating_box_3d"])
def test_the_shipped_body_cases_pass_check(case):
    """``sph check`` of every shipped case with a body exits 0 and says ok."""
    import subprocess
    import sys
    from pathlib import Path

    root = Path(__file__).resolve().parents[1]
    res = subprocess.run([sys.executable, "-m", "sphcore.cli", "check", str(root / "cases" / case)],
                         capture_output=True, text=True)
    assert res.returncode == 0 and ": ok: " in res.stdout, res.stderr


DROPPED = """
[case]
name = "dropped"
dim = 2
[domain]
min = [0.0, 0.0]
max = [1.0, 0.8]
[[domain.walls]]
shape = "box"
min = [0.45, 0.55]
max = [0.55, 0.65]
[[bodies]]
wall = 0
density = 700.0
angular_velocity = [4.0]
[[blocks]]
min = [0.0, 0.0]
max = [1.0, 0.3]
[particles]
dx = 0.01
[kernel]
h_over_dx = 2.0
[viscosity]
alpha = 0.05
[time]
t_end = 0.6
[plugins]
use = PLUGINS
"""


@pytest.mark.parametrize("plugins", ['["reflective"]', '["reflective", "wall_integral"]'])
def test_no_particle_enters_a_body_dropped_into_the_water(tmp_path, plugins):
    """A spinning box dropped 0.25 m hits the water at 2.2 m/s (its corners faster) and
    throws a splash (jets of about twice that): after every step each particle is at least
    its radius from the box's faces and inside the tank, and none is lost."""
    from sphcore.run import runner
    from sphcore.run.build import build

    case = tmp_path / "case"
    case.mkdir()
    (case / "case.toml").write_text(DROPPED.replace("PLUGINS", plugins))
    config, pm = runner.load(case)
    sim = build(config, pm, None)
    motion = next(g.motion for g in sim.ctx.case.moving if g.name.startswith("bodies"))
    lo, hi = np.array([0.45, 0.55]), np.array([0.55, 0.65])
    n, radius = sim.state.n, float(sim.state.radius.min())
    body_speed = fluid_speed = 0.0
    closest, steps = np.inf, 0
    while sim.t < 0.6:
        sim.advance()
        steps += 1
        st = sim.state
        assert st.n == n and np.isfinite(st.pos).all()
        pose = motion.pose(sim.t)
        b = pose.to_body(st.pos)  # the box's own frame, where it is [lo, hi]
        closest = min(closest, float(np.linalg.norm(np.maximum(np.maximum(lo - b, b - hi), 0.0), axis=1).min()))
        assert closest >= radius * (1 - 1e-9), (sim.t, closest, radius)
        assert st.pos.min() >= radius * (1 - 1e-9) and (np.array([1.0, 0.8]) - st.pos).min() >= radius * (1 - 1e-9)
        corners = pose.to_world(np.array([[0.45, 0.55], [0.55, 0.55], [0.55, 0.65], [0.45, 0.65]]))
        body_speed = max(body_speed, float(np.linalg.norm(pose.point_velocity(corners), axis=1).max()))
        fluid_speed = max(fluid_speed, float(np.linalg.norm(st.vel, axis=1).max()))
    assert body_speed > 2.0 and fluid_speed > 2.0, (body_speed, fluid_speed)
    assert motion.pose(sim.t).shift[1] < -0.2  # it went into the water
    print(f"{plugins}: {steps} steps, closest {closest / radius:.3f} radii, body {body_speed:.2f} m/s, "
          f"fluid {fluid_speed:.2f} m/s")
