"""The wave flume (cases/wave_flume) and its post-processing (postprocessing/wave_flume.py):
the shipped cases pass ``sph check``, Biesel's transfer function and the dispersion relation
match known values, and a coarse, short version of the case runs and is measured (exit 0,
the table printed, the PNG written). The full runs, which give the README's numbers, are
``slow``."""

from __future__ import annotations

import importlib.util
import math
import subprocess
import sys
import types
from pathlib import Path

import numpy as np
import pytest
import tomllib

from sphcore.testing import case_with, run_case

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "postprocessing" / "wave_flume.py"
CASES = [ROOT / "cases" / "wave_flume", ROOT / "cases" / "wave_flume_kh18"]
FLAP = ROOT / "cases" / "wave_flume_flap"


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


def test_the_theory_stands_alone_and_is_the_scripts():
    """postprocessing/wave_theory.py needs no run and no sibling (the validation pages load
    it by itself); the script measures against the same functions."""
    path = SCRIPT.parent / "wave_theory.py"
    spec = importlib.util.spec_from_file_location("wave_theory_alone", path)
    theory = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(theory)
    for name in ("wavenumber", "biesel", "flap", "group_velocity", "evanescent_wavenumbers", "havelock",
                 "recorded_elevation"):
        assert getattr(wf, name).__code__.co_code == getattr(theory, name).__code__.co_code, name
    assert theory.havelock(2 * math.pi / 1.1494, 0.25, 0.032)["amplitude"] == pytest.approx(29.34, abs=0.01)


def test_a_recorded_sine_stroke_makes_the_regular_wave_of_the_transfer_function():
    """X = S/2 sin(omega t) over whole periods (no padding: the record is periodic) gives
    eta = (H/S) S/2 cos(kx - omega t) at every x, for the piston and the flap; a stroke of
    the opposite sign gives the opposite elevation."""
    h, period, s = 0.4, 0.8, 0.03
    omega = 2 * math.pi / period
    t = np.arange(0, 10 * period, 0.01)[:1000]
    stroke = 0.5 * s * np.sin(omega * t)
    k = float(wf.wavenumber(omega, h))
    for transfer in (wf.biesel, wf.flap):
        for x in (0.0, 1.16, 2.66):
            eta = wf.recorded_elevation(t, stroke, h, x, transfer, n_fft=t.size)
            want = transfer(k * h) * 0.5 * s * np.cos(k * x - omega * t)
            np.testing.assert_allclose(eta, want, atol=1e-12)
            np.testing.assert_allclose(wf.recorded_elevation(t, -stroke, h, x, transfer, n_fft=t.size), -want,
                                       atol=1e-12)


def test_biesel_goes_from_kh_in_shallow_water_to_two_in_deep_water():
    kh = np.array([1e-3, 1e-2, 0.05])
    assert np.all(np.abs(wf.biesel(kh) / kh - 1.0) < kh ** 2)  # H/S = kh (1 + O(kh^2))
    np.testing.assert_allclose(wf.biesel([8.0, 15.0]), 2.0, rtol=1e-5)
    # 2 (cosh 2 - 1) / (sinh 2 + 2) at kh = 1 and its value at kh = 1.8
    assert wf.biesel(1.0) == pytest.approx(2 * (math.cosh(2) - 1) / (math.sinh(2) + 2), rel=1e-14)
    assert wf.biesel(1.0) == pytest.approx(0.98179, abs=1e-5)
    assert wf.biesel(1.8) == pytest.approx(1.58213, abs=1e-5)
    assert np.all(np.diff(wf.biesel(np.linspace(0.01, 6, 200))) > 0)


def test_the_flaps_transfer_function_goes_from_half_kh_to_two_and_stays_below_the_pistons():
    kh = np.array([1e-3, 1e-2, 0.05])
    assert np.all(np.abs(wf.flap(kh) / (kh / 2.0) - 1.0) < kh ** 2)  # H/S = kh/2 (1 + O(kh^2))
    big = np.array([15.0, 25.0])
    np.testing.assert_allclose(wf.flap(big), 2.0 * (big - 1.0) / big, rtol=1e-6)  # 2 - 2/kh in deep water
    assert wf.flap(1.0) == pytest.approx(0.52809, abs=1e-5)
    grid = np.linspace(0.01, 6, 200)
    assert np.all(wf.flap(grid) < wf.biesel(grid)) and np.all(np.diff(wf.flap(grid)) > 0)


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


