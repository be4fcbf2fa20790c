"""Wave flumes: the waves a piston and a flap make against linear wave-maker theory, and the
piston's force against Havelock's. Each wall treatment.

Runs the shipped ``cases/wave_flume`` (a piston, kh = 1.0), ``cases/wave_flume_kh18`` (a
piston, kh = 1.8) and ``cases/wave_flume_flap`` (a flap hinged at the floor, kh = 1.0) as
they are (dx = h/20, h_sml = 2 dx) with their depth gauges and the paddle's load, without
their frame writers, with the reflective walls, reflective walls + the wall model
(``wall_integral``, the cases' own choice) and ghost particles + reflective walls. The
figures are ``postprocessing/wave_flume.py``'s (``measure``, ``paddle_force``, ``decay``):
H/S at each gauge against Biesel's transfer function (the flap's for the flap), the fit of
an exponential along the flume extrapolated to the paddle, and the first harmonic of the
piston's force against Havelock's. Two further sets back the page's known limitations: the
kh = 1.0 flume with the core's default h_sml = 1.3 dx (wall model, ghosts), and the
kh = 1.8 flume shortened to 2.5 m at dx = h/20 and h/40 (wall model).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
from _common import (
    GHOST,
    POSTPROCESSING,
    REFLECTIVE,
    TREATMENTS,
    WALL_MODEL,
    load,
    pct,
    plugins_set,
    pyplot,
    run_case,
    save,
    status,
    table,
    toolkit,
)

NAME = "wave_flume"
TITLE = "Wave flumes: piston (kh = 1.0, 1.8) and flap vs Biesel's transfer functions, paddle force vs Havelock"
FLUMES = {"wave_flume": "piston, kh = 1.0", "wave_flume_kh18": "piston, kh = 1.8", "wave_flume_flap": "flap, kh = 1.0"}
GAUGES = ["probes", "wall_loads"]  # the case's gauges, without its frame writers (vtu, netcdf)
NARROW = "kernel.h_over_dx=1.3"  # the core's default smoothing length
SHORT = ["domain.planes[1].point=[2.5, 0.0]", "blocks[0].max=[2.5, 0.25]"]  # a 2.5 m flume
SHORT_T_END = 4.2
COLOURS = {REFLECTIVE: "C0", WALL_MODEL: "C3", GHOST: "C2"}


def _scripts():
    """(wave_flume, wave_theory): postprocessing/wave_flume.py as a module and its sibling
    wave_theory.py, loaded first under the name the script imports it by."""
    theory = load(POSTPROCESSING / "wave_theory.py", "wave_theory")
    return toolkit("wave_flume"), theory


def _out(runs: Path, case: str, plugins: list[str], tag: str = "") -> Path:
    return runs / f"{case}_{'_'.join(plugins)}{tag}"


def plan(runs: Path) -> list[dict]:
    """Every run of the page, in the order the build makes them: the three flumes with each
    treatment, then the runs behind the known limitations."""
    out = []
    for case in FLUMES:
        for label, plugins in TREATMENTS.items():
            out.append({"group": "main", "case": case, "label": label, "out": _out(runs, case, plugins),
                        "sets": [plugins_set(plugins + GAUGES)], "t_end": None})
    for label in (WALL_MODEL, GHOST):
        plugins = TREATMENTS[label]
        out.append({"group": "narrow", "case": "wave_flume", "label": label,
                    "out": _out(runs, "wave_flume", plugins, "_h13"),
                    "sets": [plugins_set(plugins + GAUGES), NARROW], "t_end": None})
    plugins = TREATMENTS[WALL_MODEL]
    for n, dx in ((20, 0.0125), (40, 0.00625)):
        out.append({"group": "fine", "case": "wave_flume_kh18", "label": f"h/{n}", "dx": dx,
                    "out": _out(runs, "wave_flume_kh18", plugins, f"_short_h{n}"),
                    "sets": [plugins_set(plugins + GAUGES), *SHORT] + ([f"particles.dx={dx}"] if n != 20 else []),
                    "t_end": SHORT_T_END})
    return out


def run(spec: dict, rerun: bool) -> dict:
    return run_case(spec["case"], spec["out"], spec["sets"], t_end=spec["t_end"], rerun=rerun)


def _measure(spec: dict, s: dict) -> dict:
    """The run's summary with the script's measurement (``m``), force and decay fit."""
    wf, _ = _scripts()
    r = {"spec": spec, "s": s, "m": None, "force": None, "fit": None}
    if s["status"] == "completed":
        run = wf.open_run(spec["out"])
        r["m"] = m = wf.measure(run)
        r["force"] = wf.paddle_force(run, m)
        r["fit"] = wf.decay(m)
    return r


def _err(r: dict, name: str):
    if r["m"] is None:
        return math.nan
    row = next((x for x in r["m"]["rows"] if x["name"] == name), None)
    return math.nan if row is None or not row["waves"] else row["HS"] / r["m"]["biesel"] - 1.0


def _force(r: dict) -> str:
    f = r["force"]
    if f is None:
        return "-"
    return f"{f['amplitude']:.2f} N/m ({pct(f['amplitude'] / f['theory']['amplitude'] - 1.0)})"


def _cost(s: dict) -> list[str]:
    return [f"{s['n_particles']}", f"{s['steps']}", f"{s['wall_time_s']:.0f}", f"{s['particle_steps_per_s']:.3g}"]


def _theory_table(results: dict) -> str:
    _, wt = _scripts()
    rows = []
    for case, what in FLUMES.items():
        m = next((r["m"] for r in results[case].values() if r["m"] is not None), None)
        if m is None:
            rows.append([f"`{case}`", what] + ["-"] * 7)
            continue
        omega = 2 * math.pi / m["T"]
        flap = m.get("paddle") == "flap"
        hv = None if flap else wt.havelock(omega, m["h"], m["S"], m["g"], m["rho0"])
        rows.append([f"`{case}`", what, f"{m['T']:.4f}", f"{m['kh']:.3f}", f"{m['L']:.3f}", f"{1000 * m['S']:.1f}",
                     f"{m['biesel']:.4f} ({'flap' if flap else 'Biesel'})", f"{1000 * m['biesel'] * m['S']:.2f}",
                     "-" if hv is None else f"{hv['amplitude']:.2f} N/m at {math.degrees(hv['phase']):.1f} deg"])
    return table(["case", "paddle", "T [s]", "kh", "L [m]", "S [mm]", "H/S, linear theory", "H [mm]",
                  "Havelock's force (first harmonic, phase to the displacement)"], rows)


def _flume_table(case: str, results: dict) -> str:
    rows = []
    flap = case == "wave_flume_flap"
    for label, r in results[case].items():
        m = r["m"]
        names = [x["name"] for x in m["rows"]] if m else ["G1", "G2", "G3", "G4"]
        gauges = [pct(_err(r, n)) for n in names]
        fit = r["fit"]
        at0 = pct(fit[1] / m["biesel"] - 1.0) if fit else "-"
        rate = pct(1.0 - math.exp(-fit[0]), signed=False) if fit else "-"
        row = [label, status(r["s"]), *gauges, rate, at0]
        if not flap:
            periods = r["force"]["periods"] if r["force"] else []
            row += [_force(r), f"{min(periods):.1f} .. {max(periods):.1f}" if periods else "-"]
        rows.append(row + _cost(r["s"]))
    m = next((r["m"] for r in results[case].values() if r["m"] is not None), None)
    names = [f"{x['name']} ({x['x'] / m['h']:.0f} h)" for x in m["rows"]] if m else ["G1", "G2", "G3", "G4"]
    header = ["treatment", "run", *names, "H lost per metre", "fit at x = 0"]
    if not flap:
        header += ["force (vs Havelock)", "force, each period [N/m]"]
    return table(header + ["particles", "steps", "wall time [s]", "particle-steps/s"], rows)


def _windows(case: str, results: dict) -> str:
    """The gauges' windows (the same for every treatment) and the whole waves in them (wall model)."""
    r = results[case].get(WALL_MODEL)
    if r is None or r["m"] is None:
        return ""
    parts = [f"{x['name']} {x['t0']:.2f}-{x['t1']:.2f} s ({x['waves']} whole wave{'s' if x['waves'] != 1 else ''})"
             for x in r["m"]["rows"]]
    return "Windows (whole waves in the wall model's run): " + ", ".join(parts) + ".\n"


