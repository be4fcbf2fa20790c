"""An adversarial suite of bad inputs, each asserting what the README promises: exit status
2, exactly one line on stderr naming the key (or option, or file) at fault, no traceback,
and nothing written to the case or output directory.

Generated from the option tables (``sph options``: the core's tables, ``[[blocks]]``,
``[[domain.planes]]``, ``[[domain.walls]]`` and every installed plugin's): for every key
the values of this list that its declaration itself refuses (``check_value``), so that
no value the key accepts is ever listed as bad: NaN, +-inf, subnormal, negative, zero,
huge, empty string, empty table, empty and nested list, a date, a number as text. These
complement tests/test_malformed_inputs.py (0, -1, min - 1, max + 1, 2^63, 5e-324 and the
wrong types listed there), which checks that ``sph check`` and ``sph run`` agree; here the
bulk goes through ``sph check`` in this process (the same validation ``sph run`` makes:
sphcore.cli -> runner.load, build, runner.first_step), some through ``--set`` (which must
name the option) and a handful through a real ``sph`` process. Then walls, mesh files,
command-line flags, sweep options and post-processing inputs.
"""

from __future__ import annotations

import datetime
import hashlib
import math
import os
from pathlib import Path

import pytest
from conftest import script, write_case
from core_cases import good
from test_run_lifecycle import sph

from sphcore import cli
from sphcore.case import defaults
from sphcore.case.options import check_value
from sphcore.errors import CaseError
from sphcore.plugin import pluginhost
from sphcore.testing import case_with

NAN, INF = math.nan, math.inf
#: candidate bad values; each key gets those its declaration refuses
NUMBERS = [("nan", NAN), ("inf", INF), ("-inf", -INF), ("subnormal", 1e-310), ("-subnormal", -1e-310),
           ("zero", 0.0), ("negative", -0.5), ("huge", 1e308), ("-huge", -1e308)]
OTHERS = [("empty-string", ""), ("empty-table", {}), ("empty-list", []), ("nested-list", [[1.0]]),
          ("date", datetime.date(2020, 1, 1)), ("number-as-text", "1.0"), ("nan-as-text", "nan")]
VECTORS = [("vector-nan", [NAN, 0.0]), ("vector-inf", [0.0, INF]), ("vector-text", ["", 1.0]),
           ("vector-table", [{}, 1.0]), ("vector-bool", [True, 0.0])]


def _refused(opt, value) -> bool:
    try:
        check_value(opt, value, "case.toml", "key")
    except CaseError:
        return True
    return False


def bad_values(opt) -> list[tuple[str, object]]:
    # a number of any size is one wrong type for a key that takes no float: two stand for all
    numbers = NUMBERS if opt.kind == "float" else NUMBERS[:1] + NUMBERS[5:6] if opt.kind == "int" else NUMBERS[:1]
    pool = numbers + OTHERS + (VECTORS if opt.kind == "vector" else [])
    if opt.kind == "str" and opt.choices:
        pool = pool + [("choice-upper", opt.choices[0].upper()), ("choice-space", f" {opt.choices[0]}"),
                       ("choice-nul", f"{opt.choices[0]}\0")]
    return [(name, v) for name, v in pool if _refused(opt, v)]


def tables() -> dict[str, dict]:
    """dotted prefix -> schema of every table a case may hold."""
    out = {section: schema for section, schema in defaults.CORE.items() if isinstance(schema, dict)}
    out.update(pluginhost.option_schemas())
    out["blocks[0]"] = defaults.BLOCK
    return out


def generated() -> list:
    params = []
    for prefix, schema in tables().items():
        for key, opt in schema.items():
            for name, value in bad_values(opt):
                params.append(pytest.param(f"{prefix}.{key}", value, id=f"{prefix}.{key}={name}"))
    for key, opt in defaults.PLANE.items():  # one extra plane of the box domain
        for name, value in bad_values(opt):
            params.append(pytest.param(f"domain.planes[0].{key}", value, id=f"domain.planes[0].{key}={name}"))
    top = defaults.CORE["blocks"]
    for name, value in bad_values(top):
        params.append(pytest.param("blocks", value, id=f"blocks={name}"))
    return params


GENERATED = generated()
PLANE = {"normal": [0.0, 1.0], "point": [0.0, 0.0]}


