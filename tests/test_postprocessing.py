"""The user's toolkit, postprocessing/: each script on a tiny run of its kind gives its figures
and files with the right numbers; anything else is refused with one clean line and exit 2.

Runs are tiny (sphcore.testing.run_case, 100-150 particles, a few steps); the scripts run in
a subprocess, as a user runs them (``python postprocessing/X.py``)."""

from __future__ import annotations

import importlib.util
import re
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sphcore.testing import case_with, run_case

ROOT = Path(__file__).resolve().parents[1]
SCRIPTS = ROOT / "postprocessing"
TOOLKIT = ["wavefront.py", "pressure_profile.py", "probes.py", "spheric_test2.py", "peer_series.py", "sloshing.py",
           "wave_flume.py", "render.py", "body_motion.py"]
# the validation scripts a user runs (validation/build.py and the studies validation/<case>/*.py);
# validation/pages/ holds the build's page modules, not scripts, and validation/runs/ its runs
STUDIES = sorted(p.relative_to(ROOT) for p in (ROOT / "validation").rglob("*.py")
                 if p.relative_to(ROOT / "validation").parts[0] not in ("pages", "runs"))
PAGES = sorted((ROOT / "validation" / "pages").glob("*.py"))
RHO_G = 1000.0 * 9.81

TANK = {
    "case": {"dim": 2},
    "domain": {"min": [0.0, 0.0], "max": [0.2, 0.3]},
    "blocks": [{"min": [0.0, 0.0], "max": [0.2, 0.2]}],
    "particles": {"dx": 0.02},
    "time": {"t_end": 0.004},
    "physics": {"modified_pressure": True},
    "plugins": {"use": []},
}

COLUMN = case_with(TANK, {"blocks[0].max": [0.06, 0.12], "physics.modified_pressure": None})

# a tank 0.3 m deep at rest (modified pressure: exactly hydrostatic), a pressure probe on the
# floor and a depth probe: named like SPHERIC test 2's, so every probe script reads it
PROBED = case_with(TANK, {"domain.max": [0.2, 0.4], "blocks[0].max": [0.2, 0.3], "probes": {
    "every_dt": 0.001,
    "pressure": [{"name": "P1", "point": [0.1, 0.0]}],
    "depth": [{"name": "H2", "point": [0.1, 0.0]}],
}})

# what each script needs besides the path it reads
EXTRA = {"peer_series.py": ["--reference", "buchner_2002_P1", "--H", "0.3"]}
#: sub-commands that come before the run's path
FIRST = {"sloshing.py": ["free"]}


@pytest.fixture(scope="module")
def runs(tmp_path_factory):
    root = tmp_path_factory.mktemp("runs")
    for name, case, plugins in (("tank", TANK, ["reflective", "netcdf"]),
                                ("column", COLUMN, ["reflective", "netcdf", "vtu"]),
                                ("probed", PROBED, ["reflective", "probes"])):
        s = run_case(root / name, case, plugins=plugins)
        assert s["status"] == "completed", s["message"]
    return root


def script(name, *args):
    return subprocess.run([sys.executable, str(SCRIPTS / name), *map(str, args)], capture_output=True, text=True,
                          check=False)


def refused(res, name, path):
    """Exit status 2 and one line on stderr, ``<script>: error: ...`` naming ``path``."""
    assert res.returncode == 2, (res.returncode, res.stdout, res.stderr)
    assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr, res.stderr
    assert res.stderr.startswith(f"{name}: error: ") and str(path) in res.stderr, res.stderr


def png(path):
    assert path.is_file() and path.read_bytes()[:4] == b"\x89PNG" and path.stat().st_size > 5000, path
    return True


# ---------------------------------------------------------------------------- every script


def test_the_toolkit_is_these_scripts():
    """A script added to postprocessing/ joins the tests below; runs.py is their shared reader,
    wave_theory.py the wave maker's linear theory, heave_theory.py a floating box's and
    sloshing_theory.py a tank's modes and a free decay's measures (modules that read no run;
    heave_theory's own tests check its command)."""
    assert sorted(p.name for p in SCRIPTS.glob("*.py")) == sorted(TOOLKIT + ["runs.py", "wave_theory.py",
                                                                              "heave_theory.py", "sloshing_theory.py"])


@pytest.mark.parametrize("name", TOOLKIT)
def test_help_says_what_a_script_reads_and_writes(name):
    res = script(name, "--help")
    assert res.returncode == 0 and res.stderr == "", res.stderr
    assert res.stdout.startswith(f"usage: {name} ") and "Reads " in res.stdout and "Writes " in res.stdout


