"""The two-writer drill: while a run writes its output directory, a second ``sph run``, a
``--overwrite`` and a ``--restart`` into the same directory are started at random moments
(seeded, so every run of the drill draws the same moments; the first run is held with
SIGSTOP while the second starts, so that how fast the machine is decides nothing). Every
one must be refused
(exit 2, one line naming the live run's process), and the first run's output must be
complete and bit for bit that of an undisturbed run: every particle frame of particles.nc,
every VTU frame and the collection, the final checkpoint's particles."""

from __future__ import annotations

import json
import random
import signal
import subprocess
import time
from pathlib import Path

import numpy as np
import pytest
from conftest import write_case
from test_run_lifecycle import FRAME_FIELDS, MINI_DAM, checkpoint_by_id, netcdf_frames, sph_command

from sphcore.io import outdir
from sphcore_plugins.vtu import read_pvd

pytestmark = pytest.mark.slow

T_END = "4.0"  # s simulated: about 23,000 steps, several seconds of stepping: time for a second writer to try
TRIALS = 20
INTRUDERS = ([], ["--overwrite"], ["--restart"])


def start(case_dir: Path, out: Path, *extra) -> subprocess.Popen:
    return subprocess.Popen(sph_command() + ["run", str(case_dir), "--output", str(out), "--progress", "off",
                                             "--t-end", T_END, *extra],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def vtu_files(out: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted((out / "vtu").iterdir())}


def assert_same_output(out: Path, ref: Path) -> None:
    meta, state = checkpoint_by_id(out)
    ref_meta, ref_state = checkpoint_by_id(ref)
    assert (meta["t"], meta["step"]) == (ref_meta["t"], ref_meta["step"])
    for key in ("id", "pos", "vel", "rho", "p"):
        assert np.array_equal(state[key], ref_state[key]), key
    nc, ref_nc = netcdf_frames(out), netcdf_frames(ref)
    for field in FRAME_FIELDS + ("id",):
        assert np.array_equal(nc[field], ref_nc[field]), field
    assert read_pvd(out / "mini_dam.pvd") == read_pvd(ref / "mini_dam.pvd")
    assert vtu_files(out) == vtu_files(ref)
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "completed" and summary["segments"][-1]["status"] == "completed"
    assert len(summary["segments"]) == 1  # nobody restarted it


def test_a_second_writer_at_any_moment_is_refused_and_changes_nothing(tmp_path):
    case_dir = write_case(tmp_path / "mini_dam", MINI_DAM)
    ref = tmp_path / "ref"
    proc = start(case_dir, ref)
    _, err = proc.communicate(timeout=600)
    assert proc.returncode == 0, err
    stepping_s = json.loads((ref / "summary.json").read_text())["wall_time_s"]
    rng = random.Random(4141)
    refused = []
    for trial in range(TRIALS):
        out = tmp_path / f"out{trial}"
        extra = INTRUDERS[trial % len(INTRUDERS)]
        first = start(case_dir, out)
        try:
            deadline = time.monotonic() + 120
            while not ((out / outdir.MARKER).exists() and (out / "checkpoint.npz").exists()):
                assert first.poll() is None, first.communicate()
                assert time.monotonic() < deadline, "the first run did not start writing"
                time.sleep(0.005)
            # a moment within the first half of the stepping; the first run is then held
            # (SIGSTOP: it keeps its lock and its state) while the second writer starts, so
            # that a slow start-up of the second on a loaded machine cannot outlast the first
            # run, and let go once the second has been answered
            time.sleep(rng.uniform(0.0, 0.5 * stepping_s))
            if first.poll() is not None:  # it ended first: hold it from the start instead
                first.communicate()
                launched = time.time_ns()
                first = start(case_dir, out, "--overwrite")
                marker = out / outdir.MARKER  # rewritten once the new run holds the lock
                while not (marker.exists() and marker.stat().st_mtime_ns >= launched):
                    assert first.poll() is None, first.communicate()
                    time.sleep(0.001)
            first.send_signal(signal.SIGSTOP)
            try:
                second = start(case_dir, out, *extra)
                said, err = second.communicate(timeout=300)
                still_running = first.poll() is None
            finally:
                first.send_signal(signal.SIGCONT)
            assert second.returncode == 2, (extra, second.returncode, still_running, said, err)
            assert err.strip() == (f"sph: error: {out}: another sph run (process {first.pid}) is writing this "
                                   "directory: wait for it to end, or pass --output DIR"), err
            _, first_err = first.communicate(timeout=600)
            assert first.returncode == 0, first_err
        finally:
            if first.poll() is None:
                first.kill()
                first.communicate()
        assert_same_output(out, ref)
        refused.append((extra, still_running))
    assert len(refused) == TRIALS and all(alive for _, alive in refused)