# Havelock's force on the piston: the flume's case is h = 0.25 m, S = 0.032 m, T = 1.1494 s (kh = 1)
ZETA3, ZETA5 = 1.2020569031595942, 1.0369277551433699  # Riemann zeta(3), zeta(5)


def _omega(kh, h=0.25, g=9.81):
    return math.sqrt(g * kh / h * math.tanh(kh))


@pytest.mark.parametrize("kh", [0.01, 1.0, 1.8, 30.0])
def test_the_standing_wavenumbers_solve_their_dispersion_relation(kh):
    g, h, n = 9.81, 0.25, 300
    omega = _omega(kh, h, g)
    kj = wf.evanescent_wavenumbers(omega, h, n, g)
    j = np.arange(1, n + 1)
    assert np.all(((j - 0.5) * math.pi < kj * h) & (kj * h < j * math.pi))
    # the residual as an error in kj h (d tan / d(kh) = 1 / cos^2): near j pi, tan(kj h) itself
    # carries the rounding of kj h over its small distance from j pi
    err = (-g * kj * np.tan(kj * h) - omega ** 2) * np.cos(kj * h) ** 2 / (g * kj)
    assert np.all(np.abs(err) < 1e-13 * kj * h), np.abs(err / (kj * h)).max()


@pytest.mark.parametrize("kh", [0.3, 1.0, 1.8, 5.0])
def test_the_modes_are_complete_and_the_force_is_their_projection(kh):
    """Parseval: the piston's uniform profile projected on cosh k(h+z) and the cos kj(h+z) keeps
    all of int 1^2 dz = h; and the damping and added mass are the projections' sums computed by
    quadrature (10-point Gauss-Legendre on 100 slices of the depth), not by the closed forms
    havelock() uses."""
    g, h, rho, n = 9.81, 0.25, 1000.0, 60
    omega = _omega(kh, h, g)
    k = kh / h
    kj = wf.evanescent_wavenumbers(omega, h, n, g)
    s, w = np.polynomial.legendre.leggauss(10)
    edges = np.linspace(-h, 0.0, 101)
    z = (0.5 * (edges[1:] + edges[:-1])[:, None] + 0.5 * np.diff(edges)[:, None] * s).ravel()  # -h < z < 0
    w = np.tile(0.5 * (h / 100) * w, 100)
    f0 = np.cosh(k * (h + z))
    fj = np.cos(np.outer(kj, h + z))
    p0, n0 = w @ f0, w @ f0 ** 2
    pj, nj = fj @ w, fj ** 2 @ w
    gram = np.vstack([f0, fj[:6]]) * w @ np.vstack([f0, fj[:6]]).T  # orthogonal: a diagonal Gram matrix
    np.testing.assert_allclose(gram - np.diag(np.diag(gram)), 0.0, atol=1e-12 * n0)
    big = wf.evanescent_wavenumbers(omega, h, 20000, g)  # Pj^2 / Nj summed: the tail falls as 1/n^2
    standing = np.sum(4.0 * np.sin(big * h) ** 2 / (big * (np.sin(2.0 * big * h) + 2.0 * big * h)))
    assert p0 ** 2 / n0 + standing == pytest.approx(h, rel=1e-8)
    hv = wf.havelock(omega, h, 0.032, g, rho, n=n)
    assert hv["damping"] == pytest.approx(rho * omega * p0 ** 2 / (k * n0), rel=1e-12)
    assert hv["added_mass"] == pytest.approx(rho * np.sum(pj ** 2 / (kj * nj)), rel=1e-10)


@pytest.mark.parametrize("kh", [0.05, 0.5, 1.0, 1.8, 3.0, 8.0])
def test_the_paddles_mean_power_is_the_radiated_waves_energy_flux(kh):
    """B U0^2 / 2 = E cg with E = rho g H^2 / 8, H from Biesel's transfer function."""
    g, h, rho, S = 9.81, 0.25, 1000.0, 0.032
    omega = _omega(kh, h, g)
    hv = wf.havelock(omega, h, S, g, rho)
    flux = rho * g * (S * wf.biesel(kh)) ** 2 / 8.0 * wf.group_velocity(kh / h, h, g)
    assert 0.5 * hv["radiation"] * (0.5 * omega * S) == pytest.approx(flux, rel=1e-12)
    assert hv["power"] == pytest.approx(flux, rel=1e-12)
    assert hv["HS"] == pytest.approx(wf.biesel(kh), rel=1e-13)


