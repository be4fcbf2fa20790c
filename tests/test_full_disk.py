"""A full disk at every write point: the run exits 1 with one line, the last good files stay
readable (no half file, no temporary), and ``--restart`` ends with the uninterrupted run's
end state. The disk fills through injected ENOSPC errors here, in this process; a real full
disk (a small tmpfs) is benchmarks/faults/full_disk.py."""

from __future__ import annotations

import errno
import json
import os
from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from conftest import write_case
from test_run_lifecycle import MINI_DAM, checkpoint_by_id, stray_files
from test_run_survival import CKPT, assert_same_as_reference, cli_main, mini_dam_and_reference

from sphcore.testing import case_with


@pytest.fixture(scope="module")
def dam(tmp_path_factory):
    """The mini dam break and its uninterrupted run (test_run_survival.mini_dam_and_reference)."""
    return mini_dam_and_reference(tmp_path_factory.mktemp("full_disk"))


def _enospc(path=""):
    return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))


def inject_full_disk(monkeypatch, point: str, after: int):
    """Make the ``after``-th+1 write at ``point`` fail as on a full disk (half a file written first)."""
    import pathlib

    calls = {"n": 0}

    def due():
        calls["n"] += 1
        return calls["n"] > after

    if point == "frame":  # the VTU frames: the vtu plugin writes each with Path.write_text
        real = pathlib.Path.write_text

        def write(self, *a, **k):
            if ".vtu" in self.name and due():
                real(self, "<VTKFile half")
                raise _enospc(self)
            return real(self, *a, **k)
        monkeypatch.setattr(pathlib.Path, "write_text", write)
    elif point == "checkpoint":
        real = np.savez

        def savez(f, *a, **k):
            if due():
                f.write(b"PK\x03\x04 half")
                raise _enospc(getattr(f, "name", ""))
            return real(f, *a, **k)
        monkeypatch.setattr(np, "savez", savez)
    elif point in ("summary", "gauge"):
        name = "summary" if point == "summary" else "front.csv"
        real_text, real_savetxt = pathlib.Path.write_text, np.savetxt

        def write_text(self, *a, **k):
            if name in self.name and due():
                real_text(self, "half")
                raise _enospc(self)
            return real_text(self, *a, **k)

        def savetxt(fname, *a, **k):
            if name in str(fname) and due():
                Path(fname).write_text("half")
                raise _enospc(fname)
            return real_savetxt(fname, *a, **k)
        monkeypatch.setattr(pathlib.Path, "write_text", write_text)
        monkeypatch.setattr(np, "savetxt", savetxt)
    return calls


@pytest.mark.parametrize("point, after", [("frame", 6), ("checkpoint", 3), ("summary", 0), ("gauge", 0)])
def test_full_disk_at_every_write_point(dam, tmp_path, capsys, monkeypatch, point, after):
    case_dir, ref = dam
    out = tmp_path / "out"
    argv = ["run", case_dir, "--output", out, "--progress", "off", *CKPT]
    if point == "gauge":  # the front gauge writes front.csv with the summary
        case_dir = write_case(tmp_path / "gauged", case_with(MINI_DAM, {"plugins.use": ["reflective", "vtu", "netcdf",
                                                                                        "front_gauge"]}))
        argv[1] = case_dir
    with monkeypatch.context() as m:
        calls = inject_full_disk(m, point, after)
        status, stdout, err = cli_main(capsys, *argv)
    assert calls["n"] > after  # the fault was hit
    assert status == 1, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("sph: error: ") and "No space left on device" in lines[0], err
    assert stray_files(out) == []  # no half file, no .tmp
    meta, _ = checkpoint_by_id(out)  # the last good checkpoint loads
    with xr.open_dataset(out / "particles.nc") as ds:  # the frames written are readable
        assert np.all(np.isfinite(ds["time"].values)) and ds["time"].values[-1] <= max(meta["t"], 0.3)
    if point == "gauge":
        assert not (out / "front.csv").exists() or "half" not in (out / "front.csv").read_text()
    # restartable, to the uninterrupted run's end state
    status, _, err = cli_main(capsys, *argv, "--restart")
    assert status == 0, err
    if point != "gauge":
        assert_same_as_reference(out, ref)
    s = json.loads((out / "summary.json").read_text())
    assert s["status"] == "completed" and s["t"] == 0.3


def test_full_disk_at_the_netcdf_header_leaves_no_unreadable_file(dam, tmp_path, capsys, monkeypatch):
    """The disk fills while particles.nc's header is synced (its variables declared, the
    particle ids not yet on disk): the run exits 1 with one line and leaves no particles.nc
    (a file that cannot be read as frames), and --restart finishes with the uninterrupted
    run's end state."""
    import netCDF4

    case_dir, ref = dam
    out = tmp_path / "out"
    argv = ["run", case_dir, "--output", out, "--progress", "off", *CKPT]
    calls = {"n": 0}

    class FullAtHeader(netCDF4.Dataset):
        def sync(self):
            if self.filepath().endswith("particles.nc") and "id" in self.variables and calls["n"] == 0:
                calls["n"] += 1
                raise _enospc(self.filepath())
            return super().sync()

    with monkeypatch.context() as m:
        m.setattr(netCDF4, "Dataset", FullAtHeader)
        status, _, err = cli_main(capsys, *argv)
    assert calls["n"] == 1  # the fault was hit
    assert status == 1, err
    lines = err.strip().splitlines()
    assert len(lines) == 1 and "cannot write the netCDF header: No space left on device" in lines[0], err
    assert not (out / "particles.nc").exists() and stray_files(out) == []
    checkpoint_by_id(out)  # the last good checkpoint loads
    status, _, err = cli_main(capsys, *argv, "--restart")
    assert status == 0, err
    assert_same_as_reference(out, ref)