@pytest.mark.parametrize("path", STUDIES, ids=str)
def test_every_study_answers_help(path):
    """The studies import what they use (sphcore's in-process API, the gauges)."""
    res = subprocess.run([sys.executable, str(ROOT / path), "--help"], capture_output=True, text=True, check=False)
    assert res.returncode == 0 and res.stdout.startswith(f"usage: {path.name} "), res.stderr


def test_every_validation_page_module_defines_the_build_interface():
    """validation/build.py's contract with a page module: NAME (the file's name), TITLE and
    build(runs, figures, rerun), and a page docs/validation/<NAME>.md that includes the table
    the build writes. Loading the modules runs nothing."""
    spec = importlib.util.spec_from_file_location("validation_build", ROOT / "validation" / "build.py")
    build = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(build)
    pages = build.discover()
    assert sorted(pages) == sorted(p.stem for p in PAGES if not p.name.startswith("_"))
    for name, mod in pages.items():
        assert callable(mod.build) and mod.TITLE, name
        page = ROOT / "docs" / "validation" / f"{name}.md"
        assert page.is_file() and f"tables/{name}.md" in page.read_text(), page


def test_no_script_edits_sys_path_or_guesses_its_imports():
    for path in [*SCRIPTS.glob("*.py"), *(ROOT / "validation").rglob("*.py")]:
        text = path.read_text()
        assert not re.search(r"sys\.path\s*[.\[=+]", text), path
        assert not re.search(r"except \(?(ImportError|ModuleNotFoundError)", text), path


@pytest.mark.parametrize("name", TOOLKIT)
def test_an_empty_or_missing_directory_is_refused(tmp_path, name):
    for path in (tmp_path, tmp_path / "missing"):
        refused(script(name, *FIRST.get(name, []), path, *EXTRA.get(name, [])), name, path)


# ---------------------------------------------------------------------------- frames: wavefront, pressure profile


def test_wavefront_of_a_dam_break(runs):
    """The column is 3 dx wide: the front starts at its edge, 0.06 m, and hardly moves in 4 ms;
    the .pvd (vtu) and particles.nc (netcdf) of the same run give the same front."""
    out = runs / "column" / "output"
    before = {p: p.stat().st_mtime_ns for p in out.rglob("*")}
    res = script("wavefront.py", out)
    assert res.returncode == 0, res.stderr
    for p, mtime in before.items():  # nothing sph wrote is touched
        assert p.stat().st_mtime_ns == mtime, p
    assert (out / "wavefront.csv").read_text().splitlines()[0] == "t_s,x_front_m"
    front = np.loadtxt(out / "wavefront.csv", delimiter=",", skiprows=1)
    assert front.shape[0] >= 2 and front[0, 0] == 0.0 and np.all(np.diff(front[:, 0]) > 0)
    assert front[0, 1] == pytest.approx(0.06, abs=1e-9)
    assert np.all((front[:, 1] >= 0.06 - 1e-9) & (front[:, 1] < 0.07))
    assert png(out / "wavefront.png")
    printed = dict(line.split() for line in res.stdout.splitlines())
    assert {"x_front_0.10s_m", "err_cruchaga_0.10s", "rms_rel_err_martin_moyce_T3"} <= printed.keys()
    assert printed["x_front_0.10s_m"] == "nan"  # the run ends at 4 ms: no experiment's time is reached
    from_nc = script("wavefront.py", out / "particles.nc", "--csv", out / "nc.csv", "--png", out / "nc.png")
    assert from_nc.returncode == 0, from_nc.stderr
    np.testing.assert_array_equal(np.loadtxt(out / "nc.csv", delimiter=",", skiprows=1), front)


def test_pressure_profile_of_a_tank_at_rest(runs):
    """Modified pressure keeps the tank exactly hydrostatic: every layer mean is rho g (H - y),
    the default H being the block's 0.2 m, and the largest error printed is 0."""
    out = runs / "tank" / "output"
    res = script("pressure_profile.py", out)
    assert res.returncode == 0, res.stderr
    head = (out / "pressure_profile.csv").read_text().splitlines()[0]
    assert head == "y_m,p_mean_pa,p_min_pa,p_max_pa,p_hydrostatic_pa,rel_err"
    prof = np.loadtxt(out / "pressure_profile.csv", delimiter=",", skiprows=1)
    np.testing.assert_allclose(prof[:, 0], np.arange(0.01, 0.2, 0.02), atol=1e-9)  # 10 layers, centres
    np.testing.assert_allclose(prof[:, 1], prof[:, 4], rtol=1e-9)
    np.testing.assert_allclose(prof[:, 4], RHO_G * (0.2 - prof[:, 0]), rtol=1e-6)
    assert np.all(prof[:, 2] <= prof[:, 1]) and np.all(prof[:, 1] <= prof[:, 3])
    assert "below the top two layers: 0.000%" in res.stdout
    assert png(out / "pressure_profile.png")


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
    out = runs / kind / "output"
    refused(script(name, out), name, out)