def test_havelocks_force_in_shallow_and_deep_water():
    """kh -> 0: the impedance of a long wave, B = rho h sqrt(g h), and ma = 2 zeta(5) (kh)^4 / pi^5
    rho h^2 (the first standing mode's k1 h -> pi); deep water: B = 2 rho g^2 / omega^3 and ma
    rises to 14 zeta(3) / pi^3 rho h^2 = 0.5428 rho h^2, the rigid dam's in incompressible water
    (the free surface at p = 0; Westergaard 1933), the gap closing like 1/kh."""
    g, h, rho = 9.81, 0.25, 1000.0
    for kh in (1e-3, 1e-2, 0.1):
        hv = wf.havelock(_omega(kh, h, g), h, 0.01, g, rho)
        assert hv["damping"] / (rho * h * math.sqrt(g * h)) == pytest.approx(1.0, abs=kh ** 2)
        assert hv["added_mass"] / (rho * h * h) == pytest.approx(2.0 * ZETA5 * kh ** 4 / math.pi ** 5, rel=0.1 * kh)
    limit = 14.0 * ZETA3 / math.pi ** 3
    assert limit == pytest.approx(0.54275, abs=1e-5)
    last = 0.0
    for kh in (3.0, 10.0, 30.0, 100.0, 300.0):
        omega = _omega(kh, h, g)
        hv = wf.havelock(omega, h, 0.01, g, rho, n=max(100, int(10 * kh)))
        if kh >= 10.0:  # 1 - tanh kh and 2kh / sinh 2kh below 1e-7
            assert hv["damping"] == pytest.approx(2.0 * rho * g ** 2 / omega ** 3, rel=1e-7)
        ma = hv["added_mass"] / (rho * h * h)
        assert last < ma < limit and (kh < 10.0 or (limit - ma) * kh < 1.25), (kh, ma, (limit - ma) * kh)
        last = ma


def test_havelocks_force_converges_with_the_standing_modes_and_leads_the_displacement():
    g, h, rho, S = 9.81, 0.25, 1000.0, 0.032
    omega = 2.0 * math.pi / 1.1494  # cases/wave_flume: kh = 1
    hv = {n: wf.havelock(omega, h, S, g, rho, n=n) for n in (50, 100, 200, 1000)}
    y = omega ** 2 * h / g
    for n in (50, 100, 200):  # the tail after n standing modes: y^2 / (2 pi^5 n^4) rho h^2
        tail = rho * h * h * y ** 2 / (2.0 * math.pi ** 5) * (1.0 / n ** 4 - 1.0 / 1000 ** 4)
        assert hv[1000]["added_mass"] - hv[n]["added_mass"] == pytest.approx(tail, rel=0.05)
        assert hv[n]["amplitude"] == pytest.approx(hv[1000]["amplitude"], rel=1e-10)
    f = hv[100]
    assert f["kh"] == pytest.approx(1.0, abs=1e-4) and f["kj"].shape == (100,)
    assert f["amplitude"] == pytest.approx(math.hypot(f["inertia"], f["radiation"]), rel=1e-15)
    assert f["inertia"] == pytest.approx(f["added_mass"] * omega ** 2 * S / 2, rel=1e-15)
    assert f["radiation"] == pytest.approx(f["damping"] * omega * S / 2, rel=1e-15)
    # the flume's numbers: 29.34 N/m, nearly all of it with the velocity (phase 90.4 deg)
    assert f["amplitude"] == pytest.approx(29.34, abs=0.01) and f["added_mass"] == pytest.approx(0.3815, abs=1e-3)
    assert math.degrees(f["phase"]) == pytest.approx(90.36, abs=0.01)
    for kh in (0.2, 1.8, 5.0):  # F = amplitude sin(omega t + phase), X = S/2 sin(omega t): 90 to 180 deg
        f = wf.havelock(_omega(kh, h, g), h, S, g, rho)
        assert math.pi / 2 < f["phase"] < math.pi
        assert f["amplitude"] * math.cos(f["phase"]) == pytest.approx(-f["inertia"], rel=1e-12)


