"""Runs that survive anything (issue 13): every malformed input a clean exit 2 on which
``sph check`` and ``sph run`` agree, SIGKILL at random moments then ``--restart`` bit for
bit, a restart that refuses another run's checkpoint, an overwrite that never deletes a
user's file, and a full disk at every write point.

The fuzz calls ``sphcore.cli.main`` in this process (hundreds of interpreters would take
minutes); a few variants and the kill test run ``sph`` as a real process.
"""

from __future__ import annotations

import errno
import json
import os
import random
import shutil
import signal
import subprocess
import time
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

import numpy as np
import pytest
import xarray as xr
from conftest import GOOD_CASE, write_case
from core_cases import spheres
from test_run_lifecycle import CASE, FRAME_FIELDS, checkpoint_by_id, netcdf_frames, snapshot, sph, sph_command, stray_files

import sphcore
from sphcore import cli, defaults, outdir, pluginhost

# ----------------------------------------------------------------------------------------
# helpers
# ----------------------------------------------------------------------------------------


def toml_value(v) -> str:
    if isinstance(v, bool):
        return "true" if v else "false"
    if isinstance(v, (int, float)):
        return repr(v)
    if isinstance(v, str):
        return json.dumps(v)  # a TOML basic string for the values used here
    if isinstance(v, list):
        return "[" + ", ".join(toml_value(x) for x in v) + "]"
    if isinstance(v, dict):
        return "{" + ", ".join(f"{k} = {toml_value(x)}" for k, x in v.items()) + "}"
    raise TypeError(v)


def to_toml(raw: dict) -> str:
    """TOML text of a case dict: top-level values (blocks as inline tables), then tables."""
    lines = [f"{k} = {toml_value(v)}" for k, v in raw.items() if not isinstance(v, dict)]
    for section, table in raw.items():
        if isinstance(table, dict):
            lines += ["", f"[{section}]"] + [f"{k} = {toml_value(v)}" for k, v in table.items()]
    return "\n".join(lines) + "\n"


GOOD = tomllib.loads(GOOD_CASE)


def cli_main(capsys, *argv) -> tuple[int, str, str]:
    status = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


# ----------------------------------------------------------------------------------------
# 1. malformed inputs: generated from the option declarations, plus a table of the rest
# ----------------------------------------------------------------------------------------

WRONG_TYPE = {
    "bool": [1, "yes"],
    "int": [1.5, "3", True],
    "float": ["1.0", True, [1.0]],
    "str": [5, ["a"]],
    "vector": ["1,2", [1.0, "a"], 3.0],
    "str_list": ["vtu", [1]],
    "table_list": [1, [1]],
    "list": ["x", 2.0],
}


def bad_values(opt) -> list:
    """Wrong types and out-of-range values for one declared option."""
    values = list(WRONG_TYPE[opt.kind])
    if opt.kind in ("int", "float"):
        if opt.positive:
            values += [0, -1]
        if opt.min is not None:
            values.append(opt.min - 1)
        if "max" in opt.extra:
            values.append(opt.extra["max"] + 1)
        values.append(2**63)  # beyond int64
        if opt.kind == "float" and (opt.positive or (opt.min is not None and opt.min >= 0)):
            values.append(5e-324)  # subnormal
    if opt.choices:
        values.append("no_such_choice")
    return values


def declared_variants() -> list[tuple[str, dict]]:
    """(id, raw case dict) for every declared option and every bad value of it."""
    out = []
    tables = {s: t for s, t in defaults.CORE.items() if isinstance(t, dict)}
    tables.update(pluginhost.option_schemas())
    for section, schema in tables.items():
        for key, opt in schema.items():
            for v in bad_values(opt):
                raw = json.loads(json.dumps(GOOD))
                raw.setdefault(section, {})[key] = v
                out.append((f"{section}.{key}={v!r}", raw))
    for key, opt in defaults.BLOCK.items():
        for v in bad_values(opt):
            raw = json.loads(json.dumps(GOOD))
            raw["blocks"][0][key] = v
            out.append((f"blocks[0].{key}={v!r}", raw))
    for key, opt in defaults.PLANE.items():
        for v in bad_values(opt):
            raw = json.loads(json.dumps(GOOD))
            raw["domain"]["planes"] = [{"normal": [0.0, 1.0], "point": [0.0, 0.0], key: v}]
            out.append((f"domain.planes[0].{key}={v!r}", raw))
    return out