def _plot_gauges(case: str, results: dict, figures: Path) -> None:
    plt = pyplot()
    first = next((r for r in results[case].values() if r["m"] is not None), None)
    if first is None:
        return
    m0 = first["m"]
    n = len(m0["rows"])
    fig, axes = plt.subplots(n, 1, figsize=(8, 1.7 * n + 0.6), sharex=True)
    half = 500.0 * m0["biesel"] * m0["S"]  # mm
    for j, ax in enumerate(np.atleast_1d(axes)):
        row0 = m0["rows"][j]
        ax.axvspan(row0["t0"], row0["t1"], color="0.9", lw=0)
        for label, r in results[case].items():
            if r["m"] is None:
                continue
            ax.plot(r["m"]["t"], 1000.0 * r["m"]["rows"][j]["eta"], lw=0.8, color=COLOURS[label], label=label)
        for y in (half, -half):
            ax.axhline(y, color="k", ls="--", lw=0.7)
        ax.set_ylabel(f"{row0['name']} [mm]")
        ax.set_ylim(-2.2 * half, 2.2 * half)
        ax.text(0.005, 0.05, f"x = {row0['x']:.2f} m", transform=ax.transAxes, fontsize=8)
    axes[0].legend(fontsize=7, loc="upper left", ncol=3)
    theory = "the flap's transfer function" if m0.get("paddle") == "flap" else "Biesel"
    axes[0].set_title(f"{FLUMES[case]}: elevation at the gauges; dashed: +-H/2 of {theory}; grey: window",
                      fontsize=9)
    axes[-1].set_xlabel("t [s]")
    fig.tight_layout()
    save(fig, figures, f"{NAME}_{case}_gauges.png")