def test_the_paddle_force_is_measured_against_havelock(tmp_path):
    """A wall_loads.csv written from Havelock's force (rows: the mean over the interval that ends
    at t, the water's force on the piston, -F less the still water's) is read back to its
    amplitude and phase; the window stops where the far wall's reflection returns."""
    h, S, T, g, rho = 0.25, 0.032, 1.1494, 9.81, 1000.0
    omega = 2.0 * math.pi / T
    hv = wf.havelock(omega, h, S, g, rho)
    phase0 = 0.7  # the piston's X = S/2 sin(omega t + phase0)
    t = np.arange(0.0, 12.0, 0.01)
    a, b = omega * t[:-1] + phase0 + hv["phase"], omega * t[1:] + phase0 + hv["phase"]
    fx = np.r_[np.nan, -0.5 * rho * g * h * h - hv["amplitude"] * (np.cos(a) - np.cos(b)) / (omega * 0.01)]
    col = "domain.walls[0].motion.Fx"
    np.savetxt(tmp_path / wf.WALL_LOADS_CSV, np.column_stack([t, fx]), delimiter=",", header=f"t,{col}", comments="")
    k = float(wf.wavenumber(omega, h, g))
    m = {"load": "domain.walls[0].motion", "T": T, "h": h, "S": S, "g": g, "rho0": rho, "phase0": phase0, "ramp_start": 0.0,
         "ramp_end": T, "face": 0.0, "far": 3.5, "cg": wf.group_velocity(k, h, g)}
    force = wf.paddle_force(types.SimpleNamespace(dir=tmp_path), m)  # it reads run.dir only
    assert force["amplitude"] == pytest.approx(hv["amplitude"], rel=2e-4)  # the interval's mean: sinc
    assert force["phase"] == pytest.approx(hv["phase"], abs=1e-9)
    assert force["mean"] == pytest.approx(-0.5 * rho * g * h * h, rel=1e-9)
    assert force["reflection"] and force["to"] == pytest.approx(7.0 / m["cg"], abs=0.01)
    assert len(force["periods"]) == int((7.0 / m["cg"] - T) / T)
    np.testing.assert_allclose(force["periods"], hv["amplitude"], rtol=2e-4)
    assert force["theory"]["amplitude"] == pytest.approx(hv["amplitude"], rel=1e-12)


def test_wave_heights_are_crest_to_trough_of_whole_waves():
    t = np.linspace(0.0, 3.0, 3001)
    eta = 0.01 * np.sin(2 * math.pi * t + 0.3) + 0.2
    heights = wf.wave_heights(t, eta)
    assert len(heights) == 2
    np.testing.assert_allclose(heights, 0.02, rtol=1e-4)
    assert wf.wave_heights(t[:400], eta[:400]) == []


# ---------------------------------------------------------------------------- the cases


@pytest.mark.parametrize("case", CASES + [FLAP], ids=lambda p: p.name)
def test_the_shipped_cases_pass_sph_check(case):
    res = subprocess.run([sys.executable, "-m", "sphcore.cli", "check", str(case)], capture_output=True, text=True,
                         check=False)
    assert res.returncode == 0, res.stdout + res.stderr
    assert "ok: 2D" in res.stdout


def _tiny(tmp_path):
    """The case at dx = 0.05 m (5 particles over the depth) in a 2 m flume, T = 1 s, for 3 s:
    about two whole waves at G1 before the far wall's reflection."""
    case = tomllib.loads((CASES[0] / "case.toml").read_text())
    case = case_with(case, {"particles.dx": 0.05, "domain.planes[1].point": [2.0, 0.0], "blocks[0].max": [2.0, 0.25],
                            "time.t_end": 3.0, "probes.every_dt": 0.01,
                            "domain.planes[3].motion[0].period": 1.0, "domain.planes[3].motion[0].ramp": 0.5,
                            "probes.depth": [{"name": "G1", "point": [0.5, 0.0]},
                                             {"name": "G2", "point": [0.75, 0.0]}]})
    s = run_case(tmp_path / "tiny", case, plugins=["reflective", "probes", "wall_loads"])
    assert s["status"] == "completed", s["message"]
    return tmp_path / "tiny" / "output"