def _edit(**sections) -> bytes:
    raw = json.loads(json.dumps(GOOD))
    for section, table in sections.items():
        raw.setdefault(section, {}).update(table)
    return to_toml(raw).encode()


# (id, case.toml bytes or a callable making the case directory, extra argv)
SPECIAL = [
    ("non-utf8", b'[case]\nname = "\xff\xfe"\n', []),
    ("binary", bytes(range(256)) * 40, []),
    ("nested-arrays-2000", ("a = " + "[" * 2000 + "]" * 2000 + "\n").encode(), []),
    ("nested-tables-2000", ("[" + ".".join(["t"] * 2000) + "]\n").encode(), []),
    ("inline-tables-2000", ("a = " + "{b = " * 2000 + "1" + "}" * 2000 + "\n").encode(), []),
    ("too-large", b"# " + b"x" * (2 << 20) + b"\n" + GOOD_CASE.encode(), []),
    ("empty", b"", []),
    ("syntax-error", b"[time\nt_end = 1.0\n", []),
    ("unknown-section", GOOD_CASE.encode() + b"\n[nonsense]\na = 1\n", []),
    ("h-over-dx-tiny", _edit(kernel={"h_over_dx": 1e-12}), []),
    ("h-over-dx-huge", _edit(kernel={"h_over_dx": 1e6}), []),
    ("rho0-subnormal", _edit(fluid={"rho0": 5e-324}), []),
    ("dim-beyond-int64", _edit(case={"dim": 99999999999999999999}), []),
    ("count-beyond-int64", to_toml({**GOOD, "blocks": [{"min": [0.2, 0.2], "count": [10**30, 2]}]}).encode(), []),
    ("dx-1e-6-memory", _edit(particles={"dx": 1e-6}), []),
    ("count-1e10-memory", to_toml({**GOOD, "blocks": [{"min": [0.0, 0.0], "count": [100000, 100000]}],
                                   "particles": {"dx": 1e-5}}).encode(), []),
    ("memory-limit-key", _edit(particles={"memory_limit_gib": 1e-6}), []),
    ("dt-1e-300", _edit(time={"dt": 1e-300}), []),
    ("dt-too-many-steps", _edit(time={"dt": 1e-12, "t_end": 1.0}), []),
    ("output-dir-parent", _edit(output={"dir": "../other"}), []),
    ("output-dir-absolute", _edit(output={"dir": "/tmp/sph-absolute-output"}), []),
    ("output-dir-dot", _edit(output={"dir": "."}), []),
    ("domain-inverted", _edit(domain={"min": [1.0, 1.0], "max": [0.0, 0.0]}), []),
    # values in range one by one whose physics leaves the float range: found before a step
    ("gravity-1e300", _edit(physics={"gravity": [0.0, -1e300, 0.0]}), []),
    ("nu-1e300", _edit(fluid={"nu": 1e300}), []),
    ("rho0-1e-300", _edit(fluid={"rho0": 1e-300}), []),
    ("rho0-gamma-overflow", _edit(fluid={"rho0": 1e6}, eos={"gamma": 100.0}), []),
    ("p-background-1e300", _edit(eos={"p_background": 1e300}), []),
    ("t-end-1e300", _edit(time={"t_end": 1e300}), []),
    ("set-not-a-number", GOOD_CASE.encode(), ["--set", "particles.dx=abc"]),
    ("set-no-section", GOOD_CASE.encode(), ["--set", "dx=0.1"]),
    ("set-deep", GOOD_CASE.encode(), ["--set", "time.t_end=" + "[" * 2000 + "]" * 2000]),
    ("set-unknown", GOOD_CASE.encode(), ["--set", "time.nonsense=1"]),
    ("t-end-negative", GOOD_CASE.encode(), ["--t-end", "-1"]),
    ("dev-zero-link", "dev-zero", []),
    ("case-is-directory", "directory", []),
    ("spheres-no-dt", "spheres", []),
]


