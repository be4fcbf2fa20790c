"""postprocessing/heave_theory.py: the linear heave radiation of a 2D floating rectangle in
finite depth and the free decay it gives. Each test checks physics the expansion must satisfy
(dispersion, energy, the long-wave limit, convergence in the modes, the decay's start and
fall) and the figures of the validation's box; the script refuses bad input with exit 2.

The module stands alone (the validation pages load it by itself, as they do wave_theory.py)."""

from __future__ import annotations

import importlib.util
import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "postprocessing" / "heave_theory.py"
_spec = importlib.util.spec_from_file_location("heave_theory_alone", SCRIPT)
ht = importlib.util.module_from_spec(_spec)
_spec.loader.exec_module(ht)

RHO, G = 1000.0, 9.81
BOX = {"beam": 0.2, "draft": 0.05, "depth": 0.3}  # the validation's box, mass rho B T = 10 kg/m
MASS = 10.0
EPS = np.finfo(float).eps


def script(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True, text=True,
                          check=False)


@pytest.mark.parametrize("omega", [1e-3, 0.1, 1.0, 9.0, 20.0, 100.0])
@pytest.mark.parametrize("depth", [0.05, 0.3, 3.0])
def test_wavenumbers_satisfy_their_dispersion_relations_to_round_off(omega, depth):
    """k0 tanh(k0 h) = omega^2/g to a few ulps; kn tan(kn h) = -omega^2/g to within a few times
    the change that one ulp of kn makes in kn tan(kn h) (near kn h = n pi the relation is steep:
    d/dk (k tan kh) = tan kh + kh / cos^2 kh), each kn on its own branch."""
    n, nu = 200, omega * omega / G
    k0, kn = ht.wavenumbers(omega, depth, n)
    assert abs(k0 * math.tanh(k0 * depth) - nu) <= 4 * EPS * nu
    khn = kn * depth
    assert np.all(khn > (np.arange(1, n + 1) - 0.5) * math.pi) and np.all(khn < np.arange(1, n + 1) * math.pi)
    one_ulp = (np.abs(np.tan(khn)) + khn / np.cos(khn) ** 2) * EPS * kn
    assert np.all(np.abs(kn * np.tan(khn) + nu) <= 4 * one_ulp)


@pytest.mark.parametrize("modes", [5, 20])
@pytest.mark.parametrize("omega", [0.05, 2.0, 9.0, 25.0])
@pytest.mark.parametrize("shape", [(0.2, 0.05, 0.3), (0.2, 0.1, 0.3), (1.0, 0.2, 0.5), (0.2, 0.05, 3.0)])
def test_damping_from_the_body_pressure_is_the_radiated_wave_energy(modes, omega, shape):
    """b33 from the pressure on the bottom equals 2 rho g eta^2 cg, the power of the waves going
    out on both sides (per unit velocity^2 / 2). The truncated expansion satisfies Green's
    identity exactly (both sides are Galerkin projections on the same modes), so the two agree
    to round-off (measured 8e-14) at any number of modes, not only when converged."""
    beam, draft, depth = shape
    r = ht.heave_coefficients(omega, beam, draft, depth, modes=modes)
    assert r["b33"] > 0.0
    assert r["b33_energy"] == pytest.approx(r["b33"], rel=1e-10)


def test_long_wave_limit_of_the_damping():
    """omega -> 0 in finite depth: the body's flux v B leaves as two long waves of speed
    sqrt(g h) and amplitude v B / (2 sqrt(g h)), whose power is the damping's
    b33 -> rho B^2 sqrt(g/h) / 2 (114.368 N s/m^2 for the box). The first correction is
    O((k0 h)^2) (measured: a deficit of 0.112 (k0 h)^2): b33 is within 0.2 (k0 h)^2 of the limit
    and the deficit falls as omega^2 (a quarter when omega halves)."""
    limit = RHO * BOX["beam"] ** 2 * math.sqrt(G / BOX["depth"]) / 2
    deficit = {}
    for omega in (0.05, 0.1):
        r = ht.heave_coefficients(omega, **BOX, modes=20)
        kh = r["k0"] * BOX["depth"]
        deficit[omega] = (limit - r["b33"]) / limit
        assert 0.0 < deficit[omega] < 0.2 * kh * kh, (omega, deficit[omega], kh)
    assert deficit[0.05] / deficit[0.1] == pytest.approx(0.25, rel=0.02)


