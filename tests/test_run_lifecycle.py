"""A run's life cycle through the ``sph`` command: stopped by SIGINT / SIGTERM and
restarted bit for bit, the run summary, an unstable run's output, the output directory
never clobbered, progress reporting, and a run without writer plugins.

The signal tests start ``sph run`` as a real process (the signal handling, the exit status
and stderr are what is under test); the others call ``sphcore.cli.main`` in this process,
which runs the same code without paying for a fresh interpreter each time.
"""

from __future__ import annotations

import hashlib
import json
import math
import os
import re
import shlex
import shutil
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest
import pyvista as pv
import xarray as xr
from conftest import write_case

from sphcore import cli
from sphcore.testing import case_toml
from sphcore_plugins.vtu import read_pvd

T_END = 0.3  # s simulated: ~2700 steps, ~2 s of stepping on a 2-core machine after ~2 s of start-up
N = 12 * 24  # particles
FRAME_DT = 0.01  # s between frames, both writers

# A small dam break (the Cruchaga tank of cases/dam_break at dx = 1 cm): 288 particles,
# reflective walls, VTU and netCDF frames every 0.01 s.
MINI_DAM = {
    "case": {"name": "mini_dam", "dim": 2},
    "domain": {"min": [0.0, 0.0], "max": [0.42, 0.44]},
    "blocks": [{"min": [0.0, 0.0], "count": [12, 24]}],
    "particles": {"dx": 0.01},
    "viscosity": {"alpha": 0.2},
    "time": {"t_end": T_END},
    "plugins": {"use": ["reflective", "vtu", "netcdf"]},
    "vtu": {"every_dt": FRAME_DT},
    "netcdf": {"every_dt": FRAME_DT},
}
CASE = case_toml(MINI_DAM)  # the same case as case.toml text (benchmarks/faults edit the text)

STATE = ("pos", "vel", "rho")
FRAME_FIELDS = ("time", "step", "position", "velocity", "density", "pressure")


def sph_command() -> list[str]:
    """The ``sph`` console script of this interpreter (not whatever is first on PATH)."""
    script = Path(sys.executable).with_name("sph")
    return [str(script)] if script.exists() else [sys.executable, "-m", "sphcore.cli"]


def sph(*argv, timeout=120) -> tuple[subprocess.CompletedProcess, float]:
    """Run ``sph ARGV`` to its end; (result, wall seconds)."""
    start = time.perf_counter()
    res = subprocess.run(sph_command() + [str(a) for a in argv], capture_output=True, text=True, timeout=timeout)
    return res, time.perf_counter() - start


def cli_run(capsys, *argv) -> tuple[int, str, str]:
    """``sph ARGV`` in this process: (exit status, stdout, stderr)."""
    status = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def summary_of(out: Path) -> dict:
    return json.loads((out / "summary.json").read_text())


def checkpoint_by_id(out: Path) -> tuple[dict, dict]:
    """(metadata, particle arrays ordered by id) of ``out``/checkpoint.npz."""
    with np.load(out / "checkpoint.npz") as z:
        meta = json.loads(str(z["meta"]))
        order = np.argsort(z["state_id"], kind="stable")
        arrays = {k[len("state_"):]: z[k][order] for k in z.files if k.startswith("state_")}
    return meta, arrays


def netcdf_frames(out: Path) -> dict[str, np.ndarray]:
    with xr.open_dataset(out / "particles.nc") as ds:
        assert ds.sizes["particle"] == N and ds.sizes["spatial"] == 2
        return {name: ds[name].values for name in FRAME_FIELDS + ("id",)}


def pvd_frames(out: Path) -> tuple[list[float], list]:
    """Times and meshes of ``out``/mini_dam.pvd, read with pyvista (as ParaView would)."""
    reader = pv.get_reader(str(out / "mini_dam.pvd"))
    meshes = []
    for i in range(reader.number_time_points):
        reader.set_active_time_point(i)
        meshes.append(reader.read()[0])
    return list(reader.time_values), meshes


