"""VTU writer: the .pvd opens in pyvista with every frame's time and fields, exactly."""

import os
import subprocess
import sys
import textwrap
from types import SimpleNamespace

import numpy as np
import pytest
import pyvista as pv

from sphcore.errors import CaseError, OutputError
from sphcore.physics.particles import FLUID, SPHERE, lattice, make_block
from sphcore_plugins.vtu import VtuWriter

CASE_NAME = "dam break"  # a space: the file name must be sanitised
PVD = "dam_break.pvd"


def make_sim(tmp_path, dim=2, every_dt=None, every_steps=None, seed=0, compress=True):
    """A stand-in for the core's Simulation: random fields, particles in a shuffled order."""
    rng = np.random.default_rng(seed)
    st = make_block(lattice(np.zeros(dim), np.ones(dim), 0.25), np.zeros(dim), 1000.0, 0.25, 0.1, FLUID)
    st.kind[::3] = SPHERE
    st.m = rng.uniform(0.5, 1.5, st.n)
    st.radius = rng.uniform(0.05, 0.1, st.n)
    case = SimpleNamespace(name=CASE_NAME, dim=dim, file=str(tmp_path / "case.toml"),
                           config={"vtu": {"every_dt": every_dt, "every_steps": every_steps, "compress": compress}})
    out = tmp_path / "output"
    out.mkdir()
    sim = SimpleNamespace(state=st, t=0.0, step=0, dt=0.004, case=case, output_dir=out, stats={}, restarting=False)
    sim.host = lambda: sim.state  # a writer reads the particles through host()
    advance(sim, rng, dt=0.0)  # random fields and order at step 0 too
    return sim, rng


def advance(sim, rng, dt=None):
    """One fake step: new values everywhere, then a reorder as the core's cell sort does."""
    st = sim.state
    st.pos = st.pos + 0.01 * rng.normal(size=st.pos.shape)
    st.vel = rng.normal(size=st.vel.shape)
    st.rho = 1000.0 + rng.normal(size=st.n)
    st.p = 1e3 * rng.normal(size=st.n)
    st.permute(rng.permutation(st.n))
    if dt is None:
        dt = sim.dt
    if dt:
        sim.t += dt
        sim.step += 1


def by_id(st):
    """The frame a writer should store: every field sorted by id, 2D padded to 3D."""
    o = np.argsort(st.id)
    pad = lambda a: np.hstack([a[o], np.zeros((st.n, 3 - st.dim))])  # noqa: E731
    return {"points": pad(st.pos), "velocity": pad(st.vel), "pressure": st.p[o], "density": st.rho[o],
            "mass": st.m[o], "radius": st.radius[o], "kind": st.kind[o], "id": st.id[o]}


def run(sim, rng, writer, steps):
    """Steps 0..steps with output after each, then the final call; expected frames by time."""
    expected = {}
    for i in range(steps + 1):
        if i:
            advance(sim, rng)
        before = len(writer.frames)
        writer.sph_output(ctx=sim, final=False)
        if len(writer.frames) > before:
            expected[sim.t] = by_id(sim.state)
    before = len(writer.frames)
    writer.sph_output(ctx=sim, final=True)
    if len(writer.frames) > before:
        expected[sim.t] = by_id(sim.state)
    writer.sph_finish(ctx=sim)
    return expected


def configured(sim):
    w = VtuWriter()
    w.sph_configure(case=sim.case)
    w.sph_setup(ctx=sim)
    return w


def read_all(pvd):
    reader = pv.get_reader(str(pvd))
    frames = {}
    for i, t in enumerate(reader.time_values):
        reader.set_active_time_point(i)
        frames[t] = reader.read()[0]
    return reader.time_values, frames


