"""Error figures of a wall-pressure series against the shipped experiments.

Used by the ``probes`` plugin (run summary) and by ``postprocessing/probes.py``, so both
print the same numbers. Everything is in the experiments' dimensionless form:
p* = p / (rho g H), time tau = t sqrt(g / H) (Buchner's t sqrt(g/H) and Lobovsky's t/T with
T = sqrt(H/g) are the same number); H is the initial column height, t = 0 at gate release.

Definitions
-----------
- **first rise**: the first time p* reaches ``RISE_THRESHOLD`` = 0.1, the time linearly
  interpolated between the two samples that bracket that first crossing. Applied in the
  same way to the experiment (its digitised points) and to the simulation (its samples);
  a series that never reaches 0.1 has no rise (NaN). 0.1 lies above the digitised
  experiments' noise before impact (|p*| < 0.03) and below every impact peak.
- **Buchner MAE**: mean of |p*_sim - p*_exp| over the experiment's points with tau in
  ``BUCHNER_WINDOW`` = [2.6, 5.5] that the simulation covers, the simulation linearly
  interpolated onto the experiment's times.
- **Lobovsky band fraction**: fraction of the simulation's samples with tau in
  ``LOBOVSKY_WINDOW`` = [2, 7] whose p* lies inside the experiment's 2.5-97.5 % band, the
  band linearly interpolated onto the simulation's times. **Peak**: the largest p* of the
  simulation in that window, against the band's peak range [max p2.5, max p97.5] over the
  same window (a peak inside that range is as high as the experiment's spread allows).
- **Offset** (both): the median over the same samples of p*_sim - p*_exp (Buchner: at the
  experiment's points; Lobovsky: against the band's median). It separates a systematic
  departure from noise: acoustic noise around the experiment leaves it near 0 however
  large the MAE, a flow that carries too much or too little pressure moves it. The median
  rather than the mean, so that the few samples of an impact's acoustic spikes do not set it.
- **Noise** (both): the RMS, over the simulation's samples in the scored window, of p*
  minus its centred moving average over ``NOISE_WINDOW`` = 0.05 in tau (12 ms at
  H = 0.6 m, 9 ms at H = 0.3 m): the acoustic ringing of a weakly compressible run, whose
  periods at c0 = 10 sqrt(2 g H) are a few ms, while the experiments' curves change over
  tens of ms. With the offset it says what the MAE or the band fraction is made of.
"""

from __future__ import annotations

import math

import numpy as np

from sphcore_plugins.gauges import reference

RISE_THRESHOLD = 0.1  # p / (rho g H) that marks the first rise
BUCHNER_WINDOW = (2.6, 5.5)  # t sqrt(g/H) over which the MAE is taken
LOBOVSKY_WINDOW = (2.0, 7.0)  # t / sqrt(H/g) over which the band fraction and the peak are taken
NOISE_WINDOW = 0.05  # tau: width of the centred moving average the noise is measured against


def scaled(t, p, rho, g, height):
    """(tau, p*) = (t sqrt(g/H), p / (rho g H)) as float arrays."""
    t, p = np.asarray(t, float), np.asarray(p, float)
    return t * math.sqrt(g / height), p / (rho * g * height)


def first_rise(tau, p, threshold=RISE_THRESHOLD) -> float:
    """First time ``p`` reaches ``threshold`` (interpolated between the bracketing samples); NaN if never."""
    tau, p = np.asarray(tau, float), np.asarray(p, float)
    above = np.flatnonzero(p >= threshold)
    if above.size == 0:
        return float("nan")
    i = int(above[0])
    if i == 0:
        return float(tau[0])
    t0, t1, p0, p1 = tau[i - 1], tau[i], p[i - 1], p[i]
    return float(t0 + (threshold - p0) / (p1 - p0) * (t1 - t0))


def noise(tau, ps, lo, hi, window=NOISE_WINDOW) -> float:
    """RMS of ps minus its centred moving average (width ``window`` in tau) over the samples
    with lo <= tau <= hi; NaN without samples there. ``tau`` ascending."""
    tau, ps = np.asarray(tau, float), np.asarray(ps, float)
    k = np.flatnonzero((tau >= lo) & (tau <= hi))
    if k.size == 0:
        return float("nan")
    csum = np.concatenate([[0.0], np.cumsum(ps)])
    a = np.searchsorted(tau, tau[k] - 0.5 * window, side="left")
    b = np.searchsorted(tau, tau[k] + 0.5 * window, side="right")
    return float(np.sqrt(np.mean((ps[k] - (csum[b] - csum[a]) / (b - a)) ** 2)))


