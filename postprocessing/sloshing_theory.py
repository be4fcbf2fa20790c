"""Sloshing in a 2D rectangular tank, without a run: the linear natural periods of its
modes, and the measures of a free decay (zero crossings, amplitudes, logarithmic decrement,
a damped sine fitted by least squares).

No run is read here: postprocessing/sloshing.py measures a run's gauges with these, and
validation/pages/sloshing.py tabulates them. SI units; g = 9.81 m/s^2 unless given.

    omega^2 = g k tanh(k h),  k = mode pi / L        (linear theory of a rectangular tank)
"""

from __future__ import annotations

import math

import numpy as np

G = 9.81


# ----------------------------------------------------------------------------- theory

def linear_omega(length: float, depth: float, g: float = G, mode: int = 1) -> float:
    """Natural angular frequency (rad/s) of sloshing mode ``mode`` in a 2D rectangular
    tank, linear theory: omega^2 = g k tanh(k h), k = mode pi / L."""
    if not (length > 0 and depth > 0 and g > 0 and mode >= 1):
        raise ValueError("length, depth and g must be > 0 and mode >= 1")
    k = mode * math.pi / length
    return math.sqrt(g * k * math.tanh(k * depth))


def linear_period(length: float, depth: float, g: float = G, mode: int = 1) -> float:
    """Natural period (s) of sloshing mode ``mode``: 2 pi / :func:`linear_omega`."""
    return 2.0 * math.pi / linear_omega(length, depth, g, mode)


# ----------------------------------------------------------------------------- free decay

def crossings(t: np.ndarray, y: np.ndarray) -> np.ndarray:
    """Times at which ``y`` changes sign (linear interpolation between samples)."""
    s = np.signbit(y)
    k = np.flatnonzero(s[1:] != s[:-1])
    return t[k] - y[k] * (t[k + 1] - t[k]) / (y[k + 1] - y[k])


def smooth(t: np.ndarray, y: np.ndarray, width: float) -> np.ndarray:
    """Centred moving average of ``y`` over ``width`` (s; samples about evenly spaced): takes
    out the high-frequency ripple that would add zero crossings, without moving them."""
    if len(t) < 3:
        return y
    n = int(round(width / float(np.median(np.diff(t)))))
    if n < 2:
        return y
    n += 1 - n % 2  # odd: centred
    pad = np.pad(y, n // 2, mode="edge")
    return np.convolve(pad, np.ones(n) / n, mode="valid")


def decay(t: np.ndarray, eta: np.ndarray) -> dict:
    """Period, amplitudes and damping of an oscillation ``eta`` about zero: {period (s),
    crossings, amplitudes (m, the largest |eta| between successive crossings), delta (the
    logarithmic decrement per period), zeta}; NaN where the record is too short (fewer than
    three crossings for the period, two amplitudes for the damping)."""
    tc = crossings(t, eta)
    out = {"period": math.nan, "crossings": len(tc), "amplitudes": np.empty(0), "times": np.empty(0),
           "delta": math.nan, "zeta": math.nan}
    if len(tc) >= 3:
        slope = np.polyfit(np.arange(len(tc)), tc, 1)[0]
        out["period"] = 2.0 * slope
    amps, times = [], []
    for a, b in zip(tc[:-1], tc[1:]):
        inside = (t > a) & (t < b)
        if inside.any():
            k = np.flatnonzero(inside)[np.argmax(np.abs(eta[inside]))]
            amps.append(abs(eta[k]))
            times.append(t[k])
    amps, times = np.asarray(amps), np.asarray(times)
    out["amplitudes"], out["times"] = amps, times
    if len(amps) >= 2 and np.all(amps > 0):
        # half periods between successive amplitudes: delta per period = -2 * slope
        slope = np.polyfit(np.arange(len(amps)), np.log(amps), 1)[0]
        delta = -2.0 * slope
        out["delta"] = delta
        out["zeta"] = delta / math.sqrt(4.0 * math.pi ** 2 + delta ** 2)
    return out


def fit_damped(t: np.ndarray, eta: np.ndarray, period: float) -> dict:
    """Least-squares fit of eta = exp(-s (t - t0)) (a cos w (t - t0) + b sin w (t - t0))
    + c + d (t - t0), t0 = t[0]: linear in a, b, c, d for given (w, s), which a grid search
    refined four times finds near w = 2 pi / ``period``. Returns {period (2 pi / w, s), zeta
    (s / sqrt(s^2 + w^2)), amplitude (m, at t0), rms (m, of the residual)}; NaN where the
    record is too short or ``period`` is not finite. The straight line c + d t takes up a
    slow drift of the mean level, the fit's smoothing the high-frequency ripple."""
    out = {"period": math.nan, "zeta": math.nan, "amplitude": math.nan, "rms": math.nan}
    if not np.isfinite(period) or len(t) < 8 or t[-1] - t[0] < period:
        return out
    tau = t - t[0]

    def solve(w, s):
        e = np.exp(-s * tau)
        m = np.column_stack([e * np.cos(w * tau), e * np.sin(w * tau), np.ones_like(tau), tau])
        coef, *_ = np.linalg.lstsq(m, eta, rcond=None)
        r = eta - m @ coef
        return float(r @ r), coef

    w0 = 2.0 * math.pi / period
    w_lo, w_hi, s_lo, s_hi = 0.8 * w0, 1.2 * w0, 0.0, 0.2 * w0
    best = None
    for _ in range(5):
        for w in np.linspace(w_lo, w_hi, 21):
            for s in np.linspace(s_lo, s_hi, 21):
                cost, coef = solve(w, s)
                if best is None or cost < best[0]:
                    best = (cost, w, s, coef)
        _, w, s, _ = best
        dw, ds = (w_hi - w_lo) / 10.0, (s_hi - s_lo) / 10.0
        w_lo, w_hi, s_lo, s_hi = w - dw, w + dw, max(0.0, s - ds), s + ds
    cost, w, s, coef = best
    out.update(period=2.0 * math.pi / w, zeta=s / math.hypot(s, w), amplitude=float(math.hypot(coef[0], coef[1])),
               rms=math.sqrt(cost / len(t)))
    return out
