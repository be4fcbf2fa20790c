"""SPHERIC test 2 (Kleefsman et al. 2005): a run's depth and pressure probes against the experiment.

Reads   RUN/probes.csv, written by the probes plugin of cases/dam_break_obstacle_3d (probes
        named H1-H4 and P1-P4; a run with some of them is compared on those), and the
        experiment shipped with sphcore (sphcore_plugins.gauges.reference.kleefsman).
Writes  RUN/spheric_test2_depths.png and RUN/spheric_test2_pressures.png (run and
        experiment, probe by probe) and prints, over the span the run covers (or --span):

- water depth H1-H4: RMS of (run - experiment) in m, the experiment interpolated at the
  run's sample times; for H1-H3 (dry at the start) the front's arrival, the first time the
  depth exceeds 0.02 m (one particle at the default resolution) and 0.05 m, for run and
  experiment alike: a constant delay from probe to probe is a clock, a growing one a speed;
- pressure P1-P4: first-impact time, the first time p exceeds 2 kPa (about 18 % of P1's
  peak; the same threshold for run and experiment), and the peak over the first impact
  (from that time to 0.2 s after it, or to the run's end if it ends sooner: the same
  window length for run and experiment, printed) in Pa, with the run's relative error;
- the peak of the 10 ms running mean over the same window (one 1 ms sample of an
  acoustic spike moves it by a tenth of its height);
- the impulse of the first impact, int p dt over the same window (Pa s), with the run's
  ratio to the experiment's: the load a structure responds to when the impact is short
  against its own period, and a figure that a few acoustic samples of a weakly
  compressible model hardly move (the peak is one sample).

A missing directory, a run without probes.csv or without any of these probes: one line on
stderr, exit status 2.

    python postprocessing/spheric_test2.py cases/dam_break_obstacle_3d/output
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from runs import RunError, open_run, pyplot, refuse

from sphcore_plugins.gauges.reference import kleefsman

PROG = Path(__file__).name
DEPTHS, PRESSURES = ("H1", "H2", "H3", "H4"), ("P1", "P2", "P3", "P4")
IMPACT_PA = 2000.0  # first-impact threshold (Pa)
FRONT_M = (0.02, 0.05)  # the front's arrival at a dry depth probe: depth above these (m)
WINDOW_S = 0.2  # the first impact's peak is searched this long after its arrival (s)
MEAN_S = 0.01  # the running mean of the smoothed peak (s)


def arrival(t, p, threshold=IMPACT_PA):
    """First time p > threshold (s), nan if never."""
    above = np.nonzero(p > threshold)[0]
    return float(t[above[0]]) if above.size else float("nan")


def _after(t, t_arrival, window):
    """The samples within ``window`` (s) after the first impact; None without one."""
    if not np.isfinite(t_arrival):
        return None
    return (t >= t_arrival) & (t <= t_arrival + window)


def first_peak(t, p, t_arrival, window=WINDOW_S):
    """Peak of p (Pa) within ``window`` (s) after the first impact."""
    w = _after(t, t_arrival, window)
    return float("nan") if w is None else float(p[w].max())


def first_mean_peak(t, p, t_arrival, width=MEAN_S, window=WINDOW_S):
    """Peak of the centred running mean of p over ``width`` (s; samples assumed evenly
    spaced), within ``window`` (s) after the first impact."""
    w = _after(t, t_arrival, window)
    if w is None or t.size < 2:
        return float("nan")
    k = max(int(round(width / float(np.median(np.diff(t))))), 1)
    if k > t.size:  # a record shorter than the mean's width has no such mean
        return float("nan")
    return float(np.convolve(p, np.ones(k) / k, mode="same")[w].max())


def first_impulse(t, p, t_arrival, window=WINDOW_S):
    """int p dt (Pa s, trapezoidal) within ``window`` (s) after the first impact."""
    w = _after(t, t_arrival, window)
    if w is None:
        return float("nan")
    tw, pw = t[w], p[w]
    return float(np.sum(0.5 * (pw[1:] + pw[:-1]) * np.diff(tw)))


def compare(run: dict, exp: dict, span) -> dict:
    t = run["time"]
    t0, t1 = span if span else (0.0, float(t[-1]))
    out = {"span_s": [t0, t1]}
    sel = (t >= t0) & (t <= t1)
    for h in DEPTHS:
        if h in run:
            ref = np.interp(t[sel], exp["t"], exp[h])
            out[f"{h}_rms_m"] = float(np.sqrt(np.mean((run[h][sel] - ref) ** 2)))
            if h != "H4":
                out[f"{h}_front"] = [(d, arrival(t, run[h], d), arrival(exp["t"], exp[h], d)) for d in FRONT_M]
    for p in PRESSURES:
        if p in run:
            ta_run, ta_exp = arrival(t, run[p]), arrival(exp["t"], exp[p])
            # the same window for both records: WINDOW_S, or what the run has after its arrival
            win = min(WINDOW_S, float(t[-1]) - ta_run) if np.isfinite(ta_run) else WINDOW_S
            pk_run, pk_exp = first_peak(t, run[p], ta_run, win), first_peak(exp["t"], exp[p], ta_exp, win)
            im_run, im_exp = first_impulse(t, run[p], ta_run, win), first_impulse(exp["t"], exp[p], ta_exp, win)
            mp_run, mp_exp = (first_mean_peak(t, run[p], ta_run, window=win),
                              first_mean_peak(exp["t"], exp[p], ta_exp, window=win))
            out[p] = {"arrival_s": ta_run, "arrival_exp_s": ta_exp, "arrival_error_s": ta_run - ta_exp,
                      "peak_Pa": pk_run, "peak_exp_Pa": pk_exp, "peak_error": pk_run / pk_exp - 1.0,
                      "mean_peak_Pa": mp_run, "mean_peak_exp_Pa": mp_exp,
                      "impulse_Pa_s": im_run, "impulse_exp_Pa_s": im_exp, "impulse_ratio": im_run / im_exp,
                      "window_s": win}
    return out


def plot(run: dict, exp: dict, out_dir: Path):
    plt = pyplot()
    t1 = float(run["time"][-1])
    for group, unit, fname in (("H", "m", "depths"), ("P", "Pa", "pressures")):
        fig, axes = plt.subplots(4, 1, figsize=(8, 10), sharex=True)
        for k, ax in enumerate(axes):
            name = f"{group}{k + 1}"
            keep = exp["t"] <= max(t1, 1.0)
            ax.plot(exp["t"][keep], exp[name][keep], color="0.5", lw=0.8, label="Kleefsman et al. 2005")
            if name in run:
                ax.plot(run["time"], run[name], color="C0", lw=1.0, label="sphcore")
            ax.set_ylabel(f"{name} ({unit})")
            ax.legend(loc="upper right", fontsize=8)
        axes[-1].set_xlabel("t (s)")
        fig.tight_layout()
        fig.savefig(out_dir / f"spheric_test2_{fname}.png", dpi=120)
        plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run_dir", help="the output directory of a run of cases/dam_break_obstacle_3d (or its probes.csv)")
    ap.add_argument("--span", type=float, nargs=2, metavar=("T0", "T1"), help="time span for the depth RMS (s)")
    args = ap.parse_args(argv)
    try:
        found = open_run(args.run_dir)
        run = found.probe_table()
        if not any(name in run for name in DEPTHS + PRESSURES):
            raise RunError(f"{found.dir / 'probes.csv'}: no probe named H1-H4 or P1-P4 "
                           f"(expected a run of cases/dam_break_obstacle_3d)")
    except RunError as err:
        return refuse(PROG, err)
    exp = kleefsman()
    res = compare(run, exp, args.span)
    t0, t1 = res["span_s"]
    print(f"SPHERIC test 2, {found.dir}: t in [{t0:.3g}, {t1:.3g}] s")
    for h in DEPTHS:
        if f"{h}_rms_m" in res:
            fronts = "".join(f"; depth > {d:g} m at {a:.4f} s (experiment {b:.4f} s, {a - b:+.4f} s)"
                             for d, a, b in res.get(f"{h}_front", ()))
            print(f"  {h}: depth RMS error {res[f'{h}_rms_m']:.4f} m{fronts}")
    for p in PRESSURES:
        if p in res:
            r = res[p]
            print(f"  {p}: first impact (p > {IMPACT_PA:.0f} Pa) at {r['arrival_s']:.4f} s (experiment "
                  f"{r['arrival_exp_s']:.4f} s, error {r['arrival_error_s']:+.4f} s); peak {r['peak_Pa']:.0f} Pa "
                  f"(experiment {r['peak_exp_Pa']:.0f} Pa, {100 * r['peak_error']:+.0f} %); peak of the "
                  f"{1000 * MEAN_S:g} ms mean {r['mean_peak_Pa']:.0f} Pa (experiment {r['mean_peak_exp_Pa']:.0f} Pa); "
                  f"impulse over {r['window_s']:.3g} s {r['impulse_Pa_s']:.0f} Pa s (experiment "
                  f"{r['impulse_exp_Pa_s']:.0f} Pa s, ratio {r['impulse_ratio']:.2f})")
    plot(run, exp, found.dir)
    return 0


if __name__ == "__main__":
    sys.exit(main())
