"""The output directory's writers: one run at a time writes it (a live run refuses a second
``sph run``, ``--overwrite`` or ``--restart``), and a restart never writes through a link put
in place of one of the run's files."""

from __future__ import annotations

import json
import os
import signal
import subprocess
import time

import pytest
import xarray as xr
from conftest import write_case
from test_run_lifecycle import CASE, cli_run, sph_command

from sphcore_plugins.vtu import read_pvd


@pytest.fixture(scope="module")
def case_dir(tmp_path_factory):
    """The small dam break of tests/test_run_lifecycle.py."""
    return write_case(tmp_path_factory.mktemp("writers") / "mini_dam", CASE)


def test_a_second_writer_is_refused_while_a_run_writes_the_directory(case_dir, tmp_path, capsys):
    """--overwrite and --restart into a directory a live run writes: exit 2, one line naming
    the live run, nothing of its output touched; the live run's frames stay whole (as many
    netCDF as VTU frames), and once it has ended the directory is free again."""
    out = tmp_path / "out"
    proc = subprocess.Popen(sph_command() + ["run", str(case_dir), "--output", str(out), "--progress", "off",
                                             "--t-end", "30"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        deadline = time.monotonic() + 120
        pvd = out / "mini_dam.pvd"
        while not (pvd.exists() and len(read_pvd(pvd)) >= 3):
            assert proc.poll() is None, f"sph ended before its first frames: {proc.communicate()}"
            assert time.monotonic() < deadline, "no frames after 120 s"
            time.sleep(0.01)
        for extra in (["--overwrite"], ["--restart"]):
            status, _, err = cli_run(capsys, "run", case_dir, "--output", out, "--progress", "off", *extra)
            assert status == 2, err
            assert f"another sph run (process {proc.pid}) is writing this directory" in err, err
        assert proc.poll() is None, "the live run ended: it must outlast the refused writers"
        proc.send_signal(signal.SIGTERM)
        proc.communicate(timeout=60)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    summary = json.loads((out / "summary.json").read_text())
    assert summary["status"] == "stopped"
    with xr.open_dataset(out / "particles.nc") as ds:
        assert ds.sizes["time"] == len(read_pvd(out / "mini_dam.pvd"))
    status, _, err = cli_run(capsys, "run", case_dir, "--output", out, "--progress", "off", "--t-end",
                             str(summary["t"] + 0.02), "--restart")
    assert status == 0, err


def test_restart_refuses_to_write_through_a_link_put_in_place_of_its_file(case_dir, tmp_path, capsys):
    """After a stop, particles.nc replaced by a link to a file elsewhere: --restart refuses
    (exit 2, naming the file) and the file the link points to is not touched."""
    out = tmp_path / "out"
    status, _, err = cli_run(capsys, "run", case_dir, "--output", out, "--progress", "off", "--t-end", "0.02")
    assert status == 0, err
    elsewhere = tmp_path / "elsewhere.nc"
    (out / "particles.nc").rename(elsewhere)
    (out / "particles.nc").symlink_to(elsewhere)
    before = elsewhere.read_bytes()
    status, _, err = cli_run(capsys, "run", case_dir, "--output", out, "--progress", "off", "--t-end", "0.04",
                             "--restart")
    assert status == 2 and "particles.nc is a symbolic link" in err, err
    assert elsewhere.read_bytes() == before


def test_a_refused_writer_prints_one_line_and_leaves_the_lock_free(tmp_path):
    """The lock's refusals are one line on stderr (no 'Exception ignored' from a half-made
    lock), and a refused or failed prepare in this process leaves the directory free."""
    import subprocess as sp
    import sys as _sys

    from sphcore.errors import OutputError
    from sphcore.io import outdir

    out = tmp_path / "out"
    out.mkdir()
    holder = outdir.WriterLock(out)
    holder.record()
    code = ("import sys; from pathlib import Path; from sphcore.io import outdir; from sphcore.errors import OutputError\n"
            "try:\n    outdir.WriterLock(Path(sys.argv[1]))\nexcept OutputError as e:\n    print(e, file=sys.stderr)\n")
    res = sp.run([_sys.executable, "-c", code, str(out)], capture_output=True, text=True)
    assert res.stderr.strip() == f"{out}: another sph run (process {os.getpid()}) is writing this directory: wait for " \
                                 "it to end, or pass --output DIR"
    holder.release()
    (out / "x").write_text("a user's file, not sph's")
    with pytest.raises(OutputError):
        outdir.prepare(out, overwrite=True)  # no marker: refused before any lock is taken
    (out / "x").unlink()
    manifest = outdir.prepare(out)  # free again, and a lock file alone is an empty directory
    manifest.release()