@pytest.mark.parametrize("name", ["wavefront.py", "pressure_profile.py"])
def test_a_run_without_frames_is_refused(runs, name):
    out = runs / "probed" / "output"
    refused(script(name, out), name, out)


# ---------------------------------------------------------------------------- probes: probes, spheric_test2, peer_series


def test_probes_of_a_tank_at_rest(runs):
    """The floor sensor reads rho g H (H = 0.3 m) and the depth gauge 0.3 m, within dx / 2."""
    out = runs / "probed" / "output"
    res = script("probes.py", out)
    assert res.returncode == 0, res.stderr
    lines = dict(line.split(": ", 1) for line in res.stdout.splitlines())
    p1, h2 = (float(lines[k].split()[1]) for k in ("P1", "H2"))
    assert lines["P1"].split()[2] == "Pa" and lines["H2"].split()[2] == "m"
    assert p1 == pytest.approx(RHO_G * 0.3, rel=0.02)
    assert h2 == pytest.approx(0.3, abs=0.01)
    assert png(out / "probe_P1.png") and png(out / "probe_H2.png")


def test_spheric_test2_compares_the_probes_it_finds(runs):
    """P1 and H2 only: the tank is 0.3 m deep from t = 0, so H2 reads ~0.3 m where the
    experiment's H2 is still dry (its RMS error is ~0.3 m), the front "arrives" at t = 0 and
    P1 (rho g H = 2.9 kPa > 2 kPa) impacts at once, with a peak of rho g H."""
    out = runs / "probed" / "output"
    res = script("spheric_test2.py", out)
    assert res.returncode == 0, res.stderr
    assert "  H1:" not in res.stdout and "  P2:" not in res.stdout
    rms = float(re.search(r"H2: depth RMS error ([0-9.]+) m", res.stdout).group(1))
    assert rms == pytest.approx(0.3, abs=0.01)
    assert "depth > 0.02 m at 0.0000 s" in res.stdout
    impact = re.search(r"P1: first impact \(p > 2000 Pa\) at ([0-9.]+) s .* peak ([0-9]+) Pa", res.stdout)
    assert float(impact.group(1)) == 0.0
    assert float(impact.group(2)) == pytest.approx(RHO_G * 0.3, rel=0.02)
    assert png(out / "spheric_test2_depths.png") and png(out / "spheric_test2_pressures.png")


def test_spheric_test2_refuses_a_run_without_its_probes(runs, tmp_path):
    (tmp_path / "probes.csv").write_text("time_s,other_pa\n0,1\n0.001,2\n")
    refused(script("spheric_test2.py", tmp_path), "spheric_test2.py", tmp_path / "probes.csv")


def test_peer_series_scores_a_runs_csv_column(runs):
    """The run's probes.csv read as a peer's file (--column P1_pa): the tank's floor pressure,
    about rho g H with H = 0.3 m, is above 0.1 rho g H from the first sample, so its first
    rise is at tau = 0, ahead of Buchner's by the experiment's own rise time."""
    from sphcore_plugins.gauges import reference
    from sphcore_plugins.probes import figures

    csv = runs / "probed" / "output" / "probes.csv"
    res = script("peer_series.py", csv, "--column", "P1_pa", *EXTRA["peer_series.py"])
    assert res.returncode == 0, res.stderr
    out = dict(line.split(" = ") for line in res.stdout.splitlines())
    exp = reference.series("buchner_2002_P1")
    assert float(out["rise_dtau"]) == pytest.approx(-figures.first_rise(exp[:, 0], exp[:, 1]), abs=1e-3)
    assert out["mae_rhogH"] == "nan"  # 4 ms never reach the scored window, t sqrt(g/H) in [2.6, 5.5]
    missing = script("peer_series.py", csv, "--column", "P9_pa", *EXTRA["peer_series.py"])
    refused(missing, "peer_series.py", csv)
    assert "--column P9_pa" in missing.stderr
