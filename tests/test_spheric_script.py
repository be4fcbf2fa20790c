"""postprocessing/spheric_test2.py scores the experiment against itself as perfect, and its
impulse is the integral it claims (the script is what docs/validation/spheric_test2.md quotes)."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import script

from sphcore_plugins.gauges.reference import kleefsman


def _script():
    return script("spheric_test2")


def _as_run(exp, t1=2.0):
    keep = exp["t"] <= t1
    run = {"time": exp["t"][keep]}
    for name in ("H1", "H2", "H3", "H4", "P1", "P2", "P3", "P4"):
        run[name] = exp[name][keep]
    return run


def test_the_experiment_scored_against_itself_is_perfect():
    mod, exp = _script(), kleefsman()
    res = mod.compare(_as_run(exp), exp, None)
    for h in ("H1", "H2", "H3", "H4"):
        assert res[f"{h}_rms_m"] == pytest.approx(0.0, abs=1e-12)
    for p in ("P1", "P2", "P3", "P4"):
        r = res[p]
        assert r["arrival_error_s"] == 0.0 and r["peak_error"] == 0.0
        assert r["impulse_ratio"] == pytest.approx(1.0, rel=1e-12)
    for h in ("H1", "H2", "H3"):
        for _, run_s, exp_s in res[f"{h}_front"]:
            assert run_s == exp_s and np.isfinite(run_s)
    # P1 reaches 2 kPa at 0.394 s (the experiment file), its impulse over 0.2 s is about 1.4 kPa s
    assert 0.39 < res["P1"]["arrival_exp_s"] < 0.40
    assert 1000.0 < res["P1"]["impulse_exp_Pa_s"] < 2000.0


def test_a_run_that_ends_early_is_scored_on_its_own_window():
    """A record cut 0.1 s after P1's first impact, scored against the whole experiment:
    every pressure figure uses the window the cut record has, for both, so the truncated
    experiment still scores as perfect (impulse ratio 1, not 0.1 / 0.2 of it)."""
    mod, exp = _script(), kleefsman()
    cut = _as_run(exp, t1=0.395 + 0.1)
    res = mod.compare(cut, exp, None)
    r = res["P1"]
    assert r["window_s"] == pytest.approx(0.1, abs=0.0015)
    assert r["impulse_ratio"] == pytest.approx(1.0, rel=1e-12)
    assert r["peak_error"] == 0.0
    assert r["mean_peak_Pa"] == pytest.approx(r["mean_peak_exp_Pa"], rel=1e-12)


def test_a_record_run_late_shows_its_delay_at_every_probe():
    """The experiment played 25 ms late: every front arrival and every first impact reads
    +25 ms (within one 1 ms sample), so a clock offset shows as a constant delay."""
    mod, exp = _script(), kleefsman()
    late = _as_run(exp)
    late["time"] = late["time"] + 0.025
    res = mod.compare(late, exp, None)
    for h in ("H1", "H2", "H3"):
        for _, run_s, exp_s in res[f"{h}_front"]:
            assert run_s - exp_s == pytest.approx(0.025, abs=0.0011)
    for p in ("P1", "P2", "P3", "P4"):
        assert res[p]["arrival_error_s"] == pytest.approx(0.025, abs=0.0011)


def test_impulse_of_a_step_and_of_a_spike():
    mod = _script()
    t = np.linspace(0.0, 1.0, 1001)
    p = np.where(t >= 0.3, 5000.0, 0.0)
    ta = mod.arrival(t, p)
    assert ta == pytest.approx(0.3)
    assert mod.first_impulse(t, p, ta) == pytest.approx(5000.0 * mod.WINDOW_S, rel=1e-9)
    # one sample of 100 kPa adds its 1 ms share (100 Pa s) to the impulse and sets the peak
    spike = p.copy()
    spike[350] = 1e5
    assert mod.first_impulse(t, spike, ta) - mod.first_impulse(t, p, ta) == pytest.approx(95.0, rel=1e-9)
    assert mod.first_peak(t, spike, ta) == 1e5
    # the 10 ms running mean: a step keeps its height, one 1 ms sample counts a tenth
    assert mod.first_mean_peak(t, p, ta) == pytest.approx(5000.0, rel=1e-9)
    lone = np.where(t == t[350], 1e5, 0.0)
    assert mod.first_mean_peak(t, lone, 0.3) == pytest.approx(1e4, rel=1e-9)


def test_a_missing_run_prints_one_line_and_exits_2(tmp_path, capsys):
    assert _script().main([str(tmp_path / "nothing")]) == 2
    err = capsys.readouterr().err
    assert len(err.strip().splitlines()) == 1 and "nothing" in err
