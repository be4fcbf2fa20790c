"""The edges of an output directory: the marker lists only the files sph wrote (a user's
file saved there during a run survives ``--overwrite``), a hand-edited marker is no
traceback, and ``--restart`` checks every series it continues against the checkpoint
(a file deleted, cut or replaced is refused with one line naming it, exit 2, nothing
written), never continuing into a silently shorter or longer series."""

from __future__ import annotations

import json
import os

import numpy as np
import pytest
from conftest import write_case
from test_run_lifecycle import MINI_DAM, cli_run

from sphcore.io import outdir
from sphcore.run import checkpoint
from sphcore.testing import case_with
from sphcore_plugins.vtu import read_pvd

T = "0.05"  # s simulated by the first segment: 6 frames of each writer
PROBES = case_with(MINI_DAM, {"plugins.use": ["reflective", "vtu", "netcdf", "probes"],
                              "probes.every_dt": 0.01,
                              "probes.pressure": [{"name": "p0", "point": [0.3, 0.05]}]})


def listing(out) -> dict:
    """Every file under ``out`` (relative path -> bytes)."""
    return {str(p.relative_to(out)): p.read_bytes() for p in sorted(out.rglob("*")) if p.is_file()}


@pytest.fixture(scope="module")
def dam(tmp_path_factory):
    return write_case(tmp_path_factory.mktemp("edges") / "mini_dam", MINI_DAM)


@pytest.fixture(scope="module")
def probed(tmp_path_factory):
    return write_case(tmp_path_factory.mktemp("edges") / "probed", PROBES)


def first_segment(capsys, case_dir, out):
    status, _, err = cli_run(capsys, "run", case_dir, "--output", out, "--progress", "off", "--t-end", T)
    assert status == 0, err


# -- the marker -------------------------------------------------------------------------

def test_a_file_saved_into_the_directory_during_the_run_is_not_sph_and_survives_overwrite(
        dam, tmp_path, capsys, monkeypatch):
    """A note saved into the output directory while the run writes it (here: at its first
    checkpoint) is not listed in the marker, and --overwrite keeps it."""
    out = tmp_path / "out"
    save = checkpoint.save

    def save_and_note(sim, directory, extra=None):
        (out / "notes.txt").write_text("a note saved while the run goes on")
        (out / "plots").mkdir(exist_ok=True)
        (out / "plots" / "mine.png").write_bytes(b"\x89PNG")
        return save(sim, directory, extra)

    monkeypatch.setattr(checkpoint, "save", save_and_note)
    first_segment(capsys, dam, out)
    monkeypatch.setattr(checkpoint, "save", save)
    marker = json.loads((out / outdir.MARKER).read_text())
    assert "notes.txt" not in marker["files"] and "plots/mine.png" not in marker["files"]
    assert "plots" not in marker["dirs"] and "vtu" in marker["dirs"]
    assert {"checkpoint.npz", "particles.nc", "summary.json", "mini_dam.pvd"} <= set(marker["files"])
    status, _, err = cli_run(capsys, "run", dam, "--output", out, "--progress", "off", "--t-end", "0.02",
                             "--overwrite")
    assert status == 0, err
    assert (out / "notes.txt").read_text() == "a note saved while the run goes on"
    assert (out / "plots" / "mine.png").read_bytes() == b"\x89PNG"


def test_the_marker_records_what_sph_wrote_not_what_changed(tmp_path):
    """In one process: a file written through sphcore.io.atomic is listed, a file touched
    by anyone else in the same second is not, and a file outside the directory never."""
    from sphcore.io.atomic import write_text_atomically

    out = tmp_path / "out"
    manifest = outdir.prepare(out)
    try:
        (out / "sub").mkdir()
        write_text_atomically(out / "sub" / "sph.txt", "sph")
        (out / "user.txt").write_text("user")
        write_text_atomically(tmp_path / "elsewhere.txt", "not in the directory")
        manifest.update()
    finally:
        manifest.release()
    marker = outdir.read_marker(out)
    assert marker["files"] == ["sub/sph.txt"] and marker["dirs"] == ["sub"]


