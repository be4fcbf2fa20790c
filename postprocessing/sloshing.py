"""Sloshing: the first mode of a tank against linear theory, and a rolled tank's wall
pressure against the SPHERIC benchmark's record.

Reads   RUN/probes.nc, written by the probes plugin (RUN: a run's output directory), its
        summary.json (the tank's size), and for ``roll`` the experiment's record.
Writes  RUN/sloshing_free.png (``free``: the gauges' surface elevation, the amplitudes
        fitted) or RUN/sloshing_roll.png (``roll``: sensor 1 over the experiment's two
        series), and prints a table.

``free RUN``: the depth gauges of a run (cases/sloshing_free) after the excitation stops
(``--after``, s). For each gauge and for the antisymmetric part of the two outermost
gauges, (left - right) / 2, which holds the odd modes only and not the slow drift of the mean
level that both gauges share: the surface elevation eta = depth less a straight line
fitted to it. Two measures: (1) the zero crossings of eta smoothed over T1/8 (linear
interpolation) give the period (a straight-line fit of the crossing times against their
count: T / 2 per crossing), the largest |eta| between successive crossings the amplitudes,
and a straight-line fit of their logarithms the logarithmic decrement delta per period,
hence the damping ratio zeta = delta / sqrt(4 pi^2 + delta^2); (2) a least-squares fit of
a damped sine over a straight line to eta itself (period, zeta, amplitude, and the rms of
what it leaves: the ripple). The fit's period is compared with linear theory,
omega^2 = g k tanh(k h), k = pi / L, L the tank's length and h the water depth (from the
case, or --length and --depth). Writes RUN/sloshing_free.png.

``roll RUN``: the pressure sensor (``--probe``, default the first pressure probe) of a run
of cases/sloshing_roll against the experiment's record (``--reference``, default
cases/sloshing_roll/reference/EXP_Pressure_SPHERIC_Benchmark#10.txt). The record's rows
alternate between two series, each with its own increasing times: an upper and a lower one
(the odd rows lie above the even rows in 99.9 % of the pairs; they read as the maximum and
the minimum of the raw signal over windows of about 5 ms, see
cases/sloshing_roll/reference/README.md). They are read apart; the experiment's peak is the
upper series' (the raw signal's maximum), and the curve compared sample by sample is the
midline, the mean of the two interpolated linearly at the run's sample times. Prints the
time and value of the largest pressure of simulation and experiment in each roll period
from T to 5 T (--period, s; the first four impact peaks), and the mean absolute error
against the midline over the first four periods, 0 to 4 T (within the run's own samples),
with the mean half-distance between the two series for scale. ``--shift`` (s) delays the simulation's record before the
comparison (the measured roll lags the prescribed sinusoid). Writes RUN/sloshing_roll.png.

``theory --length L --depth H``: the linear natural periods of the first modes.

A missing directory, a run without probes or a reference that cannot be read: one line on
stderr, exit status 2.

    python postprocessing/sloshing.py free cases/sloshing_free/output --after 3.957
    python postprocessing/sloshing.py roll cases/sloshing_roll/output
    python postprocessing/sloshing.py theory --length 1.0 --depth 0.3
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from runs import RunError, open_run, pyplot, refuse
from sloshing_theory import G, crossings, decay, fit_damped, linear_omega, linear_period, smooth  # noqa: F401

PROG = Path(__file__).name
FREE_PNG = "sloshing_free.png"
ROLL_PNG = "sloshing_roll.png"
REFERENCE = Path(__file__).resolve().parent.parent / "cases" / "sloshing_roll" / "reference" / \
    "EXP_Pressure_SPHERIC_Benchmark#10.txt"
ROLL_PERIOD = 1.63  # s, SPHERIC test 10
SMOOTH_PEAK = 0.005  # s: the simulation's peaks also from its record averaged over this long


def tank_size(config: dict) -> tuple[float | None, float | None]:
    """(length along x, water depth) of a run's case: the domain's x extent and the first
    fluid block's height above the floor; None where the case does not say."""
    dom = config.get("domain") or {}
    blocks = [b for b in config.get("blocks", []) if b.get("kind", "fluid") == "fluid"]
    length = depth = None
    if dom.get("min") is not None and dom.get("max") is not None:
        length = float(dom["max"][0]) - float(dom["min"][0])
    if blocks and blocks[0].get("max") is not None:
        floor = float(dom["min"][1]) if dom.get("min") is not None else float(blocks[0]["min"][1])
        depth = float(blocks[0]["max"][1]) - floor
    return length, depth