def buchner(tau, ps, exp) -> dict:
    """MAE over ``BUCHNER_WINDOW`` and first rise of (tau, p*) against ``exp`` rows (tau, p*)."""
    lo, hi = BUCHNER_WINDOW
    sel = (exp[:, 0] >= lo) & (exp[:, 0] <= hi)
    if tau.size:
        sel &= (exp[:, 0] >= tau[0]) & (exp[:, 0] <= tau[-1])
    else:
        sel[:] = False
    diff = np.interp(exp[sel, 0], tau, ps) - exp[sel, 1] if sel.any() else np.full(1, np.nan)
    mae = float(np.mean(np.abs(diff)))
    rise, rise_exp = first_rise(tau, ps), first_rise(exp[:, 0], exp[:, 1])
    return {"mae_rhogH": mae, "offset_rhogH": float(np.median(diff)), "noise_rhogH": noise(tau, ps, lo, hi),
            "mae_points": int(sel.sum()),
            "rise_tau": rise, "rise_tau_exp": rise_exp, "rise_dtau": rise - rise_exp}


def lobovsky(tau, ps, band) -> dict:
    """Band fraction and peak over ``LOBOVSKY_WINDOW`` of (tau, p*) against ``band`` rows (tau, p2.5, median, p97.5)."""
    lo, hi = LOBOVSKY_WINDOW
    hi = min(hi, float(band[-1, 0]))
    sel = (tau >= lo) & (tau <= hi)
    # the band over the window: its rows inside it and its values at the window's ends
    inner = band[(band[:, 0] > lo) & (band[:, 0] < hi)]
    ends = np.array([[x] + [np.interp(x, band[:, 0], band[:, c]) for c in (1, 2, 3)] for x in (lo, hi)])
    win = np.concatenate([inner, ends])
    out = {"band_peak_lo_rhogH": float(win[:, 1].max()), "band_peak_median_rhogH": float(win[:, 2].max()),
           "band_peak_hi_rhogH": float(win[:, 3].max())}
    if not sel.any():
        return {**out, "in_band_fraction": float("nan"), "offset_rhogH": float("nan"), "noise_rhogH": float("nan"),
                "band_samples": 0,
                "peak_rhogH": float("nan"), "peak_tau": float("nan"), "peak_in_band": False}
    b_lo = np.interp(tau[sel], band[:, 0], band[:, 1])
    b_hi = np.interp(tau[sel], band[:, 0], band[:, 3])
    inside = (ps[sel] >= b_lo) & (ps[sel] <= b_hi)
    offset = float(np.median(ps[sel] - np.interp(tau[sel], band[:, 0], band[:, 2])))
    k = int(np.argmax(ps[sel]))
    peak = float(ps[sel][k])
    return {**out, "in_band_fraction": float(inside.mean()), "offset_rhogH": offset,
            "noise_rhogH": noise(tau, ps, lo, hi), "band_samples": int(sel.sum()),
            "peak_rhogH": peak,
            "peak_tau": float(tau[sel][k]),
            "peak_in_band": bool(out["band_peak_lo_rhogH"] <= peak <= out["band_peak_hi_rhogH"])}


def window_means(tau, ps, data, kind, width, lo=None, hi=None) -> list[tuple[float, float, float]]:
    """(start, simulation mean, experiment mean) of p* over consecutive windows of ``width``
    in tau, from ``lo`` to ``hi`` (the scored window when None); the experiment's value is
    the mean of its points (Buchner) or of its band's median (Lobovsky) in the window.
    A window without a sample of either side gives NaN on that side. Shows where a
    departure lies in time (an impact, a plateau, a second rise), which the MAE, the band
    fraction and the offset each fold into one number."""
    tau, ps = np.asarray(tau, float), np.asarray(ps, float)
    col = 2 if kind == "lobovsky" else 1
    default = LOBOVSKY_WINDOW if kind == "lobovsky" else BUCHNER_WINDOW
    lo = default[0] if lo is None else lo
    hi = default[1] if hi is None else hi
    rows = []
    for a in np.arange(lo, hi - 1e-12, width):
        b = min(a + width, hi)
        sim = ps[(tau >= a) & (tau < b)]
        exp = data[(data[:, 0] >= a) & (data[:, 0] < b), col]
        rows.append((float(a), float(sim.mean()) if sim.size else float("nan"),
                     float(exp.mean()) if exp.size else float("nan")))
    return rows


def errors(name, t, p, rho, g, height) -> dict:
    """Error figures of the series (t in s, p in Pa) against the shipped reference ``name``.

    ``rho`` (kg/m^3), ``g`` (m/s^2) and ``height`` (m, the column height H) set the scaling.
    Keys without a prefix (the plugin prefixes ``probe_<name>_``).
    """
    tau, ps = scaled(t, p, rho, g, height)
    kind = reference.SERIES[name].kind
    data = reference.series(name)
    return buchner(tau, ps, data) if kind == "buchner" else lobovsky(tau, ps, data)
