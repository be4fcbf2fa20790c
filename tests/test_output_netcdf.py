"""netCDF writer: one particles.nc per run that xarray reads back exactly, with units."""

import os
import subprocess
import sys
import textwrap
from types import SimpleNamespace

import netCDF4
import numpy as np
import pytest
import xarray as xr
from conftest import write_cut_netcdf

from sphcore.errors import CaseError, OutputError
from sphcore.physics.particles import FLUID, SPHERE, lattice, make_block
from sphcore_plugins.netcdf import NetcdfWriter, case_attributes

CONFIG = {
    "case": {"name": "dam", "dim": 2, "description": ""},
    "time": {"t_end": 0.5, "dt": None, "cfl": 0.2},
    "physics": {"sph": True, "gravity": [0.0, -9.81, 0.0]},
    "blocks": [{"min": [0.0, 0.0], "max": [0.5, 1.0]}],
    "plugins": {"use": ["netcdf", "vtu"]},
    "neighbours": {"sort_every": 10},
}


def make_sim(tmp_path, dim=2, every_dt=None, every_steps=None, seed=0):
    """A stand-in for the core's Simulation: random fields, particles in a shuffled order."""
    rng = np.random.default_rng(seed)
    st = make_block(lattice(np.zeros(dim), np.ones(dim), 0.25), np.zeros(dim), 1000.0, 0.25, 0.1, FLUID)
    st.kind[::3] = SPHERE
    st.m = rng.uniform(0.5, 1.5, st.n)
    st.radius = rng.uniform(0.05, 0.1, st.n)
    config = dict(CONFIG, netcdf={"every_dt": every_dt, "every_steps": every_steps})
    case = SimpleNamespace(name="dam", dim=dim, file=str(tmp_path / "case.toml"), config=config)
    out = tmp_path / "output"
    out.mkdir()
    sim = SimpleNamespace(state=st, t=0.0, step=0, dt=0.004, case=case, output_dir=out, stats={}, restarting=False)
    sim.host = lambda: sim.state  # a writer reads the particles through host()
    shuffle(sim, rng)
    return sim, rng


def shuffle(sim, rng):
    """New values everywhere, then a reorder as the core's cell sort does."""
    st = sim.state
    st.pos = st.pos + 0.01 * rng.normal(size=st.pos.shape)
    st.vel = rng.normal(size=st.vel.shape)
    st.rho = 1000.0 + rng.normal(size=st.n)
    st.p = 1e3 * rng.normal(size=st.n)
    st.permute(rng.permutation(st.n))


def advance(sim, rng):
    shuffle(sim, rng)
    sim.t += sim.dt
    sim.step += 1


def configured(sim):
    w = NetcdfWriter()
    w.sph_configure(case=sim.case)
    w.sph_setup(ctx=sim)
    return w


def by_id(sim):
    st = sim.state
    o = np.argsort(st.id)
    return {"time": sim.t, "step": sim.step, "position": st.pos[o], "velocity": st.vel[o],
            "density": st.rho[o], "pressure": st.p[o]}


def run(sim, rng, writer, steps, finish=True):
    """Steps 0..steps with output after each, then the final call; the frames expected."""
    frames = []
    for i in range(steps + 1):
        if i:
            advance(sim, rng)
        if _writes(writer, sim, final=False):
            frames.append(by_id(sim))
    if _writes(writer, sim, final=True):
        frames.append(by_id(sim))
    if finish:
        writer.sph_finish(ctx=sim)
    return frames


def _writes(writer, sim, final):
    """Call sph_output; True when it appended a frame (a restart's reopen also moves ``row``)."""
    before = writer.schedule.frames
    writer.sph_output(ctx=sim, final=final)
    return writer.schedule.frames > before


def stacked(frames, name):
    return np.array([f[name] for f in frames])


