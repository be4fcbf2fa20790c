"""Case loading and validation, through the API and the ``sph`` CLI.

Every malformed case is a :class:`CaseError` naming the file and the key; ``sph run`` and
``sph check`` then exit with status 2, print one line on stderr naming file and key, and
create no output directory.
"""

from __future__ import annotations

import json
import re
from pathlib import Path

import pytest
from conftest import make_sim, write_case
from core_cases import good

from sphcore import cli
from sphcore.errors import CaseError
from sphcore.physics.kernels import CUBIC_SPLINE
from sphcore.run import runner
from sphcore.testing import case_with


def _edit(changes: dict) -> dict:
    """The good case (core_cases.good) with ``changes`` (see sphcore.testing.case_with)."""
    return case_with(good(), changes)


# (id, case, --set overrides, the key the error must name)
MALFORMED = [
    ("unknown-section", _edit({"bogus.x": 1}), [], "bogus"),
    ("unknown-key", _edit({"time.t_ned": 1.0}), [], "time.t_ned"),
    ("unknown-block-key", _edit({"blocks[0].velocty": [1.0, 0.0]}), [], "blocks[0].velocty"),
    ("wrong-type-float", _edit({"particles.dx": "small"}), [], "particles.dx"),
    ("wrong-type-bool", _edit({"physics.sph": 1}), [], "physics.sph"),
    ("wrong-type-section", _edit({"time": 0.002}), [], "time"),
    ("wrong-type-choice", _edit({"kernel.name": "gaussian"}), [], "kernel.name"),
    ("dx-zero", _edit({"particles.dx": 0.0}), [], "particles.dx"),
    ("dx-negative", _edit({"particles.dx": -0.02}), [], "particles.dx"),
    ("t_end-zero", _edit({"time.t_end": 0.0}), [], "time.t_end"),
    ("t_end-negative", _edit({"time.t_end": -1.0}), [], "time.t_end"),
    ("dim-4", _edit({"case.dim": 4}), [], "case.dim"),
    ("rho-bounds-crossed", _edit({"checks": {"rho_min": 1.2, "rho_max": 1.1}}), [], "checks.rho_max"),
    ("no-blocks", _edit({"blocks": None}), [], "blocks"),
    ("block-without-max", _edit({"blocks[0].max": None}), [], "blocks[0].max"),
    ("block-count-wrong", _edit({"blocks[0].max": None, "blocks[0].count": [10, 0]}), [], "blocks[0].count"),
    ("block-max-below-min", _edit({"blocks[0].max": [0.4, 0.1]}), [], "blocks[0].max"),
    ("domain-max-below-min", _edit({"domain.max": [1.0, -1.0]}), [], "domain.max"),
    ("domain-min-alone", _edit({"domain.max": None}), [], "domain.max"),
    ("vector-wrong-length", _edit({"domain.min": [0.0, 0.0, 0.0]}), [], "domain.min"),
    ("velocity-wrong-length", _edit({"blocks[0].velocity": [1.0]}), [], "blocks[0].velocity"),
    ("gravity-too-short", _edit({"physics.gravity": [0.0]}), [], "physics.gravity"),
    ("planes-bound-nothing", _edit({"domain": {"planes": [{"normal": [0.0, 1.0], "point": [0.0, 0.0]}]}}), [],
     "domain.planes"),
    ("planes-open-wedge", _edit({"domain": {"planes": [{"normal": [0.0, 1.0], "point": [0.0, 0.0]},
                                                       {"normal": [1.0, 0.0], "point": [0.0, 0.0]},
                                                       {"normal": [-1.0, 1.0], "point": [1.0, 0.0]}]}}),
     [], "domain.planes"),
    ("plane-zero-normal", _edit({"domain.planes": [{"normal": [0.0, 0.0], "point": [0.0, 0.0]}]}),
     [], "domain.planes[0].normal"),
    ("no-walls", _edit({"domain": None}), [], "domain"),
    ("unknown-plugin", _edit({"plugins.use": ["no_such_plugin"]}), [], "plugins.use"),
    ("set-bad-value", good(), ["time.t_end=abc"], "time.t_end"),
    ("set-negative-dx", good(), ["particles.dx=-1"], "particles.dx"),
    ("set-unknown-key", good(), ["time.t_ned=1.0"], "time.t_ned"),
    ("set-wrong-length", good(), ["case.dim=3"], "domain.min"),
]

