"""Sloshing: the first mode of a swayed tank against linear theory, and the rolled tank of
SPHERIC benchmark test 10 against the experiment's wall pressure. Each wall treatment.

Runs the shipped ``cases/sloshing_free`` (a 1 m tank, h = 0.3 m, swayed for three periods,
then free to t = 14 s; dx = 0.01 m, h_sml = 2 dx) and ``cases/sloshing_roll`` (SPHERIC test
10, low filling; 20 particles over the depth, h_sml = 1.3 dx) as they are with their
gauges, with the reflective walls, reflective walls + the wall model (``wall_integral``)
and ghost particles + reflective walls. The figures are ``postprocessing/sloshing.py``'s:
``free_decay`` (a damped sine fitted to the antisymmetric part of the two depth gauges after
the sway, against T1 of linear theory) and ``roll_compare`` (sensor 1's peaks per roll
period and the mean absolute error against the experiment's record). A further run backs
the page's known limitations: the free sloshing with the core's default h_sml = 1.3 dx
(wall model).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from _common import (
    GHOST,
    REFLECTIVE,
    TREATMENTS,
    WALL_MODEL,
    plugins_set,
    pyplot,
    run_case,
    save,
    status,
    table,
    toolkit,
)

NAME = "sloshing"
TITLE = "Sloshing: free sloshing period and damping vs linear theory; rolled tank vs SPHERIC test 10"
NARROW = "kernel.h_over_dx=1.3"  # the core's default smoothing length
SWAY_END = 3.957  # s: the sway of cases/sloshing_free stops here (its README); the free decay follows
COLOURS = {REFLECTIVE: "C0", WALL_MODEL: "C3", GHOST: "C2"}


def _out(runs: Path, case: str, plugins: list[str], tag: str = "") -> Path:
    return runs / f"{case}_{'_'.join(plugins)}{tag}"


def plan(runs: Path) -> list[dict]:
    """Every run of the page, in the order the build makes them."""
    out = []
    for case in ("sloshing_free", "sloshing_roll"):
        for label, plugins in TREATMENTS.items():
            out.append({"group": case, "case": case, "label": label, "out": _out(runs, case, plugins),
                        "sets": [plugins_set(plugins + ["probes"])], "t_end": None})
    plugins = TREATMENTS[WALL_MODEL]
    out.append({"group": "narrow", "case": "sloshing_free", "label": WALL_MODEL,
                "out": _out(runs, "sloshing_free", plugins, "_h13"),
                "sets": [plugins_set(plugins + ["probes"]), NARROW], "t_end": None})
    return out


def run(spec: dict, rerun: bool) -> dict:
    return run_case(spec["case"], spec["out"], spec["sets"], t_end=spec["t_end"], rerun=rerun)


def _cost(s: dict) -> list[str]:
    return [f"{s['n_particles']}", f"{s['steps']}", f"{s['wall_time_s']:.0f}", f"{s['particle_steps_per_s']:.3g}"]


def _fmt(v, spec):
    return "-" if v is None or not np.isfinite(v) else format(v, spec)


def _free(spec: dict, s: dict) -> dict | None:
    if s["status"] != "completed":
        return None
    sl = toolkit("sloshing")
    return sl.free_decay(sl.open_run(spec["out"]), SWAY_END)


def viscous_zeta(s: dict, m: dict) -> float:
    """The damping ratio the artificial viscosity alone gives the first mode, read as a
    kinematic viscosity nu = alpha h c0 / 8 (2D): zeta = 2 nu k^2 / omega, k = pi / L."""
    alpha = float(s["config"]["viscosity"]["alpha"])
    nu = alpha * float(s["h"]) * float(s["c0"]) / 8.0
    k = math.pi / m["length"]
    return 2.0 * nu * k * k / (2.0 * math.pi / m["T1"])


def _free_row(h_sml: str, label: str, s: dict, m: dict | None) -> list[str]:
    if m is None:
        return [h_sml, label, status(s)] + ["-"] * 7 + _cost(s)
    _, _, r, f = m["series"][-1]  # the antisymmetric part
    return [h_sml, label, status(s), _fmt(f["period"], ".4f"), _fmt(100 * (f["period"] / m["T1"] - 1.0), "+.1f") + " %",
            _fmt(f["zeta"], ".4f"), _fmt(r["zeta"], ".4f"), f"{viscous_zeta(s, m):.4f}", f"{m['seen']:.4f}",
            _fmt(1e3 * m["drift"], "+.2f"), *_cost(s)]


def _roll(spec: dict, s: dict) -> dict | None:
    if s["status"] != "completed":
        return None
    sl = toolkit("sloshing")
    return sl.roll_compare(sl.open_run(spec["out"]))


def _roll_rows(roll: dict) -> list[list[str]]:
    rows, exp = [], None
    for label, (s, m) in roll.items():
        if m is None:
            rows.append([label, status(s)] + ["-"] * 6 + _cost(s))
            continue
        exp = m
        exp_peaks = [(te, pe) for _, _, _, te, pe, _ in m["peaks"]]
        peaks = [f"{pq:.0f} ({pq / pe:.2f})" if np.isfinite(pq) and pe else "-"
                 for (_, pq), (_, pe) in zip(m["peaks_5ms"], exp_peaks)]
        dts = [tq - te for (tq, _), (te, _) in zip(m["peaks_5ms"], exp_peaks) if np.isfinite(tq) and np.isfinite(te)]
        times = f"{min(dts):+.2f} .. {max(dts):+.2f}" if dts else "-"
        rows.append([label, status(s), *peaks, times, f"{m['mae']:.0f}", *_cost(s)])
    if exp is not None:
        rows.insert(0, ["experiment (upper series)", "", *[f"{pe:.0f}" for _, _, _, _, pe, _ in exp["peaks"]], "",
                        f"(series {exp['spread']:.0f} Pa from their midline)", "", "", "", ""])
    return rows


def _plot_free(free: dict, figures: Path) -> None:
    plt = pyplot()
    shown = [(label, m) for label, (_, m) in free.items() if m is not None]
    if not shown:
        return
    fig, axes = plt.subplots(len(shown), 1, figsize=(8, 1.9 * len(shown) + 0.6), sharex=True, squeeze=False)
    for ax, (label, m) in zip(axes[:, 0], shown):
        _, eta, r, f = m["series"][-1]
        t = m["t"]
        ax.plot(t, 1e3 * eta, color=COLOURS[label], lw=0.9, label=f"{label}: T = {f['period']:.4f} s")
        up = np.flatnonzero((eta[:-1] < 0) & (eta[1:] >= 0))
        if len(up) and len(r["amplitudes"]):
            t0 = t[up[0]]
            w = 2 * math.pi / m["T1"]
            a = r["amplitudes"][0] * np.exp(-f["zeta"] * w * (t - t0)) if np.isfinite(f["zeta"]) else r["amplitudes"][0]
            ax.plot(t, 1e3 * a * np.sin(w * (t - t0)), "k--", lw=0.7,
                    label=f"period of linear theory, T1 = {m['T1']:.4f} s")
        ax.set_ylabel("mm")
        ax.legend(fontsize=7, loc="upper right")
    axes[0, 0].set_title(f"free sloshing: {shown[0][1]['series'][-1][0]} of the depth gauges after the sway "
                         "(dashed: in phase at the first up-crossing, the fit's damping)", fontsize=8)
    axes[-1, 0].set_xlabel("t [s]")
    fig.tight_layout()
    save(fig, figures, f"{NAME}_free.png")


def _plot_roll(roll: dict, figures: Path) -> None:
    """Sensor 1 averaged over 5 ms (the table's peaks) over the experiment's two series."""
    sl, plt = toolkit("sloshing"), pyplot()
    shown = [(label, m) for label, (_, m) in roll.items() if m is not None]
    if not shown:
        return
    fig, axes = plt.subplots(len(shown), 1, figsize=(8, 2.0 * len(shown) + 0.4), sharex=True, squeeze=False)
    for ax, (label, m) in zip(axes[:, 0], shown):
        (ta, pa), (tb, pb) = m["upper"], m["lower"]
        ax.plot(ta, pa, "-", color="0.6", lw=0.6, label="experiment, upper series")
        ax.plot(tb, pb, "-", color="0.3", lw=0.6, label="experiment, lower series")
        p5 = sl.smooth(m["t_sim"], m["p_sim"], sl.SMOOTH_PEAK)
        ax.plot(m["t_sim"], p5, "-", color=COLOURS[label], lw=0.8, label=f"{label}, sensor 1 over 5 ms")
        for _, _, pq, te, pe, _ in m["peaks"]:
            if np.isfinite(te):
                ax.plot(te, pe, "ks", ms=3)
        top = max(float(np.nanmax(pa)), float(np.nanmax(p5[m["t_sim"] <= 4.5 * m["T"]])))
        ax.set_ylim(-0.1 * top, 1.1 * top)
        ax.set_xlim(0, 5 * m["T"])
        ax.set_ylabel("Pa")
        ax.legend(fontsize=7, loc="upper left")
    axes[0, 0].set_title("SPHERIC test 10, low filling, sensor 1 (squares: the experiment's peaks)", fontsize=8)
    axes[-1, 0].set_xlabel("t [s]")
    fig.tight_layout()
    save(fig, figures, f"{NAME}_roll.png")


def build(runs: Path, figures: Path, rerun: bool) -> str:
    free, roll, narrow = {}, {}, {}
    for spec in plan(runs):
        s = run(spec, rerun)
        if spec["group"] == "sloshing_free":
            free[spec["label"]] = (s, _free(spec, s))
        elif spec["group"] == "sloshing_roll":
            roll[spec["label"]] = (s, _roll(spec, s))
        else:
            narrow[spec["label"]] = (s, _free(spec, s))
    _plot_free(free, figures)
    _plot_roll(roll, figures)
    m = next((m for _, m in free.values() if m is not None), None)
    t1 = f"T1 = {m['T1']:.4f} s (L = {m['length']:g} m, h = {m['depth']:g} m)" if m else "T1: no run completed"
    header = ["h_sml", "treatment", "run", "T (fit) [s]", "T / T1 - 1", "zeta (fit)", "zeta (log decrement)",
              "zeta of the viscosity term", "mean level [m]", "level drift [mm/s]", "particles", "steps", "wall time [s]", "particle-steps/s"]
    md = [f"### Free sloshing, `sloshing_free`: linear theory {t1}\n",
          table(header, [_free_row("2 dx (shipped)", label, s, m) for label, (s, m) in free.items()])]
    md += ["\n### Rolled tank, `sloshing_roll` (SPHERIC test 10, sensor 1)\n",
           table(["treatment", "run", "peak 1 [Pa] (/exp.)", "peak 2", "peak 3", "peak 4",
                  "5 ms peaks' times - experiment's [s]", "MAE 0-4 T [Pa]", "particles", "steps", "wall time [s]",
                  "particle-steps/s"], _roll_rows(roll))]
    rows = [_free_row("2 dx (shipped)", label, *free[label]) for label in narrow if label in free]
    rows += [_free_row("1.3 dx", label, s, m) for label, (s, m) in narrow.items()]
    md += ["\n### Smoothing length, `sloshing_free`\n", table(header, rows)]
    return "\n".join(md)