def test_round_trip_is_exact_with_units_and_attributes(tmp_path):
    sim, rng = make_sim(tmp_path, every_dt=0.01)
    static = {"mass": sim.state.m, "radius": sim.state.radius, "kind": sim.state.kind, "id": sim.state.id}
    o = np.argsort(sim.state.id)
    static = {k: v[o] for k, v in static.items()}
    frames = run(sim, rng, configured(sim), steps=12)
    assert len(frames) == 6  # t = 0, 0.012, 0.020, 0.032, 0.040, 0.048 (final)
    with xr.open_dataset(sim.output_dir / "particles.nc") as ds:
        assert dict(ds.sizes) == {"time": 6, "particle": sim.state.n, "spatial": 2}
        for name in ("time", "step", "position", "velocity", "density", "pressure"):
            assert np.array_equal(ds[name].values, stacked(frames, name)), name
        for name, want in static.items():
            assert np.array_equal(ds[name].values, want), name
        assert ds.position.dtype == np.float64 and ds.id.dtype == np.int64 and ds.kind.dtype == np.int8
        assert ds.position.dims == ("time", "particle", "spatial")
        units = {name: ds[name].attrs.get("units") for name in ds.variables}
        assert units == {"time": "s", "step": "1", "position": "m", "velocity": "m s-1",
                         "density": "kg m-3", "pressure": "Pa", "mass": "kg", "radius": "m",
                         "kind": "1", "id": "1"}
        assert ds.time.attrs["standard_name"] == "time"
        assert all("long_name" in ds[name].attrs for name in ds.variables)
        assert list(ds.kind.attrs["flag_values"]) == [FLUID, SPHERE, 2]
        assert ds.attrs["Conventions"] == "CF-1.8"
        assert ds.attrs["time.t_end"] == 0.5 and ds.attrs["time.cfl"] == 0.2
        assert "time.dt" not in ds.attrs  # None omitted
        assert ds.attrs["neighbours.sort_every"] == 10
        assert np.array_equal(ds.attrs["physics.gravity"], [0.0, -9.81, 0.0])
        assert ds.attrs["physics.sph"] == "true"
        assert ds.attrs["plugins.use"] == '["netcdf", "vtu"]'
        assert ds.attrs["blocks"].startswith("[{")


def test_case_attributes_flatten():
    attrs = case_attributes({"a": {"x": 1, "y": None, "v": [1, 2], "s": ["p"], "b": False, "e": []}})
    assert attrs["a.x"] == 1 and attrs["a.v"].dtype == np.int64 and attrs["a.b"] == "false"
    assert attrs["a.s"] == '["p"]' and attrs["a.e"] == "[]" and "a.y" not in attrs


def test_3d_and_every_steps_final_not_duplicated(tmp_path):
    sim, rng = make_sim(tmp_path, dim=3, every_steps=5)
    frames = run(sim, rng, configured(sim), steps=10)
    with xr.open_dataset(sim.output_dir / "particles.nc") as ds:
        assert list(ds.step.values) == [0, 5, 10]  # the final call at step 10 adds nothing
        assert ds.sizes["spatial"] == 3
        assert np.array_equal(ds.velocity.values, stacked(frames, "velocity"))


def test_frames_are_on_disk_while_the_run_goes_on(tmp_path):
    sim, rng = make_sim(tmp_path, every_steps=1)
    w = configured(sim)
    frames = run(sim, rng, w, steps=3, finish=False)
    # another process reads the file while the writer still holds it open
    code = "import sys, xarray as xr; print(xr.open_dataset(sys.argv[1]).sizes['time'])"
    res = subprocess.run([sys.executable, "-c", code, str(w.path)], capture_output=True, text=True, timeout=60)
    assert res.returncode == 0, res.stderr
    assert int(res.stdout) == len(frames) == 4
    w.sph_finish(ctx=sim)
    w.sph_finish(ctx=sim)  # idempotent


def test_no_frame_due_opens_no_file(tmp_path):
    sim, rng = make_sim(tmp_path, every_steps=10)
    w = configured(sim)
    for _ in range(4):  # steps 1..4: none due (step 0 output was not called)
        advance(sim, rng)
        w.sph_output(ctx=sim, final=False)
    w.sph_finish(ctx=sim)
    assert os.listdir(sim.output_dir) == []
    assert w.sph_summary(ctx=sim) is None