def make_case(root: Path, content) -> Path:
    d = root / "case"
    d.mkdir(parents=True)
    if content == "dev-zero":
        (d / "case.toml").symlink_to("/dev/zero")
    elif content == "directory":
        (d / "case.toml").mkdir()
    elif content == "spheres":  # no SPH, no gravity, no velocity: nothing sizes the step
        shutil.rmtree(d)
        d = spheres(root, dt=None, name="case")
    else:
        (d / "case.toml").write_bytes(content)
    return d


def all_variants():
    return ([pytest.param(("declared", raw), [], id=i) for i, raw in declared_variants()]
            + [pytest.param(("special", c), argv, id=i) for i, c, argv in SPECIAL])


def test_enough_variants():
    assert len(declared_variants()) + len(SPECIAL) >= 100


def _check_and_run_agree(capsys, root: Path, case_dir: Path, argv: list) -> str:
    """check and run both exit 2 with the same one line; nothing is written."""
    before = snapshot(root)
    status_c, out_c, err_c = cli_main(capsys, "check", case_dir, *argv)
    status_r, out_r, err_r = cli_main(capsys, "run", case_dir, "--progress", "off", *argv)
    assert (status_c, status_r) == (2, 2), (err_c, err_r)
    for err in (err_c, err_r):
        lines = err.strip().splitlines()
        assert len(lines) == 1 and lines[0].startswith("sph: error: "), err
        assert "Traceback" not in err
    assert err_c == err_r  # the same validation, the same message
    assert "ok" not in out_c
    assert snapshot(root) == before, "something was written"
    assert not Path("/tmp/sph-absolute-output").exists()
    return err_r


@pytest.mark.parametrize("variant, argv", all_variants())
def test_malformed_input_exits_2_and_check_agrees_with_run(tmp_path, capsys, variant, argv):
    how, content = variant
    case_dir = make_case(tmp_path, to_toml(content).encode() if how == "declared" else content)
    err = _check_and_run_agree(capsys, tmp_path, case_dir, argv)
    # the line names where (the file or the option) and what was expected
    where = "--set" if "--set" in argv else "--t-end" if "--t-end" in argv else str(case_dir / "case.toml")
    assert f"sph: error: {where}: " in err, err


def test_errors_name_the_key_and_the_numbers(tmp_path, capsys):
    case_dir = make_case(tmp_path, _edit(particles={"dx": 1e-6}))
    err = _check_and_run_agree(capsys, tmp_path, case_dir, [])
    assert ": particles.dx: dx = 1e-06 m gives 4e+10 particles" in err and "GiB" in err and "memory_limit_gib" in err
    case_dir = make_case(tmp_path / "b", GOOD_CASE.encode())
    err = _check_and_run_agree(capsys, tmp_path, case_dir, ["--set", "fluid.rho0=-3"])
    assert err.strip() == "sph: error: --set: fluid.rho0: expected a positive number, got -3.0"
    err = _check_and_run_agree(capsys, tmp_path, case_dir, ["--t-end", "0"])
    assert err.startswith("sph: error: --t-end: time.t_end: expected a positive number")
    case_dir = make_case(tmp_path / "c", b"[time\nt_end = 1.0\n")
    err = _check_and_run_agree(capsys, tmp_path, case_dir, [])
    assert ": line 1, column 6: not valid TOML" in err  # the position, not "-"
    case_dir = make_case(tmp_path / "d", _edit(time={"dt": 1e-300}))
    err = _check_and_run_agree(capsys, tmp_path, case_dir, [])
    assert "time.dt" in err and "round-off" in err


