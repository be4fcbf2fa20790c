"""Inputs at the edges, each refused with exit status 2 and one line naming the key (or
the option, or the file), nothing written, or ended with one line: a mesh file that is a
pipe or a device, a run whose step count exceeds time.max_steps, an end time lost in the
round-off, a zero-area polygon, a radius or output folder that cannot be, sweep options
that are not what they should be, a signal while sph starts, and post-processing scripts
given what is not a run."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
from conftest import write_case
from test_run_lifecycle import MINI_DAM, snapshot, sph, sph_command

from sphcore import cli
from sphcore.testing import case_with

ROOT = Path(__file__).resolve().parents[1]


def check(capsys, case_dir, *argv) -> str:
    """``sph check`` and ``sph run`` in this process: both exit 2 with the same one line,
    and nothing is written; returns that line."""
    before = snapshot(case_dir.parent)
    lines = []
    for command in ("check", "run"):
        extra = ("--progress", "off") if command == "run" else ()
        status = cli.main([command, str(case_dir), *extra, *map(str, argv)])
        out, err = capsys.readouterr()
        assert status == 2, (out, err)
        assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
        lines.append(err.strip())
    assert lines[0] == lines[1]
    assert snapshot(case_dir.parent) == before, "something was written"
    return lines[0]


@pytest.fixture
def dam(tmp_path):
    return write_case(tmp_path / "dam", MINI_DAM)


# -- the case ---------------------------------------------------------------------------

def test_a_sound_speed_needing_more_steps_than_max_steps_is_refused_naming_it(dam, capsys):
    line = check(capsys, dam, "--set", "eos.c0=1e6", "--t-end", "30")
    assert "eos.c0: c0 = 1e+06 m/s: a time step of" in line and "steps to reach" in line and "max_steps" in line
    line = check(capsys, dam, "--set", "eos.c0_factor=1e4", "--t-end", "300")
    assert ": eos.c0_factor: " in line
    line = check(capsys, dam, "--t-end", "1e6")
    assert line.startswith("sph: error: --t-end: time.t_end: a time step of"), line


def test_an_end_time_lost_in_the_round_off_is_blamed_on_the_end_time(dam, capsys):
    line = check(capsys, dam, "--t-end", "1e300")
    assert line.startswith("sph: error: --t-end: time.t_end: ") and "time.cfl" not in line, line
    write_case(dam, case_with(MINI_DAM, {"time.t_end": 1e300}))
    line = check(capsys, dam)
    assert ": time.t_end: " in line and "round-off" in line


@pytest.mark.parametrize("points", [[[0.3, 0.1], [0.35, 0.15], [0.4, 0.2]],
                                    [[0.3, 0.1], [0.4, 0.1], [0.35, 0.1], [0.32, 0.1]]], ids=["three", "four"])
def test_a_polygon_of_collinear_points_is_refused(dam, capsys, points):
    write_case(dam, case_with(MINI_DAM, {"domain.walls": [{"shape": "polygon", "points": points}]}))
    line = check(capsys, dam)
    assert ": domain.walls[0].points: " in line, line


def test_a_radius_that_reaches_the_walls_names_particles_radius(dam, capsys):
    line = check(capsys, dam, "--set", "particles.radius=1")
    assert ": particles.radius: 1 m puts the particle" in line, line


@pytest.mark.parametrize("value", ["case.toml", "case.toml/out", "./case.toml"])
def test_an_output_dir_that_is_a_file_names_output_dir(dam, capsys, value):
    write_case(dam, case_with(MINI_DAM, {"output.dir": value}))
    line = check(capsys, dam)
    assert ": output.dir: " in line and "is a file" in line, line


def test_an_output_option_below_a_file_is_refused(dam, tmp_path, capsys):
    (tmp_path / "file").write_text("a user's")
    status = cli.main(["run", str(dam), "--output", str(tmp_path / "file" / "out"), "--progress", "off"])
    err = capsys.readouterr().err
    assert status == 2 and len(err.strip().splitlines()) == 1 and "is a file" in err, err
    assert (tmp_path / "file").read_text() == "a user's"


def _mesh_case(dam: Path) -> Path:
    write_case(dam, case_with(MINI_DAM, {"domain.walls": [{"shape": "mesh", "file": "wall.obj"}]}))
    return dam / "wall.obj"


@pytest.mark.parametrize("kind", ["fifo", "dev-zero", "dev-zero-obj-link", "directory"])
def test_a_mesh_file_that_is_not_a_regular_file_is_refused_without_reading_it(dam, kind):
    """A pipe nobody writes or a link to /dev/zero would block or never end: refused at
    once (exit 2, one line naming domain.walls[0].file), as a process."""
    mesh = _mesh_case(dam)
    if kind == "fifo":
        os.mkfifo(mesh)
    elif kind == "directory":
        mesh.mkdir()
    else:
        mesh.symlink_to("/dev/zero")
    for command in ("check", "run"):
        res, wall = sph(command, dam, timeout=60)
        assert res.returncode == 2 and "Traceback" not in res.stderr, res.stderr
        assert len(res.stderr.strip().splitlines()) == 1 and "domain.walls[0].file" in res.stderr, res.stderr
        assert wall < 30
    assert not (dam / "output").exists()


# -- signals while sph starts -----------------------------------------------------------

@pytest.mark.parametrize("signum, delay", [(signal.SIGINT, 0.3), (signal.SIGTERM, 0.3), (signal.SIGINT, 0.8),
                                           (signal.SIGTERM, 0.8)])
def test_a_signal_while_sph_starts_ends_with_one_line(dam, signum, delay):
    proc = subprocess.Popen(sph_command() + ["run", str(dam), "--progress", "off", "--t-end", "30"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    time.sleep(delay)
    proc.send_signal(signum)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 128 + signum, err
    assert len(err.strip().splitlines()) == 1 and "Traceback" not in err, err


# -- sph sweep --------------------------------------------------------------------------

def sweep(capsys, *argv) -> tuple[int, str]:
    status = cli.main(["sweep", *map(str, argv)])
    return status, capsys.readouterr().err


SWEEP_REFUSALS = {
    "nested vary": (["--vary", "viscosity.alpha=" + "[" * 2000 + "]" * 2000], "--vary: viscosity.alpha: "),
    "nested set": (["--vary", "viscosity.alpha=0.1,0.2", "--set", "time.t_end=" + "[" * 500 + "]" * 500], "--set: "),
    "timeout -1": (["--vary", "viscosity.alpha=0.1,0.2", "--timeout", "-1"], "--timeout"),
    "timeout nan": (["--vary", "viscosity.alpha=0.1,0.2", "--timeout", "nan"], "--timeout"),
    "timeout inf": (["--vary", "viscosity.alpha=0.1,0.2", "--timeout", "inf"], "--timeout"),
    "timeout 0": (["--vary", "viscosity.alpha=0.1,0.2", "--timeout", "0"], "--timeout"),
}


@pytest.mark.parametrize("what", list(SWEEP_REFUSALS))
def test_sweep_refuses_bad_options_with_one_line(dam, capsys, what):
    argv, says = SWEEP_REFUSALS[what]
    before = snapshot(dam.parent)
    status, err = sweep(capsys, dam, *argv, "--dry-run")
    assert status == 2 and len(err.strip().splitlines()) == 1 and says in err and "Traceback" not in err, err
    assert snapshot(dam.parent) == before


def test_a_huge_sweep_grid_is_refused_at_once(dam, capsys):
    values = ",".join(str(0.1 + i * 1e-4) for i in range(1000))
    start = time.perf_counter()
    status, err = sweep(capsys, dam, "--vary", f"viscosity.alpha={values}", "--vary", f"viscosity.beta={values}",
                        "--dry-run")
    assert time.perf_counter() - start < 5
    assert status == 2 and "1000 x 1000 = 1000000 variants" in err and len(err.strip().splitlines()) == 1, err


@pytest.mark.parametrize("where", ["file", "below a file", "scheduler"])
def test_sweep_refuses_an_output_that_is_a_file_and_a_scheduler_that_is_not_an_address(dam, tmp_path, capsys, where):
    pytest.importorskip("distributed")
    (tmp_path / "file").write_text("a user's")
    argv = {"file": ["--output", tmp_path / "file"], "below a file": ["--output", tmp_path / "file" / "sweep"],
            "scheduler": ["--scheduler", "not an address", "--output", tmp_path / "sweep"]}[where]
    status, err = sweep(capsys, dam, "--vary", "viscosity.alpha=0.1,0.2", *argv)
    assert status == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert (tmp_path / "file").read_text() == "a user's" and not (tmp_path / "sweep").exists()


# -- post-processing --------------------------------------------------------------------

SCRIPTS = ["peer_series", "pressure_profile", "probes", "render", "spheric_test2", "wavefront"]


def _run_script(name, *argv):
    res = subprocess.run([sys.executable, str(ROOT / "postprocessing" / f"{name}.py"), *map(str, argv)],
                         capture_output=True, text=True, timeout=120)
    return res.returncode, res.stderr


def _garbage_run(d: Path) -> Path:
    d.mkdir()
    (d / "summary.json").write_text(json.dumps({"config": {"case": {"dim": 2}, "blocks": 3}}))
    (d / "probes.csv").write_bytes(b"time_s,P1_pa\nx,y\n\x00\x01")
    (d / "probes.nc").write_bytes(b"not netCDF")
    (d / "particles.nc").write_bytes(b"not netCDF")
    return d


@pytest.mark.parametrize("name", SCRIPTS)
@pytest.mark.parametrize("what", ["empty", "garbage", "config-not-tables"])
def test_post_processing_refuses_what_is_not_a_run_with_one_line(tmp_path, name, what):
    if what == "empty":
        run = tmp_path / "empty"
        run.mkdir()
    else:
        run = _garbage_run(tmp_path / "garbage")
        if what == "config-not-tables":
            (run / "summary.json").write_text(json.dumps({"config": 3}))
    argv = ([run / "probes.csv" if what != "empty" else run, "--reference", "buchner_2002_P1", "--H", "0.3"]
            if name == "peer_series" else [run])
    status, err = _run_script(name, *argv)
    assert status == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err


@pytest.mark.parametrize("h", ["nan", "-1", "0", "inf"])
def test_peer_series_refuses_a_height_that_is_not_one(tmp_path, h):
    series = tmp_path / "s.csv"
    series.write_text("0,0\n0.1,100\n0.2,50\n")
    status, err = _run_script("peer_series", series, "--reference", "buchner_2002_P1", "--H", h)
    assert status == 2 and "--H" in err and len(err.strip().splitlines()) == 1, err


def test_peer_series_refuses_a_csv_of_one_row(tmp_path):
    series = tmp_path / "s.csv"
    series.write_text("a,b\nx,y\n1,2,3\n")
    status, err = _run_script("peer_series", series, "--reference", "buchner_2002_P1", "--H", "0.3")
    assert status == 2 and "at least two rows" in err, err