def test_both_schedule_keys_is_a_case_error(tmp_path):
    sim, _ = make_sim(tmp_path, every_dt=0.02, every_steps=3)
    with pytest.raises(CaseError) as err:
        NetcdfWriter().sph_configure(case=sim.case)
    assert err.value.file == sim.case.file and err.value.key.startswith("netcdf.")


def test_changed_particle_set_is_an_output_error(tmp_path):
    sim, rng = make_sim(tmp_path, every_steps=1)
    w = configured(sim)
    w.sph_output(ctx=sim, final=False)
    sim.state.append(make_block(np.zeros((1, 2)), [0.0, 0.0], 1000.0, 0.25, 0.1, FLUID))
    sim.step += 1
    with pytest.raises(OutputError, match="particles.nc: the set of particles changed"):
        w.sph_output(ctx=sim, final=False)
    w.sph_finish(ctx=sim)


@pytest.mark.parametrize("output_at_restart_step", [False, True])
def test_restart_drops_later_frames_and_appends(tmp_path, output_at_restart_step):
    sim, rng = make_sim(tmp_path, every_steps=2)
    first = run(sim, rng, configured(sim), steps=9)  # steps 0, 2, 4, 6, 8, 9 (final)
    assert [f["step"] for f in first] == [0, 2, 4, 6, 8, 9]
    # as sphcore.run.runner does it: the restarted Simulation fires sph_setup at t = 0, step 0,
    # then loads the checkpoint (here: step 4; frames 6, 8, 9 are an abandoned future)
    sim.step, sim.t, sim.restarting = 0, 0.0, True
    w = configured(sim)
    assert w.ds is None  # nothing opened or rewritten yet
    sim.step, sim.t = 4, first[2]["time"]
    if output_at_restart_step:  # a core that also writes at the restart point
        assert not _writes(w, sim, final=False)
        assert w.row == 3
    second = []
    for _ in range(3):  # steps 5, 6, 7
        advance(sim, rng)
        if _writes(w, sim, final=False):
            second.append(by_id(sim))
    if _writes(w, sim, final=True):
        second.append(by_id(sim))
    w.sph_finish(ctx=sim)
    assert [f["step"] for f in second] == [6, 7]
    frames = first[:3] + second
    with xr.open_dataset(sim.output_dir / "particles.nc") as ds:
        for name in ("time", "step", "position", "velocity", "density", "pressure"):
            assert np.array_equal(ds[name].values, stacked(frames, name)), name
        assert ds.attrs["time.t_end"] == 0.5  # attributes survive the rewrite
        assert ds.sizes["particle"] == sim.state.n


@pytest.mark.parametrize("cut", ["empty", "attributes only", "dimensions only"])
def test_restart_after_a_kill_while_the_header_was_written(tmp_path, cut):
    """A run killed inside its first frame's header leaves a particles.nc with no frame (its
    checkpoint is the one before any frame): the restart writes the file anew, every frame."""
    sim, rng = make_sim(tmp_path, every_steps=2)
    path = sim.output_dir / "particles.nc"

    def dimensions(ds):
        ds.createDimension("particle", sim.state.n)
        ds.createDimension("time", None)

    write_cut_netcdf(path, cut, dimensions if cut == "dimensions only" else None)
    sim.restarting = True
    frames = run(sim, rng, configured(sim), steps=5)
    assert [f["step"] for f in frames] == [0, 2, 4, 5]
    with xr.open_dataset(path) as ds:
        for name in ("time", "step", "position", "velocity", "density", "pressure"):
            assert np.array_equal(ds[name].values, stacked(frames, name)), name