@pytest.mark.parametrize("dim, compress", [(2, True), (3, True), (2, False)])
def test_pvd_holds_every_frame_with_exact_fields(tmp_path, dim, compress):
    sim, rng = make_sim(tmp_path, dim=dim, every_dt=0.01, compress=compress)
    expected = run(sim, rng, configured(sim), steps=12)  # t = 0 .. 0.048 s
    times, frames = read_all(sim.output_dir / PVD)
    assert len(times) == 6  # t = 0, 0.012, 0.020, 0.032, 0.040, 0.048 (final)
    assert times == sorted(expected)  # times exact: written with repr()
    for t, mesh in frames.items():
        want = expected[t]
        assert np.array_equal(mesh.points, want["points"])
        assert mesh["velocity"].shape == (sim.state.n, 3)
        for name in ("velocity", "pressure", "density", "mass", "radius", "kind", "id"):
            assert np.array_equal(mesh[name], want[name]), name
        assert mesh["id"].dtype == np.int64 and mesh["kind"].dtype == np.int8
        assert mesh.n_cells == sim.state.n  # one vertex cell per particle
    assert isinstance(pv.read(sim.output_dir / PVD), pv.MultiBlock)
    assert sorted(os.listdir(sim.output_dir / "vtu")) == [f"dam_break_{i:06d}.vtu" for i in range(6)]
    assert not [f for f in os.listdir(sim.output_dir) if f.endswith(".tmp")]
    head = (sim.output_dir / "vtu" / "dam_break_000000.vtu").read_text()[:300]
    assert ('compressor="vtkZLibDataCompressor"' in head) == compress


def test_every_steps_and_final_frame_not_duplicated(tmp_path):
    sim, rng = make_sim(tmp_path, every_steps=5)
    run(sim, rng, w := configured(sim), steps=10)
    times, _ = read_all(sim.output_dir / PVD)
    assert len(times) == 3  # steps 0, 5, 10; the final call at step 10 adds nothing
    assert w.schedule.frames == 3
    assert np.allclose(times, [0.0, 0.02, 0.04])


def test_no_frame_due_writes_no_file(tmp_path):
    sim, rng = make_sim(tmp_path, every_steps=10)
    w = configured(sim)
    for _ in range(4):  # steps 1..4: none due (step 0 output was not called)
        advance(sim, rng)
        w.sph_output(ctx=sim, final=False)
    w.sph_finish(ctx=sim)
    assert os.listdir(sim.output_dir) == []


def test_both_schedule_keys_is_a_case_error(tmp_path):
    sim, _ = make_sim(tmp_path, every_dt=0.01, every_steps=3)
    with pytest.raises(CaseError) as err:
        VtuWriter().sph_configure(case=sim.case)
    assert err.value.file == sim.case.file and err.value.key.startswith("vtu.")


def test_options_table():
    table = VtuWriter().sph_options()
    assert set(table) == {"vtu"} and set(table["vtu"]) == {"every_dt", "every_steps", "compress"}
    assert table["vtu"]["compress"].default is True


@pytest.mark.parametrize("output_at_restart_step", [False, True])
def test_restart_drops_later_frames_and_continues(tmp_path, output_at_restart_step):
    sim, rng = make_sim(tmp_path, every_steps=2)
    run(sim, rng, configured(sim), steps=9)  # frames at steps 0, 2, 4, 6, 8, 9 (final)
    t4 = read_all(sim.output_dir / PVD)[0][2]
    # as sphcore.run.runner does it: the restarted Simulation fires sph_setup at t = 0, step 0,
    # then loads the checkpoint (here: step 4; frames 6, 8, 9 are an abandoned future)
    sim.step, sim.t, sim.restarting = 0, 0.0, True
    pvd_before = (sim.output_dir / PVD).read_text()
    w = configured(sim)
    assert (sim.output_dir / PVD).read_text() == pvd_before  # nothing touched yet
    sim.step, sim.t = 4, t4
    if output_at_restart_step:  # a core that also writes at the restart point
        w.sph_output(ctx=sim, final=False)
    for _ in range(3):  # steps 5, 6, 7
        advance(sim, rng)
        w.sph_output(ctx=sim, final=False)
    w.sph_output(ctx=sim, final=True)
    times, frames = read_all(sim.output_dir / PVD)
    assert len(times) == 5  # steps 0, 2, 4 kept; 6 and 7 (final) new
    assert times[:3] == [0.0, 2 * sim.dt, t4] and times[-1] == sim.t
    assert np.array_equal(frames[sim.t]["pressure"], by_id(sim.state)["pressure"])
    assert sorted(os.listdir(sim.output_dir / "vtu")) == [f"dam_break_{i:06d}.vtu" for i in range(5)]


