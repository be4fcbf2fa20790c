"""The wave flume (cases/wave_flume) and its post-processing (postprocessing/wave_flume.py):
the shipped cases pass ``sph check``, Biesel's transfer function and the dispersion relation
match known values, and a coarse, short version of the case runs and is measured (exit 0,
the table printed, the PNG written). The full runs, which give the README's numbers, are
``slow``."""

from __future__ import annotations

import importlib.util
import itertools
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import tomllib

from sphcore.testing import case_with, run_case

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "postprocessing" / "wave_flume.py"
CASES = [ROOT / "cases" / "wave_flume", ROOT / "cases" / "wave_flume_kh18"]


def _module():
    sys.path.insert(0, str(SCRIPT.parent))  # the script imports its sibling runs.py
    try:
        spec = importlib.util.spec_from_file_location("wave_flume_script", SCRIPT)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
    finally:
        sys.path.remove(str(SCRIPT.parent))
    return mod


wf = _module()


def script(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True, text=True,
                          check=False)


# ---------------------------------------------------------------------------- linear theory


def test_biesel_goes_from_kh_in_shallow_water_to_two_in_deep_water():
    kh = np.array([1e-3, 1e-2, 0.05])
    assert np.all(np.abs(wf.biesel(kh) / kh - 1.0) < kh ** 2)  # H/S = kh (1 + O(kh^2))
    np.testing.assert_allclose(wf.biesel([8.0, 15.0]), 2.0, rtol=1e-5)
    # 2 (cosh 2 - 1) / (sinh 2 + 2) at kh = 1 and its value at kh = 1.8
    assert wf.biesel(1.0) == pytest.approx(2 * (math.cosh(2) - 1) / (math.sinh(2) + 2), rel=1e-14)
    assert wf.biesel(1.0) == pytest.approx(0.98179, abs=1e-5)
    assert wf.biesel(1.8) == pytest.approx(1.58213, abs=1e-5)
    assert np.all(np.diff(wf.biesel(np.linspace(0.01, 6, 200))) > 0)


@pytest.mark.parametrize("kh", [0.05, 0.5, 1.0, 1.8, 4.0, 12.0])
def test_the_wavenumber_solves_the_dispersion_relation(kh):
    g, h = 9.81, 0.25
    k = kh / h
    omega = math.sqrt(g * k * math.tanh(kh))
    assert wf.wavenumber(omega, h, g) == pytest.approx(k, rel=1e-12)


def test_group_velocity_is_half_the_celerity_in_deep_water_and_all_of_it_in_shallow():
    g, h = 9.81, 0.25
    assert wf.group_velocity(20.0 / h, h, g) == pytest.approx(0.5 * math.sqrt(g / (20.0 / h)), rel=1e-6)
    assert wf.group_velocity(0.01 / h, h, g) == pytest.approx(math.sqrt(g * h), rel=1e-3)


def test_wave_heights_are_crest_to_trough_of_whole_waves():
    t = np.linspace(0.0, 3.0, 3001)
    eta = 0.01 * np.sin(2 * math.pi * t + 0.3) + 0.2
    heights = wf.wave_heights(t, eta)
    assert len(heights) == 2
    np.testing.assert_allclose(heights, 0.02, rtol=1e-4)
    assert wf.wave_heights(t[:400], eta[:400]) == []


# ---------------------------------------------------------------------------- the cases


@pytest.mark.parametrize("case", CASES, ids=lambda p: p.name)
def test_the_shipped_cases_pass_sph_check(case):
    res = subprocess.run([sys.executable, "-m", "sphcore.cli", "check", str(case)], capture_output=True, text=True,
                         check=False)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "ok: 2D" in res.stdout


def _tiny(tmp_path):
    """The case at dx = 0.05 m (5 particles over the depth) in a 2 m flume, T = 1 s, for 3 s:
    about two whole waves at G1 before the far wall's reflection."""
    case = tomllib.loads((CASES[0] / "case.toml").read_text())
    case = case_with(case, {"particles.dx": 0.05, "domain.max": [2.0, 0.5], "blocks[0].max": [2.0, 0.25],
                            "time.t_end": 3.0, "probes.every_dt": 0.01,
                            "domain.walls[0].motion[0].period": 1.0, "domain.walls[0].motion[0].ramp": 0.5,
                            "probes.depth": [{"name": "G1", "point": [0.5, 0.0]},
                                             {"name": "G2", "point": [0.75, 0.0]}]})
    s = run_case(tmp_path / "tiny", case, plugins=["reflective", "probes", "wall_loads"])
    assert s["status"] == "completed", s["message"]
    return tmp_path / "tiny" / "output"


def test_a_tiny_flume_runs_and_is_measured(tmp_path):
    out = _tiny(tmp_path)
    res = script(out)
    assert res.returncode == 0 and res.stderr == "", res.stdout + res.stderr
    assert "Biesel H/S = " in res.stdout and "window [s]" in res.stdout
    assert "G1" in res.stdout and "G2" in res.stdout and "piston force Fx" in res.stdout
    png = out / wf.PNG
    assert png.is_file() and png.read_bytes()[:4] == b"\x89PNG"
    m = wf.measure(wf.open_run(out))
    assert m["rows"][0]["waves"] >= 1 and 0.2 < m["rows"][0]["HS"] / m["biesel"] < 2.0


def test_help_and_refusals(tmp_path):
    res = script("--help")
    assert res.returncode == 0 and res.stdout.startswith("usage: wave_flume.py ")
    assert "Reads " in res.stdout and "Writes " in res.stdout
    for path in (tmp_path, tmp_path / "missing"):
        res = script(path)
        assert res.returncode == 2 and res.stderr.startswith("wave_flume.py: error: ") and "Traceback" not in res.stderr


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES, ids=lambda p: p.name)
def test_the_full_flume_makes_biesels_waves_and_damps_them_on_the_way(case, tmp_path):
    """The shipped case as it is (3 to 5 minutes on 2 cores), as the README measures it: H/S
    extrapolated back to the piston within 5 % of Biesel's, H decreasing from gauge to gauge
    (the numerical damping), the nearest gauge within 20 %."""
    from sphcore.run import runner

    out = tmp_path / "output"
    s = runner.run(case, quiet=True, output=out).summary
    assert s["status"] == "completed", s["message"]
    m = wf.measure(wf.open_run(out))
    rows = m["rows"]
    assert all(r["waves"] >= 1 for r in rows), [(r["name"], r["waves"]) for r in rows]
    hs = [r["HS"] for r in rows]
    assert all(a > b for a, b in itertools.pairwise(hs)), hs
    assert abs(hs[0] / m["biesel"] - 1.0) < 0.20, (hs, m["biesel"])
    rate, at_piston = wf.decay(m)
    assert rate > 0.0 and abs(at_piston / m["biesel"] - 1.0) < 0.05, (rate, at_piston, m["biesel"])
