"""The trade between the two schemes: the weakly compressible scheme (wcsph) against the
divergence-free one (dfsph) on the cases of the validation pages, each with the case's own
walls (reflective + the wall model, ``wall_integral``).

Runs ``cases/dam_break`` (front and back-wall height: Cruchaga et al. 2007, Martin & Moyce
1952), ``cases/dam_break_buchner`` (P1, P2: Buchner 2002), ``cases/dam_break_lobovsky``
(sensor 2: Lobovsky et al. 2014) and ``cases/dam_break_obstacle_3d`` (SPHERIC test 2:
depths H1-H4 and P1, Kleefsman et al. 2005) as shipped, once with each scheme
(``--set scheme.name=...``). The figures are those of each case's own page, by the same
definitions (the front gauge's, the probes plugin's, ``postprocessing/spheric_test2.py``),
and the cost of each run: steps, wall time, particle-steps per second, and for dfsph the
solves' iterations a step (summary.json's ``dfsph`` table).
"""

from __future__ import annotations

from pathlib import Path

from _common import cost, num, pct, plugins_set, run_case, status, table, toolkit

NAME = "scheme_trade"
TITLE = "wcsph against dfsph: accuracy and cost on the seed dam break, Buchner, Lobovsky and SPHERIC test 2"
SCHEMES = ("wcsph", "dfsph")
WALLS = ["reflective", "wall_integral"]


def _run(case: str, scheme: str, extra: list[str], runs: Path, rerun: bool) -> tuple[dict, Path]:
    out = runs / f"{case}_{scheme}"
    sets = [plugins_set(WALLS + extra), f'scheme.name="{scheme}"']
    return run_case(case, out, sets, rerun=rerun), out


def _solves(s: dict) -> str:
    """dfsph's mean density / divergence iterations a step, ``-`` for wcsph."""
    d = s.get("dfsph")
    if not d:
        return "-"
    return f"{d.get('density_iterations_mean', 0):.1f} / {d.get('divergence_iterations_mean', 0):.1f}"


def _steps(s: dict) -> str:
    return f"{s.get('steps', 0):,}"