@pytest.mark.parametrize("omega", [2.0, 9.0])
def test_doubling_the_modes_changes_the_coefficients_little_and_as_one_over_m_squared(omega):
    """The corner of the body limits the convergence to 1/M^2: from 40 to 80 cosine terms a33
    and b33 change by under 1e-4 of their value (measured 1-7e-5 and 3-14e-5 at omega = 2 and
    9 rad/s, 0.04 and 0.83 in omega^2 B/(2g)), about a quarter of their change from 20 to 40."""
    r = {m: ht.heave_coefficients(omega, **BOX, modes=m) for m in (20, 40, 80)}
    for key in ("a33", "b33"):
        coarse, fine = abs(r[40][key] - r[20][key]), abs(r[80][key] - r[40][key])
        assert fine < 2e-4 * abs(r[80][key]), (key, fine)
        assert fine < coarse / 3, (key, coarse, fine)


def test_the_box_of_the_validation():
    """B = 0.2 m, T = 0.05 m, h = 0.3 m, m = rho B T = 10 kg/m: the figures the validation page
    compares a run with (converged in the modes to 1e-4; the first eigenfunction-matching
    estimate, with twice the evanescent modes of the cosine terms, gave C33 1.413, b' 0.714,
    T 0.697 s, delta 1.02)."""
    nat = ht.natural_period(MASS, **BOX, modes=40)
    assert nat["period"] == pytest.approx(0.6966, abs=5e-4)
    assert nat["C33"] == pytest.approx(1.4116, abs=1e-3)
    assert nat["b_vugts"] == pytest.approx(0.7140, abs=1e-3)
    assert nat["delta"] == pytest.approx(1.021, abs=5e-3)
    stiffness = RHO * G * BOX["beam"]
    assert nat["omega"] ** 2 * (MASS + nat["a33"]) == pytest.approx(stiffness, rel=1e-10)


def test_free_decay_starts_at_one_at_rest_and_decays():
    """x(0)/x0 = (2 c / pi) int b33 / |c - omega^2 (m + a33) - i omega b33|^2 d omega = 1 is the
    Kramers-Kronig relation between a33 and b33 (it holds to 1e-5 at 40 modes); the body leaves
    x0 at rest, as 1 - c t^2 / (2 (m + a33(inf))) (at release only the added mass of infinite
    frequency acts); the extrema alternate in sign, fall in magnitude, and settle to a constant
    interval and ratio; those of the validation's box are the first estimate's
    (trough 0.371 s -0.552, crest 0.713 s +0.344, crest 2.066 s +0.056) to 1e-3."""
    t = np.linspace(0.0, 2.5, 1251)
    dec = ht.free_decay(MASS, **BOX, t=t, modes=40)
    x, te, xe = dec["x"], dec["t_extrema"], dec["x_extrema"]
    assert x[0] == pytest.approx(1.0, abs=1e-4)
    stiffness = RHO * G * BOX["beam"]
    a_inf = ht.heave_coefficients(dec["omega"][-1], **BOX, modes=40)["a33"]
    for k in (2, 3, 4):  # zero slope: the fall from x(0) is the parabola's, no linear term
        assert (x[0] - x[k]) == pytest.approx(0.5 * stiffness / (MASS + a_inf) * t[k] ** 2, rel=0.05)
    assert len(te) >= 6
    assert np.all(xe[:-1] * xe[1:] < 0.0) and np.all(np.abs(xe[1:]) < np.abs(xe[:-1])) and abs(xe[0]) < 1.0
    # a33 and b33 vary with the frequency: the decay's half-periods settle at the pole's, 3 %
    # shorter than the undamped natural period's half (0.338 s against 0.348 s), its
    # decrements at 0.90 per cycle (small damping at the natural frequency: 1.02)
    period = ht.natural_period(MASS, **BOX, modes=40)["period"]
    half = np.diff(te)
    assert half == pytest.approx(0.5 * period, rel=0.05)
    assert half[-1] == pytest.approx(half[-2], rel=1e-3) and half[-1] < 0.5 * period
    assert dec["deltas"][-1] == pytest.approx(dec["deltas"][-2], rel=0.01)
    assert dec["deltas"][-1] == pytest.approx(0.90, abs=0.01)
    assert te[[0, 1, 5]] == pytest.approx([0.371, 0.713, 2.066], abs=1.5e-3)
    assert xe[[0, 1, 5]] == pytest.approx([-0.552, 0.344, 0.056], abs=1e-3)