# Found when the particles are built (Simulation / sph check), not by the schema.
MALFORMED_AT_BUILD = [
    ("particles-outside-domain", _edit({"blocks[0].max": [1.3, 0.4]}), [], "blocks[0]"),
    ("particles-outside-plane",  # the extra wall x + y <= 0.6 cuts through the block
     _edit({"domain.planes": [{"normal": [-1.0, -1.0], "point": [0.3, 0.3]}]}),
     [], "blocks[0]"),
    ("empty-block", _edit({"particles.dx": 0.5}), [], "blocks[0]"),
    ("no-sound-speed-without-gravity", _edit({"physics.gravity": [0.0, 0.0]}), [], "eos.c0"),
]

ALL_MALFORMED = MALFORMED + MALFORMED_AT_BUILD


def _params(rows):
    """pytest params, one per malformed-case row."""
    return [pytest.param(*row[1:], id=row[0]) for row in rows]


def _source(case_dir: Path, key: str, overrides=()) -> str:
    """Where the error must point: the --set option when it set the key, else case.toml."""
    if any(key == o.split("=")[0] for o in overrides):
        return "--set"
    return str(case_dir / "case.toml")


def _assert_names_file_and_key(err: CaseError, case_dir: Path, key: str, overrides=()):
    assert err.file == _source(case_dir, key, overrides)
    assert err.key == key
    text = str(err)
    assert f"{err.file}: {key}: " in text
    assert err.expected  # says what was expected


def _cli(capsys, *argv):
    status = cli.main([str(a) for a in argv])
    out, err = capsys.readouterr()
    return status, out, err


def _assert_one_line_error(err: str, *needles):
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    assert lines[0].startswith("sph: error: ")
    for needle in needles:
        assert str(needle) in lines[0]


@pytest.mark.parametrize("case, overrides, key", _params(ALL_MALFORMED))
def test_malformed_case_is_a_case_error(tmp_path, case, overrides, key):
    case_dir = write_case(tmp_path / "case", case)
    with pytest.raises(CaseError) as info:
        make_sim(case_dir, overrides)
    _assert_names_file_and_key(info.value, case_dir, key, overrides)


@pytest.mark.parametrize("case, overrides, key",
                         _params(ALL_MALFORMED))
def test_cli_run_rejects_malformed_case(tmp_path, capsys, case, overrides, key):
    case_dir = write_case(tmp_path / "case", case)
    before = sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*"))
    sets = [a for o in overrides for a in ("--set", o)]
    status, out, err = _cli(capsys, "run", case_dir, *sets)
    assert status == 2
    _assert_one_line_error(err, f"{_source(case_dir, key, overrides)}: {key}: ")
    assert not (case_dir / "output").exists()
    assert sorted(p.relative_to(tmp_path) for p in tmp_path.rglob("*")) == before, "something was written"


@pytest.mark.parametrize("case, overrides, key",
                         _params(ALL_MALFORMED))
def test_cli_check_rejects_malformed_case(tmp_path, capsys, case, overrides, key):
    case_dir = write_case(tmp_path / "case", case)
    sets = [a for o in overrides for a in ("--set", o)]
    status, out, err = _cli(capsys, "check", case_dir, *sets)
    assert status == 2
    _assert_one_line_error(err, f"{_source(case_dir, key, overrides)}: {key}: ")
    assert "ok" not in out
    assert not (case_dir / "output").exists()


def test_unreadable_toml(tmp_path, capsys):
    case_dir = write_case(tmp_path / "case", "[time\nt_end = 1.0\n")
    with pytest.raises(CaseError) as info:
        runner.load(case_dir)
    assert Path(info.value.file) == case_dir / "case.toml"
    assert "TOML" in str(info.value) and "line 1" in str(info.value)
    status, out, err = _cli(capsys, "run", case_dir)
    assert status == 2
    _assert_one_line_error(err, case_dir / "case.toml", "not valid TOML", "line 1")
    assert not (case_dir / "output").exists()


def test_case_file_that_is_a_directory(tmp_path, capsys):
    case_dir = tmp_path / "case"
    (case_dir / "case.toml").mkdir(parents=True)
    status, out, err = _cli(capsys, "run", case_dir)
    assert status == 2
    _assert_one_line_error(err, case_dir / "case.toml", "a directory")
    assert not (case_dir / "output").exists()


