"""Wall pressure against experiment for each boundary treatment: one table, one plot per probe.

    python validation/wall_pressure.py [--tank-t-end 5.0] [--only buchner,lobovsky,tank,tank_delta,tank_delta_h2,dam_break]
                                           [--out docs/wall_pressure_runs.md] [--plots docs/wall_pressure]

Runs (probes sampled in-run, no VTU/netCDF frames):
- cases/dam_break_buchner (H = 0.6 m, dx = H/40): P1 and P2 against Buchner (2002);
- cases/dam_break_lobovsky (H = 0.3 m, dx = H/40): sensor 2 against Lobovsky et al. (2014);
- cases/hydrostatic_tank with plain Tait pressure (no modified pressure), 5 s: at the case's
  defaults (h = 1.3 dx, no density diffusion), with hydrostatic density diffusion
  (delta = 0.1), and with it at h = 2 dx;
- cases/dam_break (the seed's): front against Cruchaga and Martin & Moyce, residual column
  height at the back wall against Martin & Moyce;
each with the reflective walls alone, reflective + the wall model (``wall_integral``), and
ghost + reflective, at the case's defaults plus the variant's plugins. Probe definitions:
:mod:`sphcore_plugins.probes` (wall mode: Shepard-normalised, each particle's pressure
extrapolated hydrostatically to the sensor). Writes the Markdown table and the probe plots
(docs/wall_pressure/*.png) and prints the table.
"""

from __future__ import annotations

import argparse
import math
import subprocess
import sys
import tempfile
from pathlib import Path

from sphcore.run import runner

ROOT = Path(__file__).resolve().parents[1]  # the repository
VARIANTS = {
    "reflective": ["reflective"],
    "reflective + wall model": ["reflective", "wall_integral"],
    "ghost + reflective": ["ghost", "reflective"],
}
DELTA = ["density_diffusion.delta=0.1", "density_diffusion.hydrostatic=true"]
CASES = {
    "buchner": ("dam_break_buchner", ["probes"], None),
    "lobovsky": ("dam_break_lobovsky", ["probes"], None),
    "tank": ("hydrostatic_tank", ["pressure_gauge"], ["physics.modified_pressure=false"]),
    "tank_delta": ("hydrostatic_tank", ["pressure_gauge"], ["physics.modified_pressure=false", *DELTA]),
    "tank_delta_h2": ("hydrostatic_tank", ["pressure_gauge"],
                      ["physics.modified_pressure=false", *DELTA, "kernel.h_over_dx=2.0"]),
    "dam_break": ("dam_break", ["front_gauge"], ["front_gauge.wall_height=true"]),
}
LABELS = {  # what a row's case runs with beyond the case's defaults
    "tank": " (plain Tait)",
    "tank_delta": " (plain Tait, delta 0.1)",
    "tank_delta_h2": " (plain Tait, delta 0.1, h = 2 dx)",
}


def fmt(v, pct=False):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    return f"{100 * v:.1f}%" if pct else f"{v:.3g}"


def figures(key, s) -> str:
    if s["status"] != "completed":
        return f"{s['status']} at t = {s['t']:.3g} s"
    if key == "buchner":
        p = s.get("probes", {})
        return (f"P1 MAE {fmt(p.get('probe_P1_mae_rhogH'))} (offset {fmt(p.get('probe_P1_offset_rhogH'))}, "
                f"noise {fmt(p.get('probe_P1_noise_rhogH'))}), "
                f"rise dtau {fmt(p.get('probe_P1_rise_dtau'))}; P2 MAE {fmt(p.get('probe_P2_mae_rhogH'))}")
    if key == "lobovsky":
        p = s.get("probes", {})
        return (f"in band {fmt(p.get('probe_sensor2_in_band_fraction'), True)} (offset "
                f"{fmt(p.get('probe_sensor2_offset_rhogH'))}, noise {fmt(p.get('probe_sensor2_noise_rhogH'))}), peak "
                f"{fmt(p.get('probe_sensor2_peak_rhogH'))} rho g H (band {fmt(p.get('probe_sensor2_band_peak_lo_rhogH'))}"
                f"-{fmt(p.get('probe_sensor2_band_peak_hi_rhogH'))})")
    if key.startswith("tank"):
        g = s.get("pressure_gauge", {})
        return (f"worst layer {fmt(g.get('pressure_max_layer_err'), True)}, largest displacement "
                f"{fmt(g.get('max_displacement_m', math.nan) / 0.02)} dx "
                f"({fmt(g.get('max_displacement_below_top_m', math.nan) / 0.02)} dx below the top two layers), "
                f"lost {g.get('particles_lost', '-')}")
    f = s.get("front_gauge", {})
    return (f"front {fmt(f.get('err_cruchaga_0.10s'), True)} / {fmt(f.get('err_cruchaga_0.20s'), True)} vs Cruchaga, "
            f"RMS {fmt(f.get('rms_rel_err_martin_moyce_T3'), True)} vs M&M; wall height RMS "
            f"{fmt(f.get('rms_rel_err_martin_moyce_height'), True)}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tank-t-end", type=float, default=5.0)
    ap.add_argument("--only", default=",".join(CASES))
    ap.add_argument("--out", default=str(ROOT / "docs" / "wall_pressure_runs.md"))
    ap.add_argument("--plots", default=str(ROOT / "docs" / "wall_pressure"), help="folder for the probe plots")
    args = ap.parse_args(argv)
    work = Path(tempfile.mkdtemp(prefix="sph-walls-"))
    plots = Path(args.plots)
    plots.mkdir(parents=True, exist_ok=True)
    lines = ["| case | boundary | figures | wall s |", "|---|---|---|---|"]
    for key in args.only.split(","):
        case, extra, sets = CASES[key]
        for label, plugins in VARIANTS.items():
            out = work / f"{key}_{plugins[-1]}_{len(plugins)}"
            overrides = [f'plugins.use={plugins + extra}'.replace("'", '"')] + (sets or [])
            t_end = args.tank_t_end if key.startswith("tank") else None
            s = runner.run(ROOT / "cases" / case, output=out, overrides=overrides, t_end=t_end, overwrite=True,
                           quiet=True)
            row = f"| {case}{LABELS.get(key, '')} | {label} | {figures(key, s)} | {s['wall_time_s']:.0f} |"
            print(row, flush=True)
            lines.append(row)
            if key in ("buchner", "lobovsky") and s["status"] == "completed":
                subprocess.run([sys.executable, str(ROOT / "postprocessing" / "probes.py"), str(out)], check=True,
                               stdout=subprocess.DEVNULL)
                for png in out.glob("probe_*.png"):
                    png.replace(plots / f"{key}_{'_'.join(plugins)}_{png.name}")
    Path(args.out).write_text("\n".join(lines) + "\n")
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
