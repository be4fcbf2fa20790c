"""Runs that survive anything: SIGKILL at random moments then ``--restart`` bit
for bit, periodic checkpoints, a restart that refuses another run's checkpoint, an
overwrite that never deletes a user's file. A full disk at every write point:
tests/test_full_disk.py.

The kill test runs ``sph`` as real processes (SIGKILL is what is under test); the others
call ``sphcore.cli.main`` in this process. Malformed inputs: tests/test_malformed_inputs.py.
"""

from __future__ import annotations

import json
import os
import random
import shutil
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import write_case
from core_cases import good
from test_run_lifecycle import (
    FRAME_FIELDS,
    MINI_DAM,
    checkpoint_by_id,
    netcdf_frames,
    snapshot,
    sph_command,
    stray_files,
)

import sphcore
from sphcore import cli
from sphcore.io import outdir
from sphcore.testing import case_with


def cli_main(capsys, *argv) -> tuple[int, str, str]:
    status = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


# ----------------------------------------------------------------------------------------
# 2. SIGKILL at random moments, then --restart: bit for bit the uninterrupted run
# ----------------------------------------------------------------------------------------

CKPT = ["--set", "output.checkpoint_every_dt=0.02"]


def mini_dam_and_reference(root: Path) -> tuple[Path, Path]:
    """The mini dam break of test_run_lifecycle written under ``root`` and its uninterrupted
    run (in this process): (case folder, run folder)."""
    case_dir = write_case(root / "mini_dam", MINI_DAM)
    ref = root / "ref"
    assert cli.main(["run", str(case_dir), "--output", str(ref), "--progress", "off", *CKPT]) == 0
    return case_dir, ref


@pytest.fixture(scope="module")
def dam(tmp_path_factory):
    """The mini dam break and its uninterrupted run (:func:`mini_dam_and_reference`)."""
    return mini_dam_and_reference(tmp_path_factory.mktemp("survival"))


def assert_same_as_reference(out: Path, ref: Path):
    meta, final = checkpoint_by_id(out)
    ref_meta, want = checkpoint_by_id(ref)
    assert meta["t"] == ref_meta["t"] and meta["step"] == ref_meta["step"]
    for key in ("id", "pos", "vel", "rho", "p"):
        assert np.array_equal(final[key], want[key]), key
    nc, ref_nc = netcdf_frames(out), netcdf_frames(ref)
    for field in FRAME_FIELDS:
        assert np.array_equal(nc[field], ref_nc[field]), field
    assert stray_files(out) == []