def test_missing_case_toml(tmp_path, capsys):
    case_dir = tmp_path / "empty"
    case_dir.mkdir()
    with pytest.raises(CaseError) as info:
        runner.load(case_dir)
    assert Path(info.value.file) == case_dir / "case.toml"
    status, out, err = _cli(capsys, "run", case_dir)
    assert status == 2
    _assert_one_line_error(err, case_dir / "case.toml", "no such file")
    assert list(case_dir.iterdir()) == []
    status, out, err = _cli(capsys, "check", tmp_path / "does-not-exist")
    assert status == 2
    _assert_one_line_error(err, tmp_path / "does-not-exist")


def test_set_without_equals_sign(good_case, capsys):
    status, out, err = _cli(capsys, "run", good_case, "--set", "time.t_end")
    assert status == 2
    _assert_one_line_error(err, "--set", "time.t_end", "section.key=value")
    assert not (good_case / "output").exists()


def test_set_into_a_non_table(good_case, capsys):
    with pytest.raises(CaseError) as info:
        runner.load(good_case, ["blocks.min=[0.0, 0.0]"])
    assert info.value.file == "--set" and info.value.key == "blocks.min"
    status, out, err = _cli(capsys, "run", good_case, "--set", "blocks.min=[0.0, 0.0]")
    assert status == 2
    _assert_one_line_error(err, "--set", "blocks.min", "not a table")
    assert not (good_case / "output").exists()


def test_check_good_case(good_case, capsys):
    status, out, err = _cli(capsys, "check", good_case)
    assert status == 0
    assert err == ""
    line = out.strip()
    assert line.startswith(f"{good_case / 'case.toml'}: ok: 2D, 100 particles, 4 wall planes")
    assert not (good_case / "output").exists()