def test_killed_run_keeps_synced_frames(tmp_path):
    sim, _ = make_sim(tmp_path)
    child = textwrap.dedent("""
        import os, signal, sys
        from pathlib import Path
        from types import SimpleNamespace
        from sphcore.physics.particles import lattice, make_block
        from sphcore_plugins.netcdf import NetcdfWriter
        st = make_block(lattice([0, 0], [1, 1], 0.1), [0.0, 0.0], 1000.0, 0.1, 0.05, 0)
        case = SimpleNamespace(name="x", dim=2, file="case.toml", config={})
        sim = SimpleNamespace(state=st, t=0.0, step=0, case=case, output_dir=Path(sys.argv[1]), stats={}, restarting=False)
        sim.host = lambda: sim.state  # a writer reads the particles through host()
        w = NetcdfWriter()
        for i in range(3):
            sim.t, sim.step = 0.01 * i, i
            w.sph_output(ctx=sim, final=False)
        os.kill(os.getpid(), signal.SIGKILL)  # no close, no finish
    """)
    res = subprocess.run([sys.executable, "-c", child, str(sim.output_dir)], timeout=60)
    assert res.returncode == -9
    with xr.open_dataset(sim.output_dir / "particles.nc") as ds:
        assert list(ds.step.values) == [0, 1, 2]
        assert np.array_equal(ds.time.values, [0.0, 0.01, 0.02])


def test_unwritable_output_is_an_output_error(tmp_path):
    sim, _ = make_sim(tmp_path)
    (sim.output_dir / "particles.nc").mkdir()  # something that cannot be opened as a file
    with pytest.raises(OutputError, match="particles.nc: cannot create"):
        configured(sim).sph_output(ctx=sim, final=False)


@pytest.mark.skipif(os.geteuid() == 0, reason="root may write to a read-only directory")
def test_read_only_directory_is_an_output_error(tmp_path):
    sim, _ = make_sim(tmp_path)
    sim.output_dir.chmod(0o500)
    try:
        with pytest.raises(OutputError, match="particles.nc: cannot create.*Permission denied"):
            configured(sim).sph_output(ctx=sim, final=False)
    finally:
        sim.output_dir.chmod(0o700)


def test_disk_full_keeps_earlier_frames_readable(tmp_path):
    out = tmp_path / "output"
    out.mkdir()
    child = textwrap.dedent("""
        import resource, signal, sys
        from pathlib import Path
        from types import SimpleNamespace
        from sphcore.errors import OutputError
        from sphcore.physics.particles import lattice, make_block
        from sphcore_plugins.netcdf import NetcdfWriter
        st = make_block(lattice([0, 0], [1, 1], 0.05), [0.0, 0.0], 1000.0, 0.05, 0.025, 0)
        case = SimpleNamespace(name="x", dim=2, file="case.toml", config={})
        sim = SimpleNamespace(state=st, t=0.0, step=0, case=case, output_dir=Path(sys.argv[1]), stats={}, restarting=False)
        sim.host = lambda: sim.state  # a writer reads the particles through host()
        w = NetcdfWriter()
        # a file-size limit is a disk that fills up: writes past it fail with EFBIG.
        # 400 particles: ~10 kB header and static data, ~19 kB a frame; 60 000 bytes
        # runs out in the middle of the third frame.
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
        resource.setrlimit(resource.RLIMIT_FSIZE, (60000, 60000))
        try:
            for i in range(100):
                sim.t, sim.step = 0.01 * i, i
                st.p[:] = i
                w.sph_output(ctx=sim, final=False)
        except OutputError as err:
            print("OutputError:", err)
        w.sph_output(ctx=sim, final=True)  # silent after the failure, no second error
        w.sph_finish(ctx=sim)
        print("rows", w.row)
    """)
    res = subprocess.run([sys.executable, "-c", child, str(out)], capture_output=True, text=True, timeout=120)
    assert res.returncode == 0, res.stderr  # and no crash closing the failed file
    assert "particles.nc: cannot write the frame at step 2: File too large" in res.stdout
    assert int(res.stdout.split("rows")[1]) == 2
    with xr.open_dataset(out / "particles.nc") as ds:
        assert list(ds.step.values) == [0, 1]
        assert np.all(ds.pressure.values == np.array([[0.0], [1.0]]))
    with netCDF4.Dataset(out / "particles.nc") as ds:
        assert ds.data_model == "NETCDF3_64BIT_DATA"