def test_extrema_of_a_sampled_cosine():
    """The parabola through three samples finds the extrema of cos(2 pi t) between samples."""
    t = np.linspace(0.013, 2.2, 300)
    te, xe = ht.extrema(t, np.cos(2 * math.pi * t))
    assert te == pytest.approx([0.5, 1.0, 1.5, 2.0], abs=1e-4)
    assert xe == pytest.approx([-1.0, 1.0, -1.0, 1.0], abs=1e-3)


def test_cubic_interpolation_is_exact_for_a_quadratic():
    """Hermite cubics with second-order slopes reproduce a quadratic on an uneven grid (the
    free decay interpolates a33 and b33 with them)."""
    xp = np.array([0.0, 0.3, 1.0, 1.2, 2.5, 4.0])
    x = np.linspace(0.0, 4.0, 97)
    assert ht.cubic(x, xp, 3 - 2 * xp + 0.7 * xp ** 2) == pytest.approx(3 - 2 * x + 0.7 * x ** 2, abs=1e-12)


def test_the_script_prints_the_figures():
    res = script("--beam", 0.2, "--draft", 0.05, "--depth", 0.3, "--mass", 10, "--modes", 20, "--periods", 1.8)
    assert res.returncode == 0, res.stderr
    out = res.stdout
    for text in ("natural period  0.69", "C33 = a33/(rho B T) = 1.41", "sqrt(B/(2g)) = 0.71", "log decrement"):
        assert text in out, out
    rows = [ln.split() for ln in out.splitlines() if ln.startswith("   ") and ln.split()[0][0].isdigit()]
    assert len(rows) == 3 and float(rows[0][0]) == pytest.approx(0.371, abs=2e-3), out


@pytest.mark.parametrize("args, name", [
    (("--beam", 0, "--draft", 0.05, "--depth", 0.3), "beam"),
    (("--beam", 0.2, "--draft", -0.05, "--depth", 0.3), "draft"),
    (("--beam", 0.2, "--draft", 0.3, "--depth", 0.3), "draft"),
    (("--beam", 0.2, "--draft", 0.05, "--depth", 0.3, "--mass", 0), "mass"),
    (("--beam", 0.2, "--draft", 0.05, "--depth", "nan"), "depth"),
    (("--beam", 0.2, "--draft", 0.05, "--depth", 0.3, "--modes", 0), "modes"),
])
def test_the_script_refuses_bad_input(args, name):
    """One line on stderr, ``heave_theory.py: error: ...`` naming the argument, exit status 2."""
    res = script(*args)
    assert res.returncode == 2, (res.returncode, res.stdout, res.stderr)
    assert len(res.stderr.strip().splitlines()) == 1 and "Traceback" not in res.stderr, res.stderr
    assert res.stderr.startswith("heave_theory.py: error: ") and name in res.stderr, res.stderr
    assert res.stdout == ""