def _fmt(x, spec=".4f"):
    return "n/a" if x is None or not np.isfinite(x) else format(x, spec)


def free_decay(run, after: float = 0.0, until: float | None = None, length: float | None = None,
               depth: float | None = None) -> dict:
    """The free decay of a run's depth gauges from ``after`` to ``until`` (s): {length, depth,
    g, T1 (linear theory at the nominal depth), t_all, gauges (the depth probes), keep (the
    samples measured), t, level (the gauges' mean level, all samples), seen (its mean over
    the decay), drift (m/s), series: [(name, eta, decay, fit)], the last the antisymmetric
    part (left - right)/2}. Raises RunError where the run has no depth gauge or the case no
    tank size (and none is given)."""
    data = run.probes()
    t_all = data["t"]
    gauges = [p for p in data["probes"] if p["kind"] == "depth"]
    if not gauges:
        raise RunError(f"{run.dir}: no depth gauge among the probes (expected [[probes.depth]] near the end walls)")
    case_length, case_depth = tank_size(run.config)
    length = length if length is not None else case_length
    depth = depth if depth is not None else case_depth
    if length is None or depth is None:
        raise RunError(f"{run.dir}: the case gives no tank length or water depth: pass --length and --depth")
    g = float(np.linalg.norm(run.config.get("physics", {}).get("gravity", [0.0, -G])[:2])) or G
    t_theory = linear_period(length, depth, g)
    keep = (t_all >= after) & (t_all <= (until if until is not None else np.inf))
    t = t_all[keep]
    series = [(p["name"], p["values"][keep]) for p in gauges]
    if len(gauges) >= 2:
        # gauges ordered along x by name order in the case: the first and the last
        series.append((f"({gauges[0]['name']} - {gauges[-1]['name']})/2",
                       0.5 * (gauges[0]["values"][keep] - gauges[-1]["values"][keep])))
    out = {"length": length, "depth": depth, "g": g, "T1": t_theory, "t_all": t_all, "gauges": gauges,
           "keep": keep, "t": t, "after": after, "level": None, "seen": math.nan, "drift": math.nan, "series": []}
    if len(t) > 1:
        level = np.mean([p["values"] for p in gauges], axis=0)
        out.update(level=level, drift=float(np.polyfit(t, level[keep], 1)[0]), seen=float(level[keep].mean()))
    for name, v in series:
        if len(v) > 1:
            eta = v - np.polyval(np.polyfit(t, v, 1), t)  # without the drift of the mean level
            r = decay(t, smooth(t, eta, t_theory / 8.0))
        else:
            eta, r = v, decay(np.zeros(1), np.zeros(1))
        out["series"].append((name, eta, r, fit_damped(t, eta, r["period"])))
    return out


def plot_free(m: dict, ax) -> None:
    """The gauges less their mean over the decay, the antisymmetric part without its drift
    and its peaks, on ``ax`` (mm against s)."""
    keep, t_all = m["keep"], m["t_all"]
    for p in m["gauges"]:
        ax.plot(t_all, 1e3 * (p["values"] - (p["values"][keep].mean() if keep.any() else 0.0)), lw=0.8,
                label=p["name"])
    name, eta, r, _ = m["series"][-1]
    if len(m["t"]):
        ax.plot(m["t"], 1e3 * eta, "k-", lw=0.8, label=f"{name}, without its drift")
    if len(r["times"]):
        ax.plot(r["times"], 1e3 * r["amplitudes"], "k.", ms=4, label=f"|{name}| peaks")
    ax.axvline(m["after"], color="0.6", ls="--", lw=0.8)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("surface elevation [mm]")