def case_for(key: str, value) -> dict:
    base = good()
    if key.startswith("domain.planes[0]."):
        base = case_with(base, {"domain.planes": [dict(PLANE)]})
    return case_with(base, {key: value})


def snapshot(root: Path) -> dict:
    """Every path below ``root`` with its mtime (links, pipes and devices not followed) and a
    regular file's content hash."""
    snap = {}
    for p in [root, *sorted(root.rglob("*"))]:
        st = p.lstat()
        regular = p.is_file() and not p.is_symlink()
        snap[str(p.relative_to(root))] = (st.st_mtime_ns, hashlib.sha256(p.read_bytes()).hexdigest() if regular else None)
    return snap


def refused(capsys, case_dir: Path, *argv, command="check") -> str:
    """``sph COMMAND case_dir ARGV`` in this process: exit 2, one line, nothing written."""
    before = snapshot(case_dir.parent)
    extra = ["--progress", "off"] if command == "run" else []
    status = cli.main([command, str(case_dir), *extra, *map(str, argv)])
    out, err = capsys.readouterr()
    assert status == 2, (out, err)
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("sph: error: ") and "Traceback" not in err, err
    assert snapshot(case_dir.parent) == before, "something was written"
    return lines[0]


def test_the_suite_is_large():
    assert len(GENERATED) + len(SET_VALUES) + len(WALLS) + len(MESHES) + len(FLAGS) + len(SWEEPS) \
        + len(POST) >= 300


@pytest.mark.parametrize("key, value", GENERATED)
def test_every_declared_key_refuses_its_bad_values_naming_the_key(tmp_path, capsys, key, value):
    case_dir = write_case(tmp_path / "case", case_for(key, value))
    line = refused(capsys, case_dir)
    assert f": {key}" in line, line


# -- the same through --set: the option is named ------------------------------------------

SET_VALUES = [pytest.param(f"{section}.{key}", text, id=f"--set {section}.{key}={text}")
              for section in ("time", "eos", "fluid", "particles", "kernel", "viscosity", "checks", "output")
              for key, opt in defaults.CORE[section].items()
              for text in ("nan", "-inf", "1e-310", "{}")
              if _refused(opt, {"nan": NAN, "-inf": -INF, "1e-310": 1e-310, "{}": {}}[text])]


@pytest.mark.parametrize("key, text", SET_VALUES)
def test_set_names_the_option_and_the_key(tmp_path, capsys, key, text):
    case_dir = write_case(tmp_path / "case", good())
    line = refused(capsys, case_dir, "--set", f"{key}={text}")
    assert line.startswith(f"sph: error: --set: {key}"), line


# -- walls and meshes ---------------------------------------------------------------------

def _wall(**entry) -> dict:
    return entry


WALLS = {
    "polygon-collinear": _wall(shape="polygon", points=[[0.5, 0.5], [0.6, 0.6], [0.7, 0.7]]),
    "polygon-collinear-4": _wall(shape="polygon", points=[[0.5, 0.5], [0.6, 0.5], [0.7, 0.5], [0.8, 0.5]]),
    "polygon-two-points": _wall(shape="polygon", points=[[0.5, 0.5], [0.6, 0.6]]),
    "polygon-repeated": _wall(shape="polygon", points=[[0.5, 0.5], [0.5, 0.5], [0.7, 0.6]]),
    "polygon-bowtie": _wall(shape="polygon", points=[[0.5, 0.5], [0.7, 0.7], [0.7, 0.5], [0.5, 0.7]]),
    "polygon-nan": _wall(shape="polygon", points=[[0.5, 0.5], [NAN, 0.6], [0.7, 0.5]]),
    "polygon-inf": _wall(shape="polygon", points=[[0.5, 0.5], [INF, 0.6], [0.7, 0.5]]),
    "polygon-3d-points": _wall(shape="polygon", points=[[0.5, 0.5, 0.0], [0.6, 0.6, 0.0], [0.7, 0.5, 0.0]]),
    "polygon-text-points": _wall(shape="polygon", points=[["a", 0.5], [0.6, 0.6], [0.7, 0.5]]),
    "polygon-flat-list": _wall(shape="polygon", points=[0.5, 0.5, 0.6]),
    "polygon-empty": _wall(shape="polygon", points=[]),
    "polyline-one-point": _wall(shape="polyline", points=[[0.5, 0.5]]),
    "polyline-repeated": _wall(shape="polyline", points=[[0.5, 0.5], [0.5, 0.5]]),
    "polyline-fluid": _wall(shape="polyline", points=[[0.5, 0.5], [0.6, 0.6]], fluid="inside"),
    "box-inverted": _wall(shape="box", min=[0.7, 0.7], max=[0.6, 0.6]),
    "box-flat": _wall(shape="box", min=[0.6, 0.6], max=[0.8, 0.6]),
    "box-3-components": _wall(shape="box", min=[0.6, 0.6, 0.0], max=[0.8, 0.8, 1.0]),
    "box-nan": _wall(shape="box", min=[0.6, NAN], max=[0.8, 0.8]),
    "box-without-max": _wall(shape="box", min=[0.6, 0.6]),
    "box-with-points": _wall(shape="box", min=[0.6, 0.6], max=[0.8, 0.8], points=[[0.0, 0.0]]),
    "no-shape": _wall(min=[0.6, 0.6], max=[0.8, 0.8]),
    "unknown-key": _wall(shape="box", min=[0.6, 0.6], max=[0.8, 0.8], colour="red"),
    "mesh-without-file": _wall(shape="mesh"),
    "mesh-file-empty-name": _wall(shape="mesh", file=""),
    "mesh-file-nul": _wall(shape="mesh", file="a\0b.obj"),
    "mesh-file-300": _wall(shape="mesh", file="a" * 300 + ".obj"),
    "tank-and-motion": _wall(shape="box", min=[0.6, 0.6], max=[0.8, 0.8], tank=True,
                             motion=[{"type": "constant_velocity", "velocity": [0.1, 0.0]}]),
}