def _plot_heights(results: dict, figures: Path) -> None:
    plt = pyplot()
    fig, axes = plt.subplots(1, len(FLUMES), figsize=(10, 3.2), sharey=True)
    for ax, case in zip(axes, FLUMES):
        for label, r in results[case].items():
            m = r["m"]
            if m is None:
                continue
            x = [row["x"] / m["h"] for row in m["rows"]]
            ax.plot(x, [row["HS"] / m["biesel"] for row in m["rows"]], "o-", ms=4, color=COLOURS[label],
                    label=label)
        ax.axhline(1.0, color="k", lw=0.8)
        ax.axhspan(0.95, 1.05, color="0.9", lw=0)
        ax.set_title(FLUMES[case], fontsize=9)
        ax.set_xlabel("gauge distance from the paddle, x / h")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("H / H (linear theory)")
    axes[0].legend(fontsize=7, loc="lower left")
    fig.tight_layout()
    save(fig, figures, f"{NAME}_heights.png")


def _plot_force(results: dict, figures: Path) -> None:
    """The force on the water (-Fx less its mean in the window) of the wall model and the
    ghosts against Havelock's first harmonic, both piston flumes."""
    wf, _ = _scripts()
    plt = pyplot()
    cases = [c for c in FLUMES if c != "wave_flume_flap"]
    fig, axes = plt.subplots(len(cases), 1, figsize=(8, 5))
    for ax, case in zip(axes, cases):
        shown = False
        for label in (WALL_MODEL, GHOST):
            r = results[case].get(label)
            if r is None or r["force"] is None:
                continue
            f, m = r["force"], r["m"]
            lines = [ln for ln in (r["spec"]["out"] / wf.WALL_LOADS_CSV).read_text().splitlines()
                     if ln.strip() and not ln.startswith("#")]
            header = lines[0].split(",")
            data = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
            t, fx = data[:, 0], data[:, header.index(f"{m['load']}.Fx")]
            t = t - 0.5 * np.diff(t, prepend=t[0])
            sel = (t >= f["from"]) & (t <= f["to"])
            ax.plot(t[sel], f["mean"] - fx[sel], lw=0.8, color=COLOURS[label], label=label)
            if not shown:
                hv, omega = f["theory"], 2 * math.pi / m["T"]
                tt = np.linspace(f["from"], f["to"], 600)
                ax.plot(tt, hv["amplitude"] * np.sin(omega * tt + m["phase0"] + hv["phase"]), "k--", lw=1.0,
                        label="Havelock (first harmonic)")
                shown = True
        ax.set_title(f"{FLUMES[case]}: force on the water less its mean", fontsize=9)
        ax.set_ylabel("N/m")
        if shown:
            ax.legend(fontsize=7, loc="upper right", ncol=3)
    axes[-1].set_xlabel("t [s]")
    fig.tight_layout()
    save(fig, figures, f"{NAME}_force.png")


def build(runs: Path, figures: Path, rerun: bool) -> str:
    specs = plan(runs)
    done = [(spec, run(spec, rerun)) for spec in specs]
    results = {case: {} for case in FLUMES}
    narrow, fine = {}, {}
    for spec, s in done:
        r = _measure(spec, s)
        if spec["group"] == "main":
            results[spec["case"]][spec["label"]] = r
        elif spec["group"] == "narrow":
            narrow[spec["label"]] = r
        else:
            fine[spec["label"]] = r
    for case in FLUMES:
        _plot_gauges(case, results, figures)
    _plot_heights(results, figures)
    _plot_force(results, figures)
    md = ["### Linear theory\n", _theory_table(results)]
    for case, what in FLUMES.items():
        md += [f"\n### `{case}` ({what})\n", _flume_table(case, results), "\n" + _windows(case, results)]
    # the smoothing length: 1.3 dx against the shipped 2 dx, kh = 1.0
    rows = []
    for h_sml, group in (("2 dx (shipped)", results["wave_flume"]), ("1.3 dx", narrow)):
        for label in (WALL_MODEL, GHOST):
            r = group.get(label)
            if r is None:
                continue
            fit = r["fit"]
            rows.append([h_sml, label, *[pct(_err(r, n)) for n in ("G1", "G2", "G3", "G4")],
                         pct(fit[1] / r["m"]["biesel"] - 1.0) if fit else "-", _force(r),
                         f"{r['s']['wall_time_s']:.0f}"])
    md += ["\n### Smoothing length, `wave_flume` (kh = 1.0)\n",
           table(["h_sml", "treatment", "G1", "G2", "G3", "G4", "fit at x = 0", "force (vs Havelock)",
                  "wall time [s]"], rows)]
    rows = []
    for label, r in fine.items():
        rows.append([f"{label} ({r['spec']['dx'] * 1000:g} mm)", status(r["s"]), pct(_err(r, "G1")), pct(_err(r, "G2")),
                     _force(r), *_cost(r["s"])])
    md += ["\n### Resolution, `wave_flume_kh18` (kh = 1.8) shortened to 2.5 m, wall model\n",
           table(["dx", "run", "G1 (2 h)", "G2 (3 h)", "force (vs Havelock)", "particles", "steps", "wall time [s]",
                  "particle-steps/s"], rows)]
    return "\n".join(md)