def free(args) -> int:
    run = open_run(args.run)
    m = free_decay(run, args.after, args.until, args.length, args.depth)
    t, t_all, length, depth, g, t_theory = m["t"], m["t_all"], m["length"], m["depth"], m["g"], m["T1"]
    print(f"tank L = {length:g} m, water h = {depth:g} m, g = {g:g} m/s^2: linear theory "
          f"omega^2 = g k tanh(k h), k = pi/L: T1 = {t_theory:.4f} s")
    print(f"free decay from t = {t[0] if len(t) else args.after:g} s to {t[-1] if len(t) else math.nan:g} s "
          f"({len(t)} samples)")
    if m["level"] is not None:
        seen = m["seen"]
        print(f"the gauges' mean level: {m['level'][0]:.4f} m at t = {t_all[0]:g} s, {seen:.4f} m over the decay "
              f"(drifting {1e3 * m['drift']:+.2f} mm/s); linear theory at {seen:.4f} m: "
              f"T1 = {linear_period(length, seen, g):.4f} s")
    print("zero crossings (of the record smoothed over T1/8): T from their times, zeta from the logarithmic "
          "decrement of the peaks between them; fit: a damped sine over a straight line, to the record itself")
    print(f"{'gauge':<22} {'crossings':>9} {'T [s]':>8} {'zeta':>8} | {'fit T [s]':>9} {'T/T1-1':>8} {'zeta':>8} "
          f"{'a0 [mm]':>8} {'rms [mm]':>8}")
    for name, eta, r, f in m["series"]:
        err = f["period"] / t_theory - 1.0
        print(f"{name:<22} {r['crossings']:>9d} {_fmt(r['period']):>8} {_fmt(r['zeta'], '.4f'):>8} | "
              f"{_fmt(f['period']):>9} {_fmt(100 * err, '+.2f') + '%':>8} {_fmt(f['zeta'], '.4f'):>8} "
              f"{_fmt(1e3 * f['amplitude'], '.2f'):>8} {_fmt(1e3 * f['rms'], '.2f'):>8}")
    if not args.no_plot:
        plt = pyplot()
        fig, ax = plt.subplots(figsize=(8, 4))
        plot_free(m, ax)
        name, _, _, f = m["series"][-1]
        ax.set_title(f"{name}: T = {_fmt(f['period'])} s (linear theory {t_theory:.4f} s), "
                     f"zeta = {_fmt(f['zeta'], '.4f')}")
        ax.legend(fontsize=8)
        fig.tight_layout()
        png = run.dir / FREE_PNG
        fig.savefig(png, dpi=120)
        plt.close(fig)
        print(f"wrote {png}")
    return 0


# ----------------------------------------------------------------------------- roll

def read_reference(path: Path) -> tuple[tuple[np.ndarray, np.ndarray], tuple[np.ndarray, np.ndarray]]:
    """The two series of the SPHERIC test 10 pressure record, (upper, lower): the (t, p)
    of the odd and of the even data rows, each sorted by time, the one with the larger mean
    first. Lines that are not two numbers (the address and the header) are skipped."""
    try:
        text = Path(path).read_text(encoding="utf-8", errors="strict")
    except (OSError, UnicodeDecodeError) as err:
        raise RunError(f"{path}: cannot read the reference record: {err}") from None
    rows = []
    for line in text.splitlines():
        f = line.split()
        if len(f) != 2:
            continue
        try:
            rows.append((float(f[0]), float(f[1])))
        except ValueError:
            continue
    if len(rows) < 4:
        raise RunError(f"{path}: expected rows of time and pressure, found {len(rows)}")
    data = np.asarray(rows)
    out = []
    for part in (data[0::2], data[1::2]):
        order = np.argsort(part[:, 0], kind="stable")
        out.append((part[order, 0], part[order, 1]))
    if out[1][1].mean() > out[0][1].mean():
        out.reverse()
    return out[0], out[1]


def window_peaks(t, p, period, first=1, count=4):
    """(time, value) of the largest ``p`` in each window [k T, (k + 1) T), k = first ...
    first + count - 1; (nan, nan) for a window the record does not reach."""
    out = []
    for k in range(first, first + count):
        inside = (t >= k * period) & (t < (k + 1) * period)
        if inside.any():
            i = np.flatnonzero(inside)[np.argmax(p[inside])]
            out.append((float(t[i]), float(p[i])))
        else:
            out.append((math.nan, math.nan))
    return out