@pytest.mark.parametrize("name", list(WALLS))
def test_bad_walls_name_the_wall(tmp_path, capsys, name):
    case_dir = write_case(tmp_path / "case", case_with(good(), {"domain.walls": [WALLS[name]]}))
    line = refused(capsys, case_dir)
    assert ": domain.walls[0]" in line, line


def _mesh(case_dir: Path, kind: str) -> None:
    path = case_dir / "wall.obj"
    if kind == "fifo":
        os.mkfifo(path)
    elif kind == "dev-zero":
        path.symlink_to("/dev/zero")
    elif kind == "dev-null":
        path.symlink_to("/dev/null")
    elif kind == "directory":
        path.mkdir()
    elif kind == "dangling-link":
        path.symlink_to(case_dir / "nowhere.obj")
    elif kind == "empty":
        path.write_bytes(b"")
    elif kind == "garbage":
        path.write_bytes(bytes(range(256)) * 4)
    elif kind == "one-triangle-open":
        path.write_text("v 0.5 0.5 0\nv 0.6 0.5 0\nv 0.5 0.6 0\n")
    elif kind == "text-not-mesh":
        path.write_text("this is not a mesh\n" * 10)
    elif kind == "nan-vertex":
        path.write_text("v nan 0.5 0\nv 0.6 0.5 0\nv 0.5 0.6 0\nf 1 2 3\n")
    elif kind == "missing":
        pass


MESHES = ["fifo", "dev-zero", "dev-null", "directory", "dangling-link", "empty", "garbage", "one-triangle-open",
          "text-not-mesh", "nan-vertex", "missing"]


@pytest.mark.parametrize("kind", MESHES)
def test_bad_mesh_files_are_refused_without_hanging(tmp_path, capsys, kind):
    case_dir = write_case(tmp_path / "case", case_with(good(), {"domain.walls": [{"shape": "mesh", "file": "wall.obj"}]}))
    _mesh(case_dir, kind)
    line = refused(capsys, case_dir)
    assert ": domain.walls[0].file: " in line, line


# -- command-line flags -------------------------------------------------------------------