@pytest.mark.parametrize("entries", [[1, None, ["a"], {"b": 2}, True, 2.5], [["particles.nc"]], [{}], ["", "\0x"]])
def test_a_marker_with_entries_that_are_not_paths_is_no_traceback(dam, tmp_path, capsys, entries):
    """--overwrite and --restart over a marker whose lists hold numbers, nulls, lists or
    tables: those entries name no file; sph's listed files are replaced, nothing else."""
    out = tmp_path / "out"
    first_segment(capsys, dam, out)
    marker = json.loads((out / outdir.MARKER).read_text())
    marker["files"] = marker["files"] + entries
    marker["dirs"] = marker["dirs"] + entries
    (out / outdir.MARKER).write_text(json.dumps(marker))
    (out / "mine.txt").write_text("mine")
    status, _, err = cli_run(capsys, "run", dam, "--output", out, "--progress", "off", "--t-end", "0.07", "--restart")
    assert status == 0, err
    marker = json.loads((out / outdir.MARKER).read_text())
    marker["files"] = marker["files"] + entries
    (out / outdir.MARKER).write_text(json.dumps(marker))
    status, _, err = cli_run(capsys, "run", dam, "--output", out, "--progress", "off", "--t-end", "0.02",
                             "--overwrite")
    assert status == 0, err
    assert "Traceback" not in err and (out / "mine.txt").read_text() == "mine"


# -- restart against the checkpoint -----------------------------------------------------

def _delete(out, name):
    (out / name).unlink()


def _cut(out, name, fraction=0.6):
    path = out / name
    os.truncate(path, int(path.stat().st_size * fraction))


def _garbage(out, name):
    (out / name).write_bytes(b"not a netCDF file at all" * 10)


def _empty(out, name):
    (out / name).write_bytes(b"")


def _drop_frame(out, name):
    """The collection without its third frame."""
    pvd = out / name
    text = pvd.read_text().splitlines(keepends=True)
    rows = [i for i, line in enumerate(text) if "<DataSet" in line]
    del text[rows[2]]
    pvd.write_text("".join(text))


def _other_times(out, name):
    """particles.nc of a run with another schedule (a file put back from elsewhere)."""
    import netCDF4

    with netCDF4.Dataset(out / name, "a") as ds:
        ds["time"][3] = ds["time"][3] + 1e-3


BREAKS = {
    "particles.nc deleted": ("particles.nc", _delete),
    "particles.nc cut": ("particles.nc", _cut),
    "particles.nc garbage": ("particles.nc", _garbage),
    "particles.nc empty": ("particles.nc", _empty),
    "particles.nc other times": ("particles.nc", _other_times),
    "pvd deleted": ("mini_dam.pvd", _delete),
    "pvd without a frame": ("mini_dam.pvd", _drop_frame),
    "pvd garbage": ("mini_dam.pvd", _garbage),
    "vtu frame deleted": ("vtu/mini_dam_000002.vtu", _delete),
    "vtu frame cut": ("vtu/mini_dam_000002.vtu", _cut),
    "probes.nc deleted": ("probes.nc", _delete),
    "probes.nc cut": ("probes.nc", lambda out, name: _cut(out, name, 0.8)),
}


@pytest.mark.parametrize("what", list(BREAKS))
def test_restart_refuses_a_series_that_does_not_match_its_checkpoint(probed, tmp_path, capsys, what):
    """A file of the run deleted, cut, emptied, garbled or holding other frames: --restart
    exits 2 with one line naming that file and writes nothing (every file as it was)."""
    name, breaks = BREAKS[what]
    out = tmp_path / "out"
    first_segment(capsys, probed, out)
    breaks(out, name)
    before = listing(out)
    status, stdout, err = cli_run(capsys, "run", probed, "--output", out, "--progress", "off", "--t-end", "0.1",
                                  "--restart")
    assert status == 2, (stdout, err)
    assert err.count("\n") == 1 and name in err and "Traceback" not in err, err
    assert listing(out) == before


def test_frames_after_the_checkpoint_are_dropped_and_a_restart_continues_the_series(probed, tmp_path, capsys):
    """The frames a run wrote after its last checkpoint (a kill) are not an error: the
    series is cut back to the checkpoint and continued, one frame per time, in order."""
    out = tmp_path / "out"
    first_segment(capsys, probed, out)
    status, _, err = cli_run(capsys, "run", probed, "--output", out, "--progress", "off", "--t-end", "0.1",
                             "--restart")
    assert status == 0, err
    import netCDF4

    with netCDF4.Dataset(out / "particles.nc") as ds:
        t = np.asarray(ds["time"][:])
    assert len(t) == 11 and np.all(np.diff(t) > 0)
    assert [f[0] for f in read_pvd(out / "mini_dam.pvd")] == t.tolist()