@pytest.mark.parametrize("content", [b'\xff\xfe[case]\n', "dev-zero", ("a = " + "[" * 2000 + "]" * 2000).encode()],
                         ids=["non-utf8", "dev-zero", "nested"])
def test_malformed_input_as_a_process(tmp_path, content):
    case_dir = make_case(tmp_path, content)
    for command in ("check", "run"):
        res, wall = sph(command, case_dir, timeout=60)
        assert res.returncode == 2 and "Traceback" not in res.stderr, res.stderr
        assert len(res.stderr.strip().splitlines()) == 1 and res.stderr.startswith("sph: error: ")
        assert wall < 30  # /dev/zero is not read until memory runs out
    assert sorted(p.name for p in case_dir.iterdir()) == ["case.toml"]


def test_check_prints_the_resolved_output_path(tmp_path, capsys):
    case_dir = write_case(tmp_path / "case", GOOD_CASE)
    status, out, _ = cli_main(capsys, "check", case_dir)
    assert status == 0 and out.strip().endswith(f"output: {(case_dir / 'output').resolve()}")
    status, out, _ = cli_main(capsys, "check", case_dir, "--output", tmp_path / "elsewhere")
    assert status == 0 and out.strip().endswith(f"output: {(tmp_path / 'elsewhere').resolve()}")
    assert not (tmp_path / "elsewhere").exists() and not (case_dir / "output").exists()


# ----------------------------------------------------------------------------------------
# 2. SIGKILL at random moments, then --restart: bit for bit the uninterrupted run
# ----------------------------------------------------------------------------------------

CKPT = ["--set", "output.checkpoint_every_dt=0.02"]


@pytest.fixture(scope="module")
def dam(tmp_path_factory):
    """The mini dam break of test_run_lifecycle and its uninterrupted run (in this process)."""
    root = tmp_path_factory.mktemp("survival")
    case_dir = write_case(root / "mini_dam", CASE)
    ref = root / "ref"
    assert cli.main(["run", str(case_dir), "--output", str(ref), "--progress", "off", *CKPT]) == 0
    return case_dir, ref


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
    from sphcore import checkpoint

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
        other = write_case(tmp_path / "other", CASE.replace("alpha = 0.2", "alpha = 0.3"))
        argv[1] = other
        needle = "case file"
    elif change == "version":
        monkeypatch.setattr("sphcore.resume.__version__", "99.0")
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
    other = write_case(tmp_path / "other", CASE)
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
    case_dir = write_case(tmp_path / "case", GOOD_CASE + '\n[output]\ndir = "../elsewhere"\n')
    status, _, err = cli_main(capsys, "run", case_dir, "--progress", "off")
    assert status == 2 and "output.dir" in err and "--output" in err
    assert not (tmp_path / "elsewhere").exists()
    status, _, err = cli_main(capsys, "run", case_dir, "--progress", "off", "--output", tmp_path / "elsewhere")
    assert status == 0, err
    assert (tmp_path / "elsewhere" / "summary.json").exists()
    marker = json.loads((tmp_path / "elsewhere" / outdir.MARKER).read_text())
    assert {"summary.json", "checkpoint.npz"} <= set(marker["files"])


# ----------------------------------------------------------------------------------------
# 5. a full disk at every write point: exit 1, the last good files readable, restartable
# ----------------------------------------------------------------------------------------


def _enospc(path=""):
    return OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))