FLAGS = {
    "t-end nan": (["--t-end", "nan"], "--t-end"),
    "t-end inf": (["--t-end", "inf"], "--t-end"),
    "t-end -inf": (["--t-end=-inf"], "--t-end"),
    "t-end -1e-310": (["--t-end=-1e-310"], "--t-end"),
    "t-end 1e400": (["--t-end", "1e400"], "--t-end"),
    "t-end subnormal": (["--t-end", "1e-310"], "--t-end"),
    "t-end 1e300": (["--t-end", "1e300"], "--t-end: time.t_end"),
    "t-end 1e12": (["--t-end", "1e12"], "--t-end: time.t_end"),
    "set no equals": (["--set", "time.t_end"], "--set"),
    "set empty key": (["--set", "=1"], "--set"),
    "set dot key": (["--set", ".t_end=1"], "--set"),
    "set section only": (["--set", "time=1"], "--set"),
    "set unknown section": (["--set", "nonsense.key=1"], "nonsense"),
    "set index out of range": (["--set", "blocks[9].count=[1,1]"], "--set"),
    "set negative index": (["--set", "blocks[-1].count=[1,1]"], "--set"),
    "set index text": (["--set", "blocks[a].count=[1,1]"], "--set"),
    "set unbalanced": (["--set", "time.t_end=[1.0"], "--set: time.t_end"),
    "set nested 40": (["--set", "time.t_end=" + "[" * 40 + "]" * 40], "--set: time.t_end"),
    "set c0 too many steps": (["--set", "eos.c0=1e6", "--t-end", "100"], "--set: eos.c0: "),
    "set radius": (["--set", "particles.radius=1"], "--set: particles.radius: "),
    "set output dir file": (["--set", 'output.dir="case.toml"'], "output.dir: "),
    "set output dir nul": (["--set", 'output.dir="a\\u0000b"'], "output.dir"),
    "set output dir parent": (["--set", 'output.dir="../x"'], "output.dir"),
    "set output dir empty": (["--set", 'output.dir=""'], "output.dir"),
}


@pytest.mark.parametrize("what", list(FLAGS))
def test_bad_command_line_values_name_the_option(tmp_path, capsys, what):
    argv, says = FLAGS[what]
    case_dir = write_case(tmp_path / "case", good())
    line = refused(capsys, case_dir, *argv)
    assert says in line, line


RUN_ONLY = {
    "output is a file": lambda root: ["--output", root / "file"],
    "output below a file": lambda root: ["--output", root / "file" / "out"],
    "restart without checkpoint": lambda root: ["--output", root / "none", "--restart"],
    "restart of an empty directory": lambda root: ["--output", root / "emptydir", "--restart"],
    "overwrite of a user's directory": lambda root: ["--output", root / "users", "--overwrite"],
    "output a link": lambda root: ["--output", root / "link"],
}


@pytest.mark.parametrize("what", list(RUN_ONLY))
def test_run_refuses_an_output_it_may_not_write(tmp_path, capsys, what):
    case_dir = write_case(tmp_path / "case", good())
    (tmp_path / "file").write_text("a user's")
    (tmp_path / "emptydir").mkdir()
    (tmp_path / "users").mkdir()
    (tmp_path / "users" / "thesis.tex").write_text("years")
    (tmp_path / "link").symlink_to(tmp_path / "users")
    refused(capsys, case_dir, *RUN_ONLY[what](tmp_path), command="run")
    assert (tmp_path / "file").read_text() == "a user's" and (tmp_path / "users" / "thesis.tex").read_text() == "years"


# -- sweep options ------------------------------------------------------------------------

