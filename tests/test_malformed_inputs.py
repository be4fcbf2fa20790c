"""Every malformed input a clean exit 2: case files generated from the option
declarations (every option's wrong types and out-of-range values) and a table of the rest
(non-UTF-8, binary, nested 2,000 deep, a link to /dev/zero, beyond int64, subnormal, more
memory than the machine has, a step below round-off, an output directory outside the case,
bad --set/--t-end values). Each: exit 2 with one line naming the file or option, the key
and what was expected, nothing written, and ``sph check`` saying exactly what ``sph run``
says. Also: Ctrl-C in set-up, the compile notice, the ETA, a step that cannot advance t.

The fuzz calls ``sphcore.cli.main`` in this process (hundreds of interpreters would take
minutes); three variants run ``sph`` as a real process.
"""

from __future__ import annotations

import json
import shutil
import signal
import time
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

import pytest
from conftest import GOOD_CASE, write_case
from core_cases import spheres
from test_run_lifecycle import snapshot, sph

from sphcore import cli
from sphcore.case import defaults
from sphcore.plugin import pluginhost

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
    ("output-dir-300-bytes", _edit(output={"dir": "a" * 300}), []),
    ("output-dir-nul", _edit(output={"dir": "a\u0000b"}), []),
    ("mesh-without-file", to_toml({**GOOD, "domain": {**GOOD["domain"], "walls": [{"shape": "mesh"}]}}).encode(), []),
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
# 6. set-up interrupted, compilation announced, a step that cannot advance time
# ----------------------------------------------------------------------------------------


def test_ctrl_c_during_set_up_is_one_line_and_writes_nothing(tmp_path, capsys, monkeypatch):
    case_dir = write_case(tmp_path / "case", GOOD_CASE)

    def interrupted(*a, **k):
        raise KeyboardInterrupt

    monkeypatch.setattr("sphcore.run.build.Simulation", interrupted)
    before = snapshot(tmp_path)
    status, _, err = cli_main(capsys, "run", case_dir, "--progress", "off")
    assert status == 128 + signal.SIGINT
    assert err.strip() == "sph: error: interrupted during set-up; nothing written"
    assert snapshot(tmp_path) == before


def test_first_run_says_it_compiles(tmp_path, capsys, monkeypatch):
    case_dir = write_case(tmp_path / "case", GOOD_CASE)
    monkeypatch.setattr("sphcore.run.runner.kernels_cached", lambda dim=2, scheme="wcsph": False)
    status, _, err = cli_main(capsys, "run", case_dir, "--progress", "log")
    assert status == 0 and "[sph] compiling kernels, once" in err
    monkeypatch.setattr("sphcore.run.runner.kernels_cached", lambda dim=2, scheme="wcsph": True)
    status, _, err = cli_main(capsys, "run", case_dir, "--progress", "log", "--output", tmp_path / "again")
    assert status == 0 and "compiling" not in err


def test_the_cache_is_checked_before_the_first_force_evaluation_compiles(tmp_path, capsys, monkeypatch):
    """Sizing the first step evaluates the forces, which compiles (and caches) the kernels
    on a fresh machine: asked after that, the cache would always hold them."""
    from sphcore.physics import forces

    events = []
    monkeypatch.setattr("sphcore.run.runner.kernels_cached",
                        lambda dim=2, scheme="wcsph": events.append("checked") or False)
    evaluate = forces.Forces.evaluate
    monkeypatch.setattr(forces.Forces, "evaluate", lambda self, *a, **k: events.append("forces") or evaluate(self, *a, **k))
    case_dir = write_case(tmp_path / "case", GOOD_CASE)
    status, _, err = cli_main(capsys, "run", case_dir, "--progress", "log")
    assert status == 0 and "compiling kernels" in err
    assert events[0] == "checked" and "forces" in events


def test_kernels_cached_finds_the_cache():
    from sphcore.run import runner

    assert runner.kernels_cached(2)  # the runs above compiled, and numba cached, the 2D force kernel


def test_a_step_below_the_round_off_of_t_is_an_instability(tmp_path):
    from conftest import make_sim

    from sphcore.errors import Instability

    sim = make_sim(write_case(tmp_path / "case", GOOD_CASE), ["time.dt=1e-4", "time.t_end=1e20"])
    sim.ctx.t = 1e16  # ulp(1e16) = 2: t + 1e-4 == t
    with pytest.raises(Instability, match="below the round-off of t"):
        sim.advance()


def test_eta_starts_after_the_first_step():
    import io
    import re
    from types import SimpleNamespace

    from sphcore.run.progress import Progress

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


def test_a_plane_normal_of_huge_components_is_a_direction(tmp_path, capsys):
    """A normal is a direction: [1e308, 1e308] is the diagonal (its norm alone would overflow)."""
    raw = json.loads(json.dumps(GOOD))
    raw["domain"]["planes"] = [{"normal": [1e308, 1e308], "point": [0.0, 0.0]}]
    status, out, err = cli_main(capsys, "check", make_case(tmp_path, to_toml(raw).encode()))
    assert status == 0 and "ok:" in out, err


def test_an_empty_or_cut_checkpoint_is_refused_on_restart(tmp_path, capsys):
    case_dir = write_case(tmp_path / "case", GOOD_CASE)
    out = tmp_path / "out"
    assert cli_main(capsys, "run", case_dir, "--output", out, "--progress", "off")[0] == 0
    data = (out / "checkpoint.npz").read_bytes()
    for cut in (b"", data[: len(data) // 2]):
        (out / "checkpoint.npz").write_bytes(cut)
        status, _, err = cli_main(capsys, "run", case_dir, "--output", out, "--restart", "--progress", "off")
        assert status == 2 and "checkpoint.npz: --restart: not a readable checkpoint" in err and "Traceback" not in err


def test_a_reader_that_leaves_early_stops_sph_quietly():
    """`sph options | head -1`: a closed pipe ends sph with 128 + SIGPIPE and no traceback.
    The reader has left before sph starts (its whole output, 13 KB, would fit in the pipe's
    buffer: a reader that read a little first could leave after sph had written it all)."""
    import os
    import subprocess
    import sys

    read_end, write_end = os.pipe()
    os.close(read_end)
    proc = subprocess.Popen([sys.executable, "-m", "sphcore.cli", "options"], stdout=write_end,
                            stderr=subprocess.PIPE)
    os.close(write_end)
    err = proc.stderr.read().decode()
    assert proc.wait() == 128 + signal.SIGPIPE and "Traceback" not in err, err

