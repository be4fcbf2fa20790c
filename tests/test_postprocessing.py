"""Post-processing scripts on runs: the right kind gives figures, anything else one clean line.

Runs are tiny (sphcore.testing.run_case); the scripts run in a subprocess, as a user runs them."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sphcore.testing import run_case

SCRIPTS = Path(__file__).resolve().parents[1] / "postprocessing"

TANK = """
[case]
dim = 2
[domain]
min = [0.0, 0.0]
max = [0.2, 0.3]
[[blocks]]
min = [0.0, 0.0]
max = [0.2, 0.2]
[particles]
dx = 0.02
[time]
t_end = 0.004
[physics]
modified_pressure = true
[plugins]
use = []
"""

COLUMN = TANK.replace("max = [0.2, 0.2]", "max = [0.06, 0.12]").replace("modified_pressure = true", "")


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    for name, text in (("tank", TANK), ("column", COLUMN)):
        s = run_case(root / name, text, plugins=["reflective", "netcdf"])
        assert s["status"] == "completed", s["message"]
    return root


def script(name, *args):
    return subprocess.run([sys.executable, str(SCRIPTS / name), *map(str, args)], capture_output=True, text=True)


@pytest.mark.parametrize("name,kind", [("wavefront.py", "column"), ("pressure_profile.py", "tank")])
def test_each_script_reads_its_kind_and_writes_beside_the_run(runs, name, kind):
    out = runs / kind / "output"
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    res = script(name, out)
    assert res.returncode == 0, res.stderr
    for p, mtime in before.items():  # nothing sph wrote is touched
        assert p.stat().st_mtime_ns == mtime, p
    if name == "pressure_profile.py":
        prof = np.loadtxt(out / "pressure_profile.csv", delimiter=",", skiprows=1)
        # modified pressure keeps the tank exactly hydrostatic: the default H is the block's 0.2 m
        np.testing.assert_allclose(prof[:, 1], prof[:, 4], rtol=1e-9)
    else:
        front = np.loadtxt(out / "wavefront.csv", delimiter=",", skiprows=1)
        assert front[0, 1] == pytest.approx(0.06, abs=1e-9)  # the column's width: 3 dx, the tip's edge


def test_pressure_profile_columns_of_a_tank_at_rest(runs):
    """--column prints every layer of the chosen particles: with modified pressure the tank
    stays on its lattice with the exact hydrostatic pressure, so both departures vanish."""
    res = script("pressure_profile.py", runs / "tank" / "output", "--column", 0.0, 0.02, "--column", 0.08, 0.12)
    assert res.returncode == 0, res.stderr
    for head in ("x in [0, 0.02) m", "x in [0.08, 0.12) m"):
        block = res.stdout.split(head)[1].split("x in [")[0].splitlines()[1:]  # this column's rows only
        rows = np.array([[float(v) for v in line.split()] for line in block if line.strip()])
        np.testing.assert_array_equal(rows[:, 0], np.arange(1, 11))  # 10 layers of 0.02 m, from the top
        np.testing.assert_allclose(rows[:, 1:], 0.0, atol=1e-9)
    bad = script("pressure_profile.py", runs / "tank" / "output", "--column", 0.1, 0.1)
    assert bad.returncode == 2 and "--column 0.1 0.1: expected XA < XB" in bad.stderr, bad.stderr


@pytest.mark.parametrize("name,kind", [("wavefront.py", "tank"), ("pressure_profile.py", "column")])
def test_a_run_of_another_kind_is_refused(runs, name, kind):
    res = script(name, runs / kind / "output")
    assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1, res.stderr
    assert res.stderr.startswith(f"{name}: error: ") and "Traceback" not in res.stderr


@pytest.mark.parametrize("name", ["wavefront.py", "pressure_profile.py"])
def test_a_missing_run_or_a_foreign_directory_is_refused(tmp_path, name):
    for path in (tmp_path / "missing", tmp_path):
        res = script(name, path)
        assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1, res.stderr
        assert "Traceback" not in res.stderr