def assert_frames_good(out: Path, t_max: float) -> dict[str, np.ndarray]:
    """Both writers' frames are readable, complete, finite, in time order, at most ``t_max``,
    and the same frames in both files; returns the netCDF frames."""
    nc = netcdf_frames(out)
    times = nc["time"]
    assert len(times) >= 2
    assert np.all(np.isfinite(times)) and times[0] == 0.0 and times[-1] <= t_max
    assert np.all(np.diff(times) > 0), times  # every frame once, increasing
    assert np.all(np.diff(nc["step"]) > 0)
    for name in ("position", "velocity", "density", "pressure"):
        assert np.all(np.isfinite(nc[name])), name
    assert np.array_equal(nc["id"], np.arange(N))
    pvd_times, meshes = pvd_frames(out)
    assert np.array_equal(pvd_times, times)  # pvd times are written with repr(): exact
    for i, mesh in enumerate(meshes):
        assert mesh.n_points == N
        assert np.array_equal(mesh.points[:, :2], nc["position"][i])
        assert np.array_equal(mesh["density"], nc["density"][i])
    return nc


def stray_files(out: Path) -> list[str]:
    """Temporary files a writer or the checkpoint left behind (there should be none)."""
    return [str(p.relative_to(out)) for p in out.rglob("*") if ".tmp" in p.name]


def snapshot(root: Path) -> dict[str, tuple]:
    """Every path below ``root`` (and root) with its mtime, and a file's size and content hash."""
    snap = {}
    for p in [root, *(sorted(root.rglob("*")) if root.is_dir() else [])]:
        st = p.stat()
        digest = hashlib.sha256(p.read_bytes()).hexdigest() if p.is_file() else None
        snap[str(p.relative_to(root))] = (st.st_mtime_ns, st.st_size if digest else None, digest)
    return snap


# ----------------------------------------------------------------------------------------
# fixtures: the case, and one uninterrupted run of it shared by the tests below
# ----------------------------------------------------------------------------------------


@pytest.fixture(scope="module")
def case_dir(tmp_path_factory) -> Path:
    return write_case(tmp_path_factory.mktemp("lifecycle") / "mini_dam", MINI_DAM)


@pytest.fixture(scope="module")
def reference(case_dir, tmp_path_factory):
    """The uninterrupted run: (output directory, wall seconds of the whole process)."""
    out = tmp_path_factory.mktemp("reference") / "out"
    res, wall = sph("run", case_dir, "--output", out, "--progress", "off")
    assert res.returncode == 0, res.stderr
    return out, wall


# ----------------------------------------------------------------------------------------
# 1. SIGINT / SIGTERM: clean stop with a checkpoint, then --restart to the same end state
# ----------------------------------------------------------------------------------------