def roll_compare(run, reference: Path = REFERENCE, probe: str | None = None, period: float = ROLL_PERIOD,
                 shift: float = 0.0) -> dict:
    """A run's pressure sensor against the experiment's record: {probe (its name), t_sim,
    p_sim, upper (ta, pa), lower (tb, pb), T, shift, peaks: [(t_sim, p_sim, p_sim over 5 ms,
    t_exp, p_exp, midline)] for the windows T .. 5 T, peaks_5ms: [(t, p)] of the record
    averaged over 5 ms in the same windows, mae (Pa, 0 to 4 T against the
    midline), spread (Pa, the two series' mean half-distance), span (the samples compared)}.
    Raises RunError where the run has no such pressure probe or the record cannot be read."""
    data = run.probes()
    pressure = [p for p in data["probes"] if p["kind"] == "pressure"]
    if probe is not None:
        pressure = [p for p in pressure if p["name"] == probe]
    if not pressure:
        raise RunError(f"{run.dir}: no pressure probe" + (f" named {probe!r}" if probe else ""))
    sensor = pressure[0]
    t_sim, p_sim = data["t"] + shift, np.asarray(sensor["values"], float)
    (ta, pa), (tb, pb) = read_reference(reference)
    T = period
    exp_a = np.interp(t_sim, ta, pa, left=np.nan, right=np.nan)
    exp_b = np.interp(t_sim, tb, pb, left=np.nan, right=np.nan)
    exp = 0.5 * (exp_a + exp_b)
    # the experiment's mean on its own fine grid, for its peaks
    grid = np.union1d(ta, tb)
    exp_grid = 0.5 * (np.interp(grid, ta, pa) + np.interp(grid, tb, pb))
    smoothed = window_peaks(t_sim, smooth(t_sim, p_sim, SMOOTH_PEAK), T)
    peaks = [(ts, ps, pq, te, pe, pm) for (ts, ps), (_, pq), (te, pe), (_, pm) in
             zip(window_peaks(t_sim, p_sim, T), smoothed, window_peaks(ta, pa, T), window_peaks(grid, exp_grid, T))]
    window = (t_sim >= 0.0) & (t_sim <= 4 * T) & np.isfinite(exp)
    mae = float(np.mean(np.abs(p_sim[window] - exp[window]))) if window.any() else math.nan
    spread = float(np.mean(0.5 * np.abs(exp_a[window] - exp_b[window]))) if window.any() else math.nan
    span = (t_sim[window][0], t_sim[window][-1]) if window.any() else (math.nan, math.nan)
    return {"probe": sensor["name"], "t_sim": t_sim, "p_sim": p_sim, "upper": (ta, pa), "lower": (tb, pb), "T": T,
            "shift": shift, "peaks": peaks, "peaks_5ms": smoothed, "mae": mae, "spread": spread, "span": span}


def plot_roll(m: dict, ax) -> None:
    """The experiment's two series, the run's sensor and both sides' peaks on ``ax`` (Pa against s)."""
    (ta, pa), (tb, pb), t_sim = m["upper"], m["lower"], m["t_sim"]
    ax.plot(ta, pa, "-", color="0.75", lw=0.6, label="experiment, upper series")
    ax.plot(tb, pb, "-", color="0.55", lw=0.6, label="experiment, lower series")
    ax.plot(t_sim, m["p_sim"], "C0-", lw=0.9, label=f"sphcore {m['probe']}")
    for ts, ps, _, te, pe, _ in m["peaks"]:
        if np.isfinite(ts):
            ax.plot(ts, ps, "C0o", ms=4)
        if np.isfinite(te):
            ax.plot(te, pe, "ks", ms=4)
    ax.set_xlim(0, max(t_sim[-1] if len(t_sim) else 0.0, 5 * m["T"]))
    ax.set_xlabel("t [s]")
    ax.set_ylabel("pressure [Pa]")