def test_a_tiny_flap_flume_is_measured_against_the_flaps_transfer_function(tmp_path):
    """The flap case at dx = 0.05 m in a 2 m flume for 3 s: the script takes the stroke at the
    still-water level, 2 h tan(amplitude), and the flap's transfer function, and gives no
    Havelock force (a piston's)."""
    case = tomllib.loads((FLAP / "case.toml").read_text())
    case = case_with(case, {"particles.dx": 0.05, "domain.planes[1].point": [2.0, 0.0], "blocks[0].max": [2.0, 0.25],
                            "time.t_end": 3.0, "probes.every_dt": 0.01,
                            "domain.planes[3].motion[0].period": 1.0, "domain.planes[3].motion[0].ramp": 0.5,
                            "probes.depth": [{"name": "G1", "point": [0.5, 0.0]}]})
    s = run_case(tmp_path / "tiny", case, plugins=["reflective", "probes", "wall_loads"])
    assert s["status"] == "completed", s["message"]
    out = tmp_path / "tiny" / "output"
    res = script(out)
    assert res.returncode == 0 and res.stderr == "", res.stdout + res.stderr
    assert "(a flap hinged at the floor)" in res.stdout and "Havelock" not in res.stdout
    m = wf.measure(wf.open_run(out))
    assert m["S"] == pytest.approx(2.0 * 0.25 * math.tan(math.radians(6.785)), rel=1e-12)
    assert m["biesel"] == pytest.approx(float(wf.flap(m["kh"])), rel=1e-14)
    assert m["rows"][0]["waves"] >= 1 and 0.2 < m["rows"][0]["HS"] / m["biesel"] < 2.0


def test_a_tiny_flume_runs_and_is_measured(tmp_path):
    out = _tiny(tmp_path)
    res = script(out)
    assert res.returncode == 0 and res.stderr == "", res.stdout + res.stderr
    assert "Biesel H/S = " in res.stdout and "window [s]" in res.stdout
    assert "G1" in res.stdout and "G2" in res.stdout and "piston force Fx" in res.stdout and "Havelock" in res.stdout
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


#: the nearest gauge's tolerance against Biesel per case: the shipped runs read -0.8 % at
#: kh = 1.0 and -6.4 % at kh = 1.8 (the shorter waves, 1.3 dx high, lose height on the way)
NEAREST = {"wave_flume": 0.05, "wave_flume_kh18": 0.10, "wave_flume_flap": 0.05}


@pytest.mark.slow
@pytest.mark.parametrize("case", CASES + [FLAP], ids=lambda p: p.name)
def test_the_full_flume_makes_biesels_waves_and_havelocks_force(case, tmp_path):
    """The shipped case as it is (the wall model, h_sml = 2 dx; 1.5 minutes a case on 2
    cores), as the README measures it: H/S at the nearest gauge within 5 % of Biesel's at
    kh = 1.0 (measured -0.8 %) and 10 % at kh = 1.8 (-6.4 %), extrapolated back to the
    piston within 5 % at both (-1.9 %, +0.6 %), and the piston's first-harmonic force within
    10 % of Havelock's (+3.2 %, -1.0 %). The flap (kh = 1.0): its nearest gauge within 5 % of
    the flap's transfer function (-1.0 %), no Havelock force (a piston's)."""
    from sphcore.run import runner

    out = tmp_path / "output"
    s = runner.run(case, quiet=True, output=out).summary
    assert s["status"] == "completed", s["message"]
    run = wf.open_run(out)
    m = wf.measure(run)
    rows = m["rows"]
    assert all(r["waves"] >= 1 for r in rows), [(r["name"], r["waves"]) for r in rows]
    hs = [r["HS"] for r in rows]
    assert abs(hs[0] / m["biesel"] - 1.0) < NEAREST[case.name], (hs, m["biesel"])
    _, at_piston = wf.decay(m)
    assert abs(at_piston / m["biesel"] - 1.0) < 0.05, (at_piston, m["biesel"])
    force = wf.paddle_force(run, m)
    if case == FLAP:
        assert force is None
        return
    assert force["amplitude"] == pytest.approx(force["theory"]["amplitude"], rel=0.10)