GOOD_3D = {
    "case": {"dim": 3},
    "domain": {"min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]},
    "blocks": [{"min": [0.2, 0.2, 0.2], "count": [5, 4, 3]}],
    "particles": {"dx": 0.02},
}

# a box without its top (y = 1) face: open upwards
OPEN_BOX_3D = case_with(GOOD_3D, {"domain": {"planes": [{"normal": n, "point": p} for n, p in [
    ([1.0, 0.0, 0.0], [0.0, 0.0, 0.0]), ([-1.0, 0.0, 0.0], [1.0, 1.0, 1.0]),
    ([0.0, 1.0, 0.0], [0.0, 0.0, 0.0]),
    ([0.0, 0.0, 1.0], [0.0, 0.0, 0.0]), ([0.0, 0.0, -1.0], [1.0, 1.0, 1.0])]]}})


def test_check_good_3d_case(tmp_path, capsys):
    case_dir = write_case(tmp_path / "cube", GOOD_3D)
    status, out, err = _cli(capsys, "check", case_dir)
    assert status == 0, err
    assert ": ok: 3D, 60 particles, 6 wall planes" in out
    # the same planes given one by one, closed with a tilted lid, bound a region too
    lid = {"normal": [0.0, -1.0, -0.2], "point": [0.0, 1.0, 0.0]}
    write_case(tmp_path / "lid", case_with(OPEN_BOX_3D, {"domain.planes": [*OPEN_BOX_3D["domain"]["planes"], lid]}))
    status, out, err = _cli(capsys, "check", tmp_path / "lid")
    assert status == 0, err
    assert ": ok: 3D, 60 particles, 6 wall planes" in out


def test_open_3d_box_bounds_no_region(tmp_path, capsys):
    case_dir = write_case(tmp_path / "open", OPEN_BOX_3D)
    with pytest.raises(CaseError) as info:
        runner.load(case_dir)
    _assert_names_file_and_key(info.value, case_dir, "domain.planes")
    # the open direction, named (as printed it may carry negative zeros: -0.0 == 0.0)
    opened = re.search(r"open along \[([^\]]*)\]", str(info.value))
    assert opened and [float(v) for v in opened.group(1).split(",")] == [0.0, 1.0, 0.0]
    status, out, err = _cli(capsys, "run", case_dir)
    assert status == 2
    _assert_one_line_error(err, case_dir / "case.toml", "domain.planes")
    assert not (case_dir / "output").exists()


def test_defaults_are_filled_in(good_case):
    case, _ = runner.load(good_case)
    cfg = case.config
    assert cfg["kernel"]["name"] == "wendland_c2" and cfg["kernel"]["h_over_dx"] == 1.3
    assert cfg["integrator"]["scheme"] == "leapfrog"
    assert cfg["time"]["dt"] is None and cfg["time"]["cfl"] == 0.3
    assert case.h == pytest.approx(1.3 * 0.02) and case.radius == pytest.approx(0.01)
    assert case.gravity.tolist() == [0.0, -9.81, 0.0]
    assert case.name == "good"


def test_set_overrides_are_applied(good_case):
    case, _ = runner.load(good_case, ["time.t_end=0.01", "kernel.name=cubic_spline", "viscosity.alpha=0",
                                      "physics.gravity=[0.0, -1.0, 0.0]", "eos.c0=12.5"])
    assert case.config["time"]["t_end"] == 0.01
    assert case.config["kernel"]["name"] == "cubic_spline"
    assert case.config["viscosity"]["alpha"] == 0.0
    assert case.gravity.tolist() == [0.0, -1.0, 0.0]
    sim = make_sim(good_case, ["kernel.name=cubic_spline", "eos.c0=12.5"])
    assert sim.params.kernel_id == CUBIC_SPLINE and sim.params.c0 == 12.5
    # the file on disk is untouched
    assert "cubic_spline" not in (good_case / "case.toml").read_text()


def test_cli_run_with_set_reaches_the_new_end_time(good_case, capsys, tmp_path):
    out_dir = tmp_path / "out"
    status, out, err = _cli(capsys, "run", good_case, "--output", out_dir, "--set", "time.t_end=0.003",
                            "--progress", "off")
    assert status == 0, err
    summary = json.loads((out_dir / "summary.json").read_text())
    assert summary["status"] == "completed"
    assert summary["t"] == 0.003
    assert "completed: t = 0.003 s" in out
    # --t-end wins over the case and is applied the same way
    status, out, err = _cli(capsys, "run", good_case, "--output", out_dir, "--overwrite", "--t-end", "0.001",
                            "--progress", "off")
    assert status == 0, err
    assert json.loads((out_dir / "summary.json").read_text())["t"] == 0.001


def test_output_directory_is_never_clobbered(good_case, capsys, tmp_path):
    out_dir = tmp_path / "out"
    assert _cli(capsys, "run", good_case, "--output", out_dir, "--progress", "off")[0] == 0
    first = (out_dir / "summary.json").read_text()
    status, out, err = _cli(capsys, "run", good_case, "--output", out_dir, "--progress", "off")
    assert status == 2
    _assert_one_line_error(err, out_dir, "--overwrite")
    assert (out_dir / "summary.json").read_text() == first
    foreign = tmp_path / "foreign"
    foreign.mkdir()
    (foreign / "precious.txt").write_text("keep me")
    status, out, err = _cli(capsys, "run", good_case, "--output", foreign, "--overwrite", "--progress", "off")
    assert status == 2
    _assert_one_line_error(err, foreign, "refusing")
    assert (foreign / "precious.txt").read_text() == "keep me"


def test_a_dx_that_rounds_a_block_into_a_wall_says_which_max_fits(tmp_path, capsys):
    """A block against the right wall, 0.6 m long: dx = 0.016 gives 37.5 rows, rounded up to
    38, the last past the wall. The one-line error names the block and the max that fits,
    and with that max the case loads."""
    case_dir = write_case(tmp_path / "case", _edit({"blocks[0].min": [0.4, 0.0], "blocks[0].max": [1.0, 0.4]}))
    status, _, err = _cli(capsys, "check", case_dir, "--set", "particles.dx=0.016")
    assert status == 2
    _assert_one_line_error(err, "blocks[0]", "37.5 dx", "give max[0] = 0.992", "--set 'blocks[0].max=[0.992, 0.4]'")
    assert not (case_dir / "output").exists()
    sim = make_sim(case_dir, ["particles.dx=0.016", "blocks[0].max=[0.992, 0.4]"])
    x = sim.state.pos[:, 0]
    assert x.max() == pytest.approx(0.992 - 0.008) and x.min() == pytest.approx(0.408)
