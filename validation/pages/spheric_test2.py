"""SPHERIC test 2 (Kleefsman et al. 2005): the 3D dam break against a box, each wall treatment.

Runs ``cases/dam_break_obstacle_3d`` as shipped (dx = 0.02 m, 85,400 particles, 2 s) with
the probes plugin alone for output, with the reflective walls and with reflective walls +
the wall model (``wall_integral``); ghost particles do not apply (they mirror the fluid
across an infinite plane, and the box is a finite solid standing in the flow). Compares the
water depths H1-H4 and the pressures P1-P4 with the experiment through
``postprocessing/spheric_test2.py`` (its definitions: depth RMS over the run, first impact
at p > 2 kPa, peak and impulse over the 0.2 s after it).
"""

from __future__ import annotations

import math
from pathlib import Path

from _common import REFLECTIVE, TREATMENTS, WALL_MODEL, cost, num, pct, plugins_set, pyplot, run_case, save, \
    status, table, toolkit

NAME = "spheric_test2"
TITLE = "SPHERIC test 2: 3D dam break against a box, depths H1-H4 and pressure P1 vs Kleefsman et al. (2005)"
CASE = "dam_break_obstacle_3d"
ROWS = (REFLECTIVE, WALL_MODEL)  # ghosts: no finite obstacle


def build(runs: Path, figures: Path, rerun: bool) -> str:
    from sphcore_plugins.gauges.reference import kleefsman

    st2, open_run = toolkit("spheric_test2"), toolkit("runs").open_run
    exp = kleefsman()
    results = {}
    for label in reversed(ROWS):  # the case's own walls first: the row that matters most
        out = runs / "_".join(TREATMENTS[label])
        s = run_case(CASE, out, [plugins_set(TREATMENTS[label] + ["probes"])], rerun=rerun)
        # a run stopped before its end is compared over the span it covers (its status says so)
        probes = open_run(out).probe_table() if (out / "probes.csv").exists() else None
        res = st2.compare(probes, exp, None) if probes is not None else {}
        results[label] = (s, probes, res)
    results = {label: results[label] for label in ROWS}
    _plots(results, exp, figures)
    return _tables(results, st2)


def _tables(results: dict, st2) -> str:
    rows_h, rows_p = [], []
    for label, (s, _, r) in results.items():
        rows_h.append([label, status(s), *[num(r.get(f"{h}_rms_m")) for h in st2.DEPTHS],
                       *[_front(r, h) for h in ("H1", "H2", "H3")],
                       *cost(s)])
        p1 = r.get("P1", {})
        rows_p.append([label, _f(p1.get("arrival_error_s"), 1000, "+.1f"), _f(p1.get("peak_Pa"), 1e-3, ".1f"),
                       pct(p1.get("peak_error"), digits=0), _f(p1.get("mean_peak_Pa"), 1e-3, ".1f"),
                       _f(p1.get("impulse_Pa_s"), 1, ".0f"), num(p1.get("impulse_ratio")), _f(p1.get("window_s"), 1, ".3g"),
                       f"{s.get('n_particles', 0):,}", num(s.get("c0"))])
    p1_exp = next((r["P1"] for _, _, r in results.values() if "P1" in r), {})
    md = "Water depth: RMS error over the run (m) and the front's arrival at H1-H3 (depth > 0.05 m) "
    md += "against the experiment's (s, + late).\n\n"
    md += table(["walls", "status", "H1 RMS", "H2 RMS", "H3 RMS", "H4 RMS",
                 "H1 arrival", "H2 arrival", "H3 arrival", "wall s", "particle-steps/s"], rows_h)
    md += ("\nPressure P1 (the lowest sensor on the box's face), first impact: its arrival (p > 2 kPa) against the "
           "experiment's (ms, + late), the peak and its error, the peak of the 10 ms running mean, and the impulse "
           "over the window after the impact (0.2 s, or what the run holds after it) with its ratio to the "
           f"experiment's over the same window. Experiment: peak {_f(p1_exp.get('peak_exp_Pa'), 1e-3, '.1f')} kPa, "
           f"10 ms mean peak {_f(p1_exp.get('mean_peak_exp_Pa'), 1e-3, '.1f')} kPa.\n\n")
    md += table(["walls", "arrival (ms)", "peak (kPa)", "peak error", "10 ms mean peak (kPa)", "impulse (Pa s)",
                 "impulse ratio", "window (s)", "particles", "c0 (m/s)"], rows_p)
    return md


def _f(v, scale: float, fmt: str) -> str:
    """``v * scale`` formatted, ``-`` for a missing figure."""
    return "-" if v is None or not math.isfinite(v) else format(v * scale, fmt)


def _front(r: dict, h: str) -> str:
    """The run's arrival at ``h`` (depth > 0.05 m) minus the experiment's (s)."""
    fronts = {d: a - b for d, a, b in r.get(f"{h}_front", ())}
    return f"{fronts[0.05]:+.3f}" if math.isfinite(fronts.get(0.05, math.nan)) else "-"


def _plots(results, exp, figures: Path):
    plt = pyplot()
    t1 = max((float(p["time"][-1]) for _, p, _ in results.values() if p is not None), default=2.0)
    keep = exp["t"] <= t1
    _panels(plt, exp, keep, results, ("H1", "H2", "H3", "H4"), "m", 0.9, (7, 8), figures, f"{NAME}_depths.png")
    _panels(plt, exp, keep, results, ("P1", "P3"), "Pa", 0.7, (7, 6), figures, f"{NAME}_pressures.png")


def _panels(plt, exp, keep, results, names, unit, lw, size, figures, file):
    """One panel per probe of ``names``: the experiment and each treatment's run."""
    fig, axes = plt.subplots(len(names), 1, figsize=size, sharex=True)
    for ax, name in zip(axes, names):
        ax.plot(exp["t"][keep], exp[name][keep], color="0.3", lw=1.2, label="Kleefsman et al. 2005")
        for i, (label, (_, p, _)) in enumerate(results.items()):
            if p is not None and name in p:
                ax.plot(p["time"], p[name], color=f"C{i}", lw=lw, label=f"sphcore, {label}")
        ax.set_ylabel(f"{name} ({unit})")
    axes[0].legend(loc="upper right", fontsize=8)
    axes[-1].set_xlabel("t (s)")
    fig.tight_layout()
    save(fig, figures, file)