def start_and_stop(case_dir: Path, out: Path, signum: int) -> subprocess.CompletedProcess:
    """Start ``sph run``, wait until its first frames are on disk, send ``signum``; returns
    the finished process (returncode, stdout, stderr)."""
    proc = subprocess.Popen(sph_command() + ["run", str(case_dir), "--output", str(out), "--progress", "log"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120  # a cold numba cache compiles for a while
        pvd = out / "mini_dam.pvd"
        while True:
            # the collection is replaced atomically: it is whole whenever it exists
            if pvd.exists() and len(read_pvd(pvd)) >= 3:  # frames at t = 0, 0.01, 0.02 s
                break
            assert proc.poll() is None, f"sph ended before its first frames: {proc.communicate()}"
            assert time.monotonic() < deadline, "no frames after 120 s"
            time.sleep(0.01)
        assert proc.poll() is None, "the run ended before the signal: make T_END longer"
        proc.send_signal(signum)
        stdout, stderr = proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:  # a failed assertion above: do not leave the run behind
            proc.kill()
            proc.communicate()
    return subprocess.CompletedProcess(proc.args, proc.returncode, stdout, stderr)


@pytest.mark.parametrize("signum", [signal.SIGINT, signal.SIGTERM], ids=["SIGINT", "SIGTERM"])
def test_signal_stops_cleanly_and_restart_is_bit_for_bit(case_dir, reference, tmp_path, signum):
    ref_out, _ = reference
    out = tmp_path / "out"
    stopped = start_and_stop(case_dir, out, signum)

    # a clean stop: 128 + signal number, one message naming the signal and the checkpoint
    assert stopped.returncode == 128 + signum, stopped.stderr
    assert "Traceback" not in stopped.stderr
    name = signal.Signals(signum).name
    assert re.search(rf"^sph: stopped by {name}; checkpoint written, continue with --restart$",
                     stopped.stderr, re.M), stopped.stderr
    assert ": stopped: t = " in stopped.stdout
    summary = summary_of(out)
    assert summary["status"] == "stopped" and name in summary["message"]
    meta, _ = checkpoint_by_id(out)
    assert 0.0 < meta["t"] == summary["t"] < T_END
    assert meta["step"] == summary["steps"] > 0
    assert (out / ".sphcore-output").exists()
    assert stray_files(out) == []
    # what was written is readable: the pvd with pyvista, particles.nc with xarray
    assert_frames_good(out, t_max=meta["t"])

    # --restart continues to t_end
    res, _ = sph("run", case_dir, "--output", out, "--restart", "--progress", "off")
    assert res.returncode == 0, res.stderr
    assert "Traceback" not in res.stderr
    restarted, ref = summary_of(out), summary_of(ref_out)
    assert restarted["status"] == "completed" and restarted["t"] == ref["t"] == T_END
    # the summary covers the whole run: both segments, their steps adding up
    assert restarted["steps"] == ref["steps"]
    assert [seg["status"] for seg in restarted["segments"]] == ["stopped", "completed"]
    assert [seg["steps"] for seg in restarted["segments"]] == [meta["step"], ref["steps"] - meta["step"]]
    assert restarted["wall_time_s"] >= sum(seg["wall_time_s"] for seg in restarted["segments"]) * (1 - 1e-9)

    # Bit for bit, not approximately: the numba kernels are deterministic. Each particle's
    # sums are accumulated by one thread in a fixed neighbour order (the cell list's
    # counting sort), with no parallel reduction across particles, so the thread count and
    # scheduling cannot change a single bit. The checkpoint holds the float64 state as is
    # (in the particles' current order, so the next neighbour sums run in the same order),
    # the leapfrog's rates (acc, drho), which its next step reuses instead of recomputing,
    # and t, step and dt (JSON floats round-trip exactly); so the restarted run takes the
    # same steps on the same numbers as the uninterrupted one. Writing frames reads the
    # state and never changes it.
    _, final = checkpoint_by_id(out)
    _, want = checkpoint_by_id(ref_out)
    assert np.array_equal(final["id"], want["id"])
    for key in STATE:
        assert np.array_equal(final[key], want[key]), key
    assert not np.array_equal(final["pos"], netcdf_frames(ref_out)["position"][0])  # it did move

    # the restarted run's files hold every frame time exactly once, increasing, and are
    # the uninterrupted run's frames, bit for bit
    nc, ref_nc = assert_frames_good(out, T_END), netcdf_frames(ref_out)
    assert len(np.unique(nc["time"])) == len(nc["time"])
    assert nc["time"][-1] == T_END
    for field in FRAME_FIELDS:
        assert np.array_equal(nc[field], ref_nc[field]), field
    assert read_pvd(out / "mini_dam.pvd") == read_pvd(ref_out / "mini_dam.pvd")
    assert sorted(os.listdir(out / "vtu")) == sorted(os.listdir(ref_out / "vtu"))  # no stale frame
    assert stray_files(out) == []


# ----------------------------------------------------------------------------------------
# 2. the run summary; an unstable run keeps its last good frames
# ----------------------------------------------------------------------------------------


def test_summary_of_a_completed_run(reference):
    out, process_wall = reference
    s = summary_of(out)
    assert s["status"] == "completed" and s["message"] == "" and s["t"] == T_END
    for key in ("wall_time_s", "steps", "n_particles", "particle_steps_per_s", "peak_memory_mb"):
        assert isinstance(s[key], (int, float)) and not isinstance(s[key], bool), key
        assert math.isfinite(s[key]), key
    for key in ("steps", "n_particles"):
        assert isinstance(s[key], int), key
    assert 0.0 < s["wall_time_s"] < process_wall  # the stepping, without the interpreter's start
    assert s["n_particles"] == N
    # ~T_END / (0.2 h / c0) acoustic steps: h = 0.013 m, c0 = 10 sqrt(2 g 0.24 m) = 21.7 m/s
    assert 1000 < s["steps"] < 10_000
    assert s["particle_steps_per_s"] == pytest.approx(s["steps"] * N / s["wall_time_s"], rel=1e-12)
    assert s["reflective"]["guard_returns"] == 0
    assert 20.0 < s["peak_memory_mb"] < 8192.0  # numba + vtk + netCDF loaded, 288 particles


def test_unstable_run_exits_1_and_keeps_the_last_good_frames(case_dir, tmp_path, capsys):
    # the hydrostatic start is 0.5 % above rho0 at the bottom; the collapsing column
    # passes 1 % at t ~ 0.08 s, after several frames
    out = tmp_path / "out"
    status, stdout, err = cli_run(capsys, "run", case_dir, "--output", out, "--progress", "off",
                                  "--set", "checks.rho_max=1.01", "--t-end", "0.15")
    assert status == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("sph: error: unstable at step "), err
    assert "density above the upper bound" in lines[0]
    s = summary_of(out)
    assert s["status"] == "unstable"
    assert lines[0] == f"sph: error: {s['message']}"
    assert ": unstable: " in stdout
    assert 0.0 < s["t"] < 0.15 and s["steps"] > 0
    nc = assert_frames_good(out, t_max=s["t"])  # readable, no NaN, no frame after the failure
    assert len(nc["time"]) >= 3
    assert stray_files(out) == []


# ----------------------------------------------------------------------------------------
# 3. the output directory
# ----------------------------------------------------------------------------------------


def test_existing_output_is_refused_and_overwrite_replaces_only_sph_output(case_dir, tmp_path, capsys):
    out = tmp_path / "out"
    args = ("run", case_dir, "--output", out, "--progress", "off", "--t-end", "0.02")
    assert cli_run(capsys, *args)[0] == 0
    assert (out / "particles.nc").exists() and (out / "vtu").is_dir()
    before = snapshot(out)
    time.sleep(0.01)  # a later write would show in the mtimes

    # refused: exit 2, one line, not a byte or a timestamp changed
    status, _, err = cli_run(capsys, *args)
    assert status == 2 and len(err.strip().splitlines()) == 1
    assert str(out) in err and "--overwrite" in err
    assert snapshot(out) == before
    # a case that fails to set up leaves it alone even with --overwrite
    status, _, err = cli_run(capsys, *args, "--overwrite", "--set", "domain.min=[0.05, 0.0]")
    assert status == 2 and "blocks[0]" in err and "outside wall plane" in err
    assert snapshot(out) == before

    # --overwrite replaces what sph wrote: nothing of the old run remains, but a file the
    # user added (not in the marker's manifest) is kept, even among the frames
    (out / "vtu" / "mine.vtu").write_text("the user's")
    old_frames = sorted(os.listdir(out / "vtu"))
    assert cli_run(capsys, *args[:-1], "0.01", "--overwrite")[0] == 0
    assert (out / "vtu" / "mine.vtu").read_text() == "the user's"
    new_frames = sorted(Path(rel).name for _, rel in read_pvd(out / "mini_dam.pvd"))
    assert sorted(os.listdir(out / "vtu")) == sorted(new_frames + ["mine.vtu"])
    assert len(old_frames) == 4 and len(new_frames) == 2  # the old run's third frame is gone
    assert summary_of(out)["t"] == 0.01
    assert len(netcdf_frames(out)["time"]) == 2  # t = 0 and 0.01 s, none of the old run's 3
    assert (out / ".sphcore-output").exists()

    # a non-empty directory sph did not write is never deleted, --overwrite or not
    foreign = tmp_path / "foreign"
    (foreign / "sub").mkdir(parents=True)
    (foreign / "precious.txt").write_text("keep me")
    (foreign / "sub" / "data.bin").write_bytes(b"\x00\x01")
    before = snapshot(foreign)
    time.sleep(0.01)
    for extra in ((), ("--overwrite",)):
        status, _, err = cli_run(capsys, "run", case_dir, "--output", foreign, "--progress", "off", *extra)
        assert status == 2 and len(err.strip().splitlines()) == 1 and str(foreign) in err
        assert snapshot(foreign) == before
    assert "refusing" in err and ".sphcore-output" in err


def test_output_path_that_is_a_file_is_refused(case_dir, tmp_path, capsys):
    path = tmp_path / "results"
    path.write_text("not a directory")
    before = snapshot(path)
    for extra in ((), ("--overwrite",), ("--restart",)):
        status, _, err = cli_run(capsys, "run", case_dir, "--output", path, "--progress", "off", *extra)
        assert status == 2, extra
        assert err.startswith("sph: error: ") and len(err.strip().splitlines()) == 1, err
        assert path.read_text() == "not a directory" and snapshot(path) == before


# ----------------------------------------------------------------------------------------
# 4. progress
# ----------------------------------------------------------------------------------------

LOG_LINE = re.compile(r"^\[sph\] t = (\S+)/(\S+) s \((\S+)%\), step (\d+), dt = \S+ s, "
                      r"(\d+) steps/s, (\S+) particle-steps/s, ETA \S+ s$")


def test_progress_log_lines_and_off(case_dir, tmp_path, capsys):
    status, _, err = cli_run(capsys, "run", case_dir, "--output", tmp_path / "log", "--progress", "log",
                             "--t-end", "0.02", "--set", "output.log_interval_s=0.001")
    assert status == 0, err
    lines = [line for line in err.splitlines() if line.startswith("[sph]")]
    assert len(lines) >= 3, err
    ts = []
    for line in lines:
        m = LOG_LINE.match(line)
        assert m, line
        t, t_end, steps_per_s, particle_steps_per_s = (float(m.group(i)) for i in (1, 2, 5, 6))
        assert t_end == 0.02 and 0.0 < t <= t_end
        assert steps_per_s > 0
        # both rates come from one count of steps: they differ by the particle count, up to
        # the printed rounding (steps/s to an integer, particle-steps/s to 3 digits)
        assert abs(particle_steps_per_s / N - steps_per_s) <= 0.5 + 0.006 * particle_steps_per_s / N
        ts.append(t)
    assert ts == sorted(ts)

    status, _, err = cli_run(capsys, "run", case_dir, "--output", tmp_path / "off", "--progress", "off",
                             "--t-end", "0.02", "--set", "output.log_interval_s=0.001")
    assert status == 0, err
    assert "[sph]" not in err and "steps/s" not in err


@pytest.mark.skipif(shutil.which("script") is None, reason="needs script(1) for a pseudo-terminal")
def test_progress_bar_on_a_terminal(case_dir, tmp_path):
    """``--progress auto`` (the default) draws a bar when stderr is a terminal."""
    def on_a_terminal(cmd):
        # a pty made by script(1) may have 0 columns, and tqdm then draws nothing: set a size
        return subprocess.run(["script", "-qec", f"stty cols 120 rows 40; {cmd}", "/dev/null"],
                              stdin=subprocess.DEVNULL, capture_output=True, text=True, timeout=120)

    probe = on_a_terminal("test -t 2")
    if probe.returncode != 0:
        pytest.skip(f"script(1) gives no pseudo-terminal here: {probe.stdout[-300:]}{probe.stderr[-300:]}")
    res = on_a_terminal(shlex.join(sph_command() + ["run", str(case_dir), "--output", str(tmp_path / "out"),
                                                    "--t-end", "0.05"]))
    assert res.returncode == 0, res.stdout + res.stderr
    assert re.search(r"\d+%\|.*\| t=\S+/0\.05 s \[.*\d+ steps/s, \S+ particle-steps/s\]", res.stdout), res.stdout
    assert "[sph] t = " not in res.stdout  # a bar, not log lines


# ----------------------------------------------------------------------------------------
# 5. no writer plugin: no frames
# ----------------------------------------------------------------------------------------


def test_run_without_writers_writes_no_frames(case_dir, tmp_path, capsys):
    out = tmp_path / "out"
    status, _, err = cli_run(capsys, "run", case_dir, "--output", out, "--progress", "off", "--t-end", "0.02",
                             "--set", 'plugins.use=["reflective"]')
    assert status == 0, err
    files = sorted(str(p.relative_to(out)) for p in out.rglob("*"))
    assert files == [".sphcore-lock", ".sphcore-output", "checkpoint.npz", "summary.json"]
    s = summary_of(out)
    assert s["status"] == "completed" and "vtu_frames" not in s and "netcdf_frames" not in s