def build(runs: Path, figures: Path, rerun: bool) -> str:
    md = []
    trade = []

    rows = []
    for scheme in SCHEMES:
        s, _ = _run("dam_break", scheme, ["front_gauge"], runs, rerun)
        f = s.get("front_gauge", {})
        rows.append([scheme, status(s), pct(f.get("err_cruchaga_0.10s")), pct(f.get("err_cruchaga_0.20s")),
                     pct(f.get("rms_rel_err_martin_moyce_T3"), signed=False),
                     pct(f.get("rms_rel_err_martin_moyce_height"), signed=False), _steps(s), _solves(s), *cost(s)])
        trade.append(["seed dam break (2D)", scheme, f"front RMS {pct(f.get('rms_rel_err_martin_moyce_T3'), signed=False)}",
                      _steps(s), *cost(s)])
    md.append("**The seed dam break** (`cases/dam_break`, 2,592 particles, 0.3 s): the front against Cruchaga at "
              "0.1 and 0.2 s, the RMS error of the front and of the back-wall height against Martin & Moyce.\n\n"
              + table(["scheme", "status", "front 0.1 s", "front 0.2 s", "front RMS", "height RMS", "steps",
                       "iterations a step", "wall s", "particle-steps/s"], rows))

    rows = []
    for scheme in SCHEMES:
        s, _ = _run("dam_break_buchner", scheme, ["probes"], runs, rerun)
        p = s.get("probes", {})
        rows.append([scheme, status(s), num(p.get("probe_P1_mae_rhogH")), f"{p.get('probe_P1_offset_rhogH', float('nan')):+.3f}",
                     num(p.get("probe_P1_noise_rhogH")), f"{p.get('probe_P1_rise_dtau', float('nan')):+.3f}",
                     num(p.get("probe_P2_mae_rhogH")), _steps(s), _solves(s), *cost(s)])
        trade.append(["Buchner P1 (2D)", scheme, f"P1 MAE {num(p.get('probe_P1_mae_rhogH'))} rho g H", _steps(s),
                      *cost(s)])
    md.append("**Buchner (2002)** (`cases/dam_break_buchner`, 3,200 particles, 1.61 s): the MAE of p / (rho g H) "
              "at P1 over t sqrt(g/H) in [2.6, 5.5], its offset and noise, the first rise against the experiment's "
              "(in t sqrt(g/H)), the MAE at P2.\n\n"
              + table(["scheme", "status", "P1 MAE", "P1 offset", "P1 noise", "P1 first rise - exp.", "P2 MAE",
                       "steps", "iterations a step", "wall s", "particle-steps/s"], rows))

    rows = []
    for scheme in SCHEMES:
        s, _ = _run("dam_break_lobovsky", scheme, ["probes"], runs, rerun)
        p = s.get("probes", {})
        band = f"{num(p.get('probe_sensor2_band_peak_lo_rhogH'))}-{num(p.get('probe_sensor2_band_peak_hi_rhogH'))}"
        rows.append([scheme, status(s), pct(p.get("probe_sensor2_in_band_fraction"), signed=False),
                     f"{p.get('probe_sensor2_offset_rhogH', float('nan')):+.3f}", num(p.get("probe_sensor2_noise_rhogH")),
                     num(p.get("probe_sensor2_peak_rhogH")), band, _steps(s), _solves(s), *cost(s)])
        trade.append(["Lobovsky sensor 2 (2D)", scheme,
                      f"in band {pct(p.get('probe_sensor2_in_band_fraction'), signed=False)}", _steps(s), *cost(s)])
    md.append("**Lobovsky et al. (2014)** (`cases/dam_break_lobovsky`, 3,200 particles): the share of sensor 2's "
              "samples (t / sqrt(H/g) in [2, 7]) inside the experiment's 2.5-97.5 % band, the offset from its median, "
              "the noise, the peak against the band's peak range.\n\n"
              + table(["scheme", "status", "in band", "offset", "noise", "peak (rho g H)", "experiment's peak range",
                       "steps", "iterations a step", "wall s", "particle-steps/s"], rows))

    from sphcore_plugins.gauges.reference import kleefsman

    st2, open_run = toolkit("spheric_test2"), toolkit("runs").open_run
    exp = kleefsman()
    rows = []
    for scheme in SCHEMES:
        s, out = _run("dam_break_obstacle_3d", scheme, ["probes"], runs, rerun)
        probes = open_run(out).probe_table() if (out / "probes.csv").exists() else None
        r = st2.compare(probes, exp, None) if probes is not None else {}
        p1 = r.get("P1", {})
        rows.append([scheme, status(s), *[num(r.get(f"{h}_rms_m")) for h in st2.DEPTHS],
                     num(p1.get("peak_Pa", float("nan")) * 1e-3), pct(p1.get("peak_error"), digits=0),
                     num(p1.get("impulse_ratio")), _steps(s), _solves(s), *cost(s)])
        trade.append(["SPHERIC test 2 (3D)", scheme, f"P1 peak {pct(p1.get('peak_error'), digits=0)}", _steps(s),
                      *cost(s)])
    md.append("**SPHERIC test 2** (`cases/dam_break_obstacle_3d`, 85,400 particles, 2 s): the RMS error of the "
              "depths H1-H4 over the run (m), P1's first peak (kPa) and its error against the experiment's, and P1's "
              "impulse over the 0.2 s after the impact as a ratio to the experiment's.\n\n"
              + table(["scheme", "status", "H1 RMS", "H2 RMS", "H3 RMS", "H4 RMS", "P1 peak", "P1 peak error",
                       "P1 impulse ratio", "steps", "iterations a step", "wall s", "particle-steps/s"], rows))

    md.insert(0, "**The trade**, one row per case and scheme: the figure that matters most on each case's page, "
                 "and the cost.\n\n"
              + table(["case", "scheme", "figure", "steps", "wall s", "particle-steps/s"], trade))
    return "\n".join(md)