def roll(args) -> int:
    run = open_run(args.run)
    m = roll_compare(run, args.reference, args.probe, args.period, args.shift)
    T, t_sim = m["T"], m["t_sim"]
    print(f"sensor {m['probe']!r} against {Path(args.reference).name}, roll period T = {T:g} s"
          + (f", simulation delayed by {args.shift:g} s" if args.shift else ""))
    print(f"p_sim: the largest sample; 5 ms: the largest of the record averaged over {1e3 * SMOOTH_PEAK:g} ms; "
          "p_exp: the upper series' largest; midline: the largest of the two series' mean")
    print(f"{'peak':>4} {'window [s]':>11} {'t_sim':>7} {'p_sim [Pa]':>10} {'5 ms':>6} {'t_exp':>7} "
          f"{'p_exp [Pa]':>10} {'midline':>8} {'dt [s]':>7} {'p_sim/p_exp':>11}")
    for k, (ts, ps, pq, te, pe, pm) in enumerate(m["peaks"], 1):
        lo, hi = k * T, (k + 1) * T
        print(f"{k:>4} {f'{lo:.2f}-{hi:.2f}':>11} {_fmt(ts, '.3f'):>7} {_fmt(ps, '.0f'):>10} {_fmt(pq, '.0f'):>6} "
              f"{_fmt(te, '.3f'):>7} {_fmt(pe, '.0f'):>10} {_fmt(pm, '.0f'):>8} {_fmt(ts - te, '+.3f'):>7} "
              f"{_fmt(ps / pe if pe else math.nan, '.2f'):>11}"
              + (" (the run ends inside this window)" if np.isfinite(ts) and t_sim[-1] < hi else ""))
    span = m["span"]
    print(f"mean absolute error, t = {_fmt(span[0], '.3f')} to {_fmt(span[1], '.3f')} s (first four periods "
          f"within the run): {_fmt(m['mae'], '.1f')} Pa against the midline; the experiment's upper and lower series lie "
          f"{_fmt(m['spread'], '.1f')} Pa from it on average")
    if not args.no_plot:
        plt = pyplot()
        fig, ax = plt.subplots(figsize=(9, 4))
        plot_roll(m, ax)
        ax.set_title(f"SPHERIC test 10, sensor 1: MAE (0-4T) = {_fmt(m['mae'], '.0f')} Pa")
        ax.legend(fontsize=8, loc="upper left")
        fig.tight_layout()
        png = run.dir / ROLL_PNG
        fig.savefig(png, dpi=120)
        plt.close(fig)
        print(f"wrote {png}")
    return 0


def theory(args) -> int:
    print(f"tank L = {args.length:g} m, water h = {args.depth:g} m, g = {args.g:g} m/s^2")
    print(f"{'mode':>4} {'omega [rad/s]':>14} {'T [s]':>8}")
    for n in range(1, args.modes + 1):
        w = linear_omega(args.length, args.depth, args.g, n)
        print(f"{n:>4} {w:>14.4f} {2 * math.pi / w:>8.4f}")
    return 0


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    sub = ap.add_subparsers(dest="command", required=True)
    f = sub.add_parser("free", help="first sloshing mode's period and damping from the depth gauges")
    f.add_argument("run", help="the run's output directory")
    f.add_argument("--after", type=float, default=0.0, help="s: analyse the gauges from this time on (the end of "
                   "the excitation; cases/sloshing_free: 3.957)")
    f.add_argument("--until", type=float, default=None, help="s: and up to this time (default: the end of the run)")
    f.add_argument("--length", type=float, default=None, help="m: tank length (default: the case's domain)")
    f.add_argument("--depth", type=float, default=None, help="m: water depth (default: the case's fluid block)")
    f.add_argument("--no-plot", action="store_true", help="print the table only")
    r = sub.add_parser("roll", help="sensor 1 of the SPHERIC sloshing benchmark against the experiment")
    r.add_argument("run", help="the run's output directory")
    r.add_argument("--reference", type=Path, default=REFERENCE, help="the experiment's pressure record")
    r.add_argument("--probe", default=None, help="pressure probe name (default: the first)")
    r.add_argument("--period", type=float, default=ROLL_PERIOD, help="s: roll period (default 1.63)")
    r.add_argument("--shift", type=float, default=0.0, help="s: delay the simulation's record by this much")
    r.add_argument("--no-plot", action="store_true", help="print the table only")
    th = sub.add_parser("theory", help="linear natural periods of a rectangular tank")
    th.add_argument("--length", type=float, required=True, help="m")
    th.add_argument("--depth", type=float, required=True, help="m")
    th.add_argument("--g", type=float, default=G, help="m/s^2 (default 9.81)")
    th.add_argument("--modes", type=int, default=3, help="how many modes (default 3)")
    args = ap.parse_args(argv)
    try:
        return {"free": free, "roll": roll, "theory": theory}[args.command](args)
    except (RunError, ValueError) as err:
        return refuse(PROG, err)


if __name__ == "__main__":
    sys.exit(main())