SWEEPS = {
    "vary without equals": (["--vary", "viscosity.alpha"], "--vary"),
    "vary empty value": (["--vary", "viscosity.alpha=0.1,,0.2"], "--vary: viscosity.alpha"),
    "vary unbalanced": (["--vary", "viscosity.alpha=[0.1,0.2"], "--vary: viscosity.alpha"),
    "vary close first": (["--vary", "viscosity.alpha=]0.1"], "--vary: viscosity.alpha"),
    "vary nested 2000": (["--vary", "viscosity.alpha=" + "[" * 2000 + "]" * 2000], "--vary: viscosity.alpha"),
    "vary nested tables": (["--vary", "viscosity.alpha=" + "{a=" * 100 + "1" + "}" * 100], "--vary: viscosity.alpha"),
    "vary twice": (["--vary", "viscosity.alpha=0.1,0.2", "--vary", "viscosity.alpha=0.3"], "viscosity.alpha"),
    "vary unknown key": (["--vary", "viscosity.nonsense=1,2"], "viscosity.nonsense"),
    "vary nan": (["--vary", "viscosity.alpha=0.1,nan"], "viscosity.alpha"),
    "vary negative": (["--vary", "viscosity.alpha=0.1,-1"], "viscosity.alpha"),
    "vary linked mismatch": (["--vary", "viscosity.alpha,viscosity.beta=[0.1],[0.2,0.3]"], "--vary"),
    "vary linked not arrays": (["--vary", "viscosity.alpha,viscosity.beta=0.1,0.2"], "--vary"),
    "vary huge grid": (["--vary", "viscosity.alpha=" + ",".join(str(i) for i in range(100)),
                        "--vary", "viscosity.beta=" + ",".join(str(i) for i in range(100))], "10000 variants"),
    "vary index text": (["--vary", "blocks[x].count=[1,1],[2,2]"], "--vary"),
    "set nested": (["--vary", "viscosity.alpha=0.1,0.2", "--set", "time.t_end=" + "[" * 100 + "]" * 100], "--set"),
    "timeout -1": (["--vary", "viscosity.alpha=0.1,0.2", "--timeout", "-1"], "--timeout"),
    "timeout nan": (["--vary", "viscosity.alpha=0.1,0.2", "--timeout", "nan"], "--timeout"),
    "timeout inf": (["--vary", "viscosity.alpha=0.1,0.2", "--timeout", "inf"], "--timeout"),
    "timeout 0": (["--vary", "viscosity.alpha=0.1,0.2", "--timeout", "0"], "--timeout"),
    "workers 0": (["--vary", "viscosity.alpha=0.1,0.2", "--workers", "0"], "--workers"),
    "workers and scheduler": (["--vary", "viscosity.alpha=0.1,0.2", "--workers", "2", "--scheduler",
                               "tcp://127.0.0.1:1"], "--workers"),
    "t-end nan": (["--vary", "viscosity.alpha=0.1,0.2", "--t-end", "nan"], "time.t_end"),
}


@pytest.mark.parametrize("what", list(SWEEPS))
def test_bad_sweep_options_are_refused_before_anything_runs(tmp_path, capsys, what):
    argv, says = SWEEPS[what]
    case_dir = write_case(tmp_path / "case", good())
    before = snapshot(tmp_path)
    status = cli.main(["sweep", str(case_dir), *argv, "--dry-run"])
    err = capsys.readouterr().err
    assert status == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert says in err, err
    assert snapshot(tmp_path) == before


# -- post-processing ----------------------------------------------------------------------

def _run_dir(root: Path, kind: str) -> Path:
    d = root / kind
    d.mkdir()
    if kind == "summary-garbage":
        (d / "summary.json").write_bytes(b"\x00\xff{")
    elif kind == "summary-list":
        (d / "summary.json").write_text("[1, 2]")
    elif kind == "config-number":
        (d / "summary.json").write_text('{"config": 3}')
    elif kind == "config-partial":
        (d / "summary.json").write_text('{"config": {"case": {"dim": 2}, "blocks": [{"min": "x"}]}}')
    elif kind == "frames-garbage":
        (d / "summary.json").write_text('{"config": {}}')
        (d / "particles.nc").write_bytes(b"CDF\x05 cut")
        (d / "probes.nc").write_bytes(b"CDF\x05 cut")
        (d / "probes.csv").write_text("time_s,P1_pa\nnan,x\n")
    return d


POST = [pytest.param(name, kind, id=f"{name}-{kind}")
        for name in ("pressure_profile", "probes", "spheric_test2", "wavefront")
        for kind in ("empty", "summary-garbage", "summary-list", "config-number", "config-partial", "frames-garbage")]


@pytest.mark.parametrize("name, kind", POST)
def test_post_processing_scripts_refuse_what_is_not_a_run(tmp_path, capsys, name, kind):
    run = _run_dir(tmp_path, kind)
    before = snapshot(tmp_path)
    status = script(name).main([str(run)])
    err = capsys.readouterr().err
    assert status == 2 and len(err.strip().splitlines()) == 1 and "Traceback" not in err, err
    assert snapshot(tmp_path) == before


# -- a handful as real processes -------------------------------------------------------------

@pytest.mark.parametrize("key, value", [("eos.c0", NAN), ("particles.dx", -INF), ("time.t_end", 1e-310),
                                        ("output.progress", "")])
def test_as_a_process(tmp_path, key, value):
    case_dir = write_case(tmp_path / "case", case_for(key, value))
    res, _ = sph("check", case_dir, timeout=60)
    assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1 and key in res.stderr, res.stderr
    assert sorted(p.name for p in case_dir.iterdir()) == ["case.toml"]