def kill_and_restart(case_dir: Path, out: Path, kills: int, rng: random.Random, stepping_s: float) -> int:
    """Start the run, SIGKILL it at a random moment, restart and kill again ``kills`` times,
    then restart to the end. A kill lands during start-up (one in four, once a checkpoint
    exists) or while stepping, writing frames or a checkpoint: uniformly within
    2 ``stepping_s`` / (kills + 1) (``stepping_s``: the uninterrupted run's stepping time)
    after the process prepared its output directory (rewrote the marker). Returns the kills
    that hit a running process."""
    hit = 0
    marker = out / outdir.MARKER
    for k in range(kills + 1):
        argv = ["run", str(case_dir), "--output", str(out), "--progress", "off", *CKPT]
        if k > 0:
            argv.append("--restart")
        launched = time.time_ns()
        proc = subprocess.Popen(sph_command() + argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
        try:
            if k == kills:  # the last one runs to its end
                _, err = proc.communicate(timeout=120)
                assert proc.returncode == 0, err
                break
            deadline = time.monotonic() + 60
            during_startup = k > 0 and rng.random() < 0.25
            if during_startup:
                time.sleep(rng.uniform(0.0, 1.5))
            else:
                while proc.poll() is None and not (marker.exists() and marker.stat().st_mtime_ns >= launched
                                                   and (out / "checkpoint.npz").exists()):
                    assert time.monotonic() < deadline, "the run did not start"
                    time.sleep(0.002)
                # spread over the run: on average the kills together cover all of it
                time.sleep(rng.uniform(0.0, 2.0 * stepping_s / (kills + 1)))
            if proc.poll() is None:
                proc.send_signal(signal.SIGKILL)
                hit += 1
            proc.communicate(timeout=60)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.communicate()
    return hit


def test_sigkill_at_random_moments_then_restart_is_bit_for_bit(dam, tmp_path):
    case_dir, ref = dam
    out = tmp_path / "out"
    stepping_s = json.loads((ref / "summary.json").read_text())["wall_time_s"]
    hit = kill_and_restart(case_dir, out, kills=3, rng=random.Random(13), stepping_s=stepping_s)
    assert hit >= 2  # kills land while the run goes (a late one may find it finished)
    assert_same_as_reference(out, ref)
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "completed" and s["steps"] == json.loads((ref / "summary.json").read_text())["steps"]
    assert len(s["segments"]) >= 2


def test_checkpoints_are_periodic(dam, tmp_path, capsys, monkeypatch):
    case_dir, ref = dam
    meta, _ = checkpoint_by_id(ref)
    assert meta["version"] == sphcore.__version__ and meta["output_dir"] == str(ref.resolve())
    from sphcore.run import checkpoint

    saved, real = [], checkpoint.save
    monkeypatch.setattr(checkpoint, "save", lambda sim, d, extra=None: saved.append((sim.t, sim.step)) or real(sim, d, extra))
    # by simulated time: at the start, at the first step past each 0.02 s, at the end
    status, _, err = cli_main(capsys, "run", case_dir, "--output", tmp_path / "dt", "--progress", "off",
                              "--t-end", "0.1", *CKPT, "--set", "output.checkpoint_every_s=0")
    assert status == 0, err
    times = [t for t, _ in saved]
    assert times[0] == 0.0 and times[-1] == 0.1 and len(times) == 7, times
    for k, t in enumerate(times[1:5], start=1):  # the first step at or past k * 0.02 s
        assert 0.02 * k * (1 - 1e-12) <= t < 0.02 * k + 2e-4, times
    # by wall time: every 0.02 s of a ~0.3 s run (2,700 steps/s here)
    saved.clear()
    status, _, err = cli_main(capsys, "run", case_dir, "--output", tmp_path / "wall", "--progress", "off",
                              "--t-end", "0.1", "--set", "output.checkpoint_every_s=0.02")
    assert status == 0, err
    assert len(saved) >= 2 + 2, saved  # start, end and at least two periodic ones
    assert [step for _, step in saved] == sorted(step for _, step in saved)


# ----------------------------------------------------------------------------------------
# 3. a restart checks that it continues the same run
# ----------------------------------------------------------------------------------------


@pytest.fixture
def stopped_run(dam, tmp_path, capsys):
    """A run of the mini dam stopped at t = 0.05 s (completed there: a valid checkpoint)."""
    case_dir, _ = dam
    out = tmp_path / "out"
    status, _, err = cli_main(capsys, "run", case_dir, "--output", out, "--progress", "off", "--t-end", "0.05")
    assert status == 0, err
    return case_dir, out


@pytest.mark.parametrize("change", ["dx", "other_case", "version", "other_dir"])
def test_restart_of_another_run_is_refused_and_appends_nothing(stopped_run, tmp_path, capsys, monkeypatch, change):
    case_dir, out = stopped_run
    argv = ["run", case_dir, "--output", out, "--progress", "off", "--restart"]
    if change == "dx":
        argv += ["--set", "particles.dx=0.005"]
        needle = "particles.dx = 0.01 in the checkpoint, 0.005 now"
    elif change == "other_case":
        other = write_case(tmp_path / "other", case_with(MINI_DAM, {"viscosity.alpha": 0.3}))
        argv[1] = other
        needle = "case file"
    elif change == "version":
        monkeypatch.setattr("sphcore.run.resume.__version__", "99.0")
        needle = "written by sphcore 0.1.0, this is 99.0"
    else:  # the directory copied elsewhere: its checkpoint belongs to the first one
        moved = tmp_path / "copy"
        shutil.copytree(out, moved, symlinks=True)
        argv[3] = out = moved
        needle = "output directory"
    before = snapshot(out)
    time.sleep(0.01)
    status, _, err = cli_main(capsys, *argv)
    assert status == 2 and len(err.strip().splitlines()) == 1, err
    assert needle in err and "checkpoint.npz" in err
    assert snapshot(out) == before  # nothing appended, not a timestamp changed


# ----------------------------------------------------------------------------------------
# 4. --overwrite never deletes a user's file
# ----------------------------------------------------------------------------------------


def test_overwrite_refuses_a_copied_marker(stopped_run, tmp_path, capsys):
    case_dir, out = stopped_run
    user = tmp_path / "mine"
    user.mkdir()
    (user / "thesis.tex").write_text("years of work")
    (user / "particles.nc").write_text("mine, same name as sph's")
    shutil.copy(out / outdir.MARKER, user / outdir.MARKER)
    before = snapshot(user)
    status, _, err = cli_main(capsys, "run", case_dir, "--output", user, "--overwrite", "--progress", "off")
    assert status == 2 and "copied marker" in err
    assert snapshot(user) == before
    # a marker that is a link to a real one proves nothing either
    (user / outdir.MARKER).unlink()
    (user / outdir.MARKER).symlink_to(out / outdir.MARKER)
    status, _, err = cli_main(capsys, "run", case_dir, "--output", user, "--overwrite", "--progress", "off")
    assert status == 2 and "not written by sph" in err
    assert (user / "thesis.tex").read_text() == "years of work"


def test_overwrite_keeps_user_files_and_never_follows_links(stopped_run, tmp_path, capsys):
    case_dir, out = stopped_run
    (out / "wavefront.png").write_bytes(b"\x89PNG a user's plot")
    notes = tmp_path / "notes"
    notes.mkdir()
    (notes / "keep.txt").write_text("keep")
    # a user replaced sph's frame folder by a link to their own folder holding a same-named file
    frames = sorted(os.listdir(out / "vtu"))
    shutil.rmtree(out / "vtu")
    (notes / frames[0]).write_text("the user's, not a frame")
    (out / "vtu").symlink_to(notes)
    status, _, err = cli_main(capsys, "run", case_dir, "--output", out, "--overwrite", "--progress", "off",
                              "--t-end", "0.02")
    # the link is never followed: refused before anything is deleted or written
    assert status == 2 and "vtu is a symbolic link" in err, err
    assert (out / "wavefront.png").read_bytes() == b"\x89PNG a user's plot"
    assert (notes / "keep.txt").read_text() == "keep" and (notes / frames[0]).read_text() == "the user's, not a frame"
    assert (out / "vtu").is_symlink()


def test_overwrite_refuses_the_output_of_another_case(stopped_run, tmp_path, capsys):
    _, out = stopped_run
    other = write_case(tmp_path / "other", MINI_DAM)
    before = snapshot(out)
    status, _, err = cli_main(capsys, "run", other, "--output", out, "--overwrite", "--progress", "off")
    assert status == 2 and "holds the output of another case" in err
    assert snapshot(out) == before


def test_restart_removes_temporaries_a_kill_left_and_nothing_else(stopped_run, capsys):
    case_dir, out = stopped_run
    frame = sorted((out / "vtu").iterdir())[-1]
    left = [out / "checkpoint.tmp.npz", out / ".summary.json.tmp", frame.with_name(f".{frame.name}.tmp")]
    for p in left:
        p.write_bytes(b"half")
    (out / ".notes.tmp").write_text("a user's")
    status, _, err = cli_main(capsys, "run", case_dir, "--output", out, "--progress", "off", "--restart",
                              "--t-end", "0.06")
    assert status == 0, err
    assert not any(p.exists() for p in left)
    assert (out / ".notes.tmp").read_text() == "a user's"


def test_symlinked_output_directory_is_refused(stopped_run, tmp_path, capsys):
    case_dir, out = stopped_run
    link = tmp_path / "link"
    link.symlink_to(out)
    before = snapshot(out)
    for extra in ((), ("--overwrite",), ("--restart",)):
        status, _, err = cli_main(capsys, "run", case_dir, "--output", link, "--progress", "off", *extra)
        assert status == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert "symbolic link" in err or "checkpoint" in err
    assert snapshot(out) == before


def test_output_dir_outside_the_case_needs_the_option(tmp_path, capsys):
    case_dir = write_case(tmp_path / "case", case_with(good(), {"output.dir": "../elsewhere"}))
    status, _, err = cli_main(capsys, "run", case_dir, "--progress", "off")
    assert status == 2 and "output.dir" in err and "--output" in err
    assert not (tmp_path / "elsewhere").exists()
    status, _, err = cli_main(capsys, "run", case_dir, "--progress", "off", "--output", tmp_path / "elsewhere")
    assert status == 0, err
    assert (tmp_path / "elsewhere" / "summary.json").exists()
    marker = json.loads((tmp_path / "elsewhere" / outdir.MARKER).read_text())
    assert {"summary.json", "checkpoint.npz"} <= set(marker["files"])


def test_periodic_checkpoint_schedule():
    from sphcore.run.activities import StepInterval, periodic
    from sphcore.run.state import Clock

    def due(schedule, t, step=0):
        return schedule.due(Clock(t=t, step=step))

    clock = periodic(0, 0.1, t0=0.25)  # simulated time only, restarted at 0.25 s
    fired = [t for t in np.arange(0.26, 0.71, 0.01).round(2) if due(clock, float(t))]
    assert fired == [0.3, 0.4, 0.5, 0.6, 0.7]
    clock = periodic(0.05, None, t0=0.0)  # wall time only
    assert not due(clock, 1.0)
    time.sleep(0.06)
    assert due(clock, 1.0) and not due(clock, 1.0)
    assert not any(due(periodic(0, None, 0.0), t) for t in (0.1, 1.0, 100.0))  # both off
    both = periodic(0.05, 0.1, t0=0.0)  # either fires; a simulated-time firing restarts the wall interval
    time.sleep(0.03)
    assert due(both, 0.1) and not due(both, 0.11)
    time.sleep(0.03)
    assert not due(both, 0.12)  # 0.03 s since the last firing
    time.sleep(0.03)
    assert due(both, 0.13)
    every3 = StepInterval(3, skip_first=True)
    assert [k for k in range(10) if due(every3, 0.0, k)] == [3, 6, 9]


def test_restart_ignores_tables_of_plugins_the_run_does_not_use():
    from types import SimpleNamespace

    from sphcore.run import resume

    cfg = {"time": {"t_end": 1.0}, "plugins": {"use": ["vtu"]}, "vtu": {"every_dt": 0.01}}
    meta = {"version": sphcore.__version__, "config": resume.config_json({**cfg, "newly_installed": {"a": 1}})}
    case = SimpleNamespace(config=cfg, file=Path("case.toml"))
    resume.verify(meta, case, Path("out"), "checkpoint.npz")  # an unused plugin's table: no matter
    changed = {**cfg, "vtu": {"every_dt": 0.02}}
    with pytest.raises(sphcore.errors.CaseError, match="vtu.every_dt = 0.01 in the checkpoint, 0.02 now"):
        resume.verify(meta, SimpleNamespace(config=changed, file=Path("case.toml")), Path("out"), "checkpoint.npz")


def test_restart_accepts_a_change_of_a_plugin_option_declared_restart_true():
    """Option(restart=True) (vtu.compress) may change on --restart; other plugin keys may not."""
    from types import SimpleNamespace

    from sphcore.run import resume

    cfg = {"time": {"t_end": 1.0}, "plugins": {"use": ["vtu"]}, "vtu": {"every_dt": 0.01, "compress": True}}
    meta = {"version": sphcore.__version__, "config": resume.config_json(cfg)}
    keys = frozenset({"vtu.compress"})
    changed = {**cfg, "vtu": {"every_dt": 0.01, "compress": False}}
    resume.verify(meta, SimpleNamespace(config=changed, file=Path("case.toml"), restart_keys=keys), Path("out"),
                  "checkpoint.npz")
    with pytest.raises(sphcore.errors.CaseError, match="vtu.compress"):
        resume.verify(meta, SimpleNamespace(config=changed, file=Path("case.toml")), Path("out"), "checkpoint.npz")


def test_the_vtu_writers_compress_option_may_change_on_restart(tmp_path):
    """End to end: the case's restart_keys come from the plugins' Option(restart=True)."""
    from sphcore.run import runner

    case_dir = write_case(tmp_path / "c", plugins=["reflective", "vtu"])
    case, _ = runner.load(case_dir)
    assert "vtu.compress" in case.restart_keys and "vtu.every_dt" not in case.restart_keys