def test_unwritable_output_is_an_output_error(tmp_path):
    sim, rng = make_sim(tmp_path)
    (sim.output_dir / "vtu").write_text("a file where the frame directory should be")
    with pytest.raises(OutputError) as err:
        configured(sim).sph_output(ctx=sim, final=False)
    assert "vtu" in str(err.value)


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write to a read-only directory")
def test_read_only_directory_is_an_output_error(tmp_path):
    sim, _ = make_sim(tmp_path)
    sim.output_dir.chmod(0o500)
    try:
        with pytest.raises(OutputError, match="Permission denied"):
            configured(sim).sph_output(ctx=sim, final=False)
    finally:
        sim.output_dir.chmod(0o700)


CHILD = textwrap.dedent("""
    import resource, signal, sys
    from pathlib import Path
    from types import SimpleNamespace
    import numpy as np
    from sphcore.errors import OutputError
    from sphcore.physics.particles import lattice, make_block
    from sphcore_plugins.vtu import VtuWriter
    case = SimpleNamespace(name="x", dim=2, file="case.toml", config={})
    sim = SimpleNamespace(state=None, t=0.0, step=0, case=case, output_dir=Path(sys.argv[1]), stats={}, restarting=False)
    sim.host = lambda: sim.state  # a writer reads the particles through host()
    w = VtuWriter()
    # a file-size limit is a disk that fills up: writes past it fail with EFBIG
    signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
    resource.setrlimit(resource.RLIMIT_FSIZE, (20000, 20000))
    try:
        for i in range(100):  # frames grow by 50 particles until one no longer fits
            sim.state = make_block(lattice([0, 0], [1, 1], 0.1, count=[10, 5 * (i + 1)]),
                                   [0.0, 0.0], 1000.0, 0.1, 0.05, 0)
            sim.state.p[:] = i
            sim.t, sim.step = 0.01 * i, i
            w.sph_output(ctx=sim, final=False)
    except OutputError as err:
        print("OutputError:", err)
        w.sph_output(ctx=sim, final=True)  # silent after the failure, no second error
        w.sph_finish(ctx=sim)
        print("frames", len(w.frames))
""")


def test_disk_full_keeps_earlier_frames_readable(tmp_path):
    out = tmp_path / "output"
    out.mkdir()
    res = subprocess.run([sys.executable, "-c", CHILD, str(out)], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr
    assert "OutputError:" in res.stdout and "File too large" in res.stdout
    n = int(res.stdout.split("frames")[1])
    assert n >= 2
    assert f"x_{n:06d}.vtu: cannot write" in res.stdout  # names the frame that failed
    times, frames = read_all(out / "x.pvd")
    assert len(times) == n
    for i, t in enumerate(times):
        assert np.all(frames[t]["pressure"] == i)
    assert not [f for f in os.listdir(out) + os.listdir(out / "vtu") if f.endswith(".tmp")]


def test_writers_register_as_sphcore_plugins():
    # the entry points resolve, and every hook the writers implement is a known spec
    from importlib.metadata import entry_points

    import pluggy

    from sphcore.plugin import hookspecs

    eps = {ep.name: ep for ep in entry_points(group="sphcore")}
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    for name in ("vtu", "netcdf"):
        pm.register(eps[name].load()(), name=name)
    pm.check_pending()
    tables = {k for result in pm.hook.sph_options() for k in result}
    assert tables == {"vtu", "netcdf"}