def inject_full_disk(monkeypatch, point: str, after: int):
    """Make the ``after``-th+1 write at ``point`` fail as on a full disk (half a file written first)."""
    import pathlib

    import sphcore_plugins.vtu as vtu

    calls = {"n": 0}

    def due():
        calls["n"] += 1
        return calls["n"] > after

    if point == "frame":
        real = vtu.meshio.write

        def write(path, *a, **k):
            if due():
                Path(path).write_bytes(b"<VTKFile half")
                raise _enospc(path)
            return real(path, *a, **k)
        monkeypatch.setattr(vtu.meshio, "write", write)
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
        case_dir = write_case(tmp_path / "gauged", CASE.replace('"netcdf"]', '"netcdf", "front_gauge"]'))
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


# ----------------------------------------------------------------------------------------
# 6. set-up interrupted, compilation announced, a step that cannot advance time
# ----------------------------------------------------------------------------------------


def test_ctrl_c_during_set_up_is_one_line_and_writes_nothing(tmp_path, capsys, monkeypatch):
    case_dir = write_case(tmp_path / "case", GOOD_CASE)

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr("sphcore.simulation.Simulation", interrupted)
    before = snapshot(tmp_path)
    status, _, err = cli_main(capsys, "run", case_dir, "--progress", "off")
    assert status == 128 + signal.SIGINT
    assert err.strip() == "sph: error: interrupted during set-up; nothing written"
    assert snapshot(tmp_path) == before


def test_first_run_says_it_compiles(tmp_path, capsys, monkeypatch):
    case_dir = write_case(tmp_path / "case", GOOD_CASE)
    monkeypatch.setattr("sphcore.runner.kernels_cached", lambda: False)
    status, _, err = cli_main(capsys, "run", case_dir, "--progress", "log")
    assert status == 0 and "[sph] compiling kernels, once" in err
    monkeypatch.setattr("sphcore.runner.kernels_cached", lambda: True)
    status, _, err = cli_main(capsys, "run", case_dir, "--progress", "log", "--output", tmp_path / "again")
    assert status == 0 and "compiling" not in err


def test_kernels_cached_finds_the_cache():
    from sphcore import runner

    assert runner.kernels_cached()  # the runs above compiled, and numba cached, the force kernel


def test_a_step_below_the_round_off_of_t_is_an_instability(tmp_path):
    from conftest import make_sim

    from sphcore.errors import Instability

    sim = make_sim(write_case(tmp_path / "case", GOOD_CASE), ["time.dt=1e-4", "time.t_end=1e20"])
    sim.t = 1e16  # ulp(1e16) = 2: t + 1e-4 == t
    with pytest.raises(Instability, match="below the round-off of t"):
        sim.advance()


def test_checkpoint_clock():
    from sphcore.resume import CheckpointClock

    clock = CheckpointClock(0, 0.1, t0=0.25)  # simulated time only, restarted at 0.25 s
    fired = [t for t in np.arange(0.26, 0.71, 0.01).round(2) if clock.due(float(t))]
    assert fired == [0.3, 0.4, 0.5, 0.6, 0.7]
    clock = CheckpointClock(0.05, None, t0=0.0)  # wall time only
    assert not clock.due(1.0)
    time.sleep(0.06)
    assert clock.due(1.0) and not clock.due(1.0)
    assert not any(CheckpointClock(0, None, 0.0).due(t) for t in (0.1, 1.0, 100.0))  # both off


def test_eta_starts_after_the_first_step():
    import io
    import re
    from types import SimpleNamespace

    from sphcore.progress import Progress

    stream = io.StringIO()
    bar = Progress(t_end=1.0, n=10, mode="log", interval_s=0.0, stream=stream)
    time.sleep(1.2)  # the first step compiles the kernels
    sim = SimpleNamespace(step=1, t=0.1, dt=0.1)
    bar.update(sim)  # no line: the clock starts now
    assert stream.getvalue() == ""
    time.sleep(0.05)
    sim.step, sim.t = 5, 0.55  # half of what is left, in 0.05 s
    bar.update(sim)
    eta = float(re.search(r"ETA (\S+) s", stream.getvalue()).group(1))
    assert eta == 0.0  # ~0.05 s to go; counting the 1.2 s of compiling would say >= 1 s
