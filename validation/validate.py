"""The paper's validations, each boundary treatment, one table.

    python validation/validate.py [--tank-t-end 5.0] [--out docs/validation.md]

Runs, without VTU/netCDF output (the gauges measure in-run):
- dam break (cases/dam_break, 0.3 s) with reflective, ghost, ghost + reflective, and the
  seed paper's exact setup (explicit Euler, dt = 1e-5 s, free surface at p = 0, corrected
  kernel gradient, Eq. 2 at the end point) with reflective walls;
- hydrostatic tank (cases/hydrostatic_tank, 5 s) with each boundary, with the modified
  pressure (the paper's formulation) and with plain Tait.
Prints a Markdown table of the errors against experiment / hydrostatics, wall time and
throughput, and writes it to --out. A run that goes unstable is reported as such.
"""

from __future__ import annotations

import argparse
import math
import tempfile
from pathlib import Path

from sphcore.run import runner

ROOT = Path(__file__).resolve().parents[1]  # the repository
BOUNDARIES = {"reflective": ["reflective"], "ghost": ["ghost"], "ghost+reflective": ["ghost", "reflective"]}
PAPER = ['integrator.scheme="euler"', "time.dt=1e-5", 'reflective.velocity="end"',
         'corrections.kernel_gradient=true']


def runs(tank_t_end):
    for name, plugins in BOUNDARIES.items():
        yield "dam_break", name, "default", [f"plugins.use={plugins + ['front_gauge']}"], None
    yield "dam_break", "reflective", "paper (Euler, dt=1e-5, free surface, CSPH)", \
        [f"plugins.use={['reflective', 'free_surface', 'front_gauge']}"] + PAPER, None
    for mp, label in ((True, "modified pressure"), (False, "plain Tait")):
        for name, plugins in BOUNDARIES.items():
            yield "hydrostatic_tank", name, label, [f"plugins.use={plugins + ['pressure_gauge']}",
                                                     f"physics.modified_pressure={str(mp).lower()}"], tank_t_end


def fmt(v, pct=False):
    if v is None or (isinstance(v, float) and math.isnan(v)):
        return "-"
    return f"{100 * v:+.1f}%" if pct else f"{v:.4g}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--tank-t-end", type=float, default=5.0, help="simulated time of the tank runs (s)")
    ap.add_argument("--out", default=str(ROOT / "docs" / "validation.md"))
    args = ap.parse_args(argv)
    rows = []
    work = Path(tempfile.mkdtemp(prefix="sph-validate-"))
    for k, (case, boundary, variant, sets, t_end) in enumerate(runs(args.tank_t_end)):
        sets = [s.replace("'", '"') for s in sets]
        s = runner.run(ROOT / "cases" / case, output=work / f"run{k}", overrides=sets, t_end=t_end,
                       overwrite=True, quiet=True).summary
        rows.append((case, boundary, variant, s))
        status = s["status"] if s["status"] == "completed" else f"{s['status']} at t = {s['t']:.3g} s"
        print(f"{case:17s} {boundary:17s} {variant:44s} {status}, {s['wall_time_s']:.1f} s", flush=True)
    lines = ["| case | boundary | variant | status | x_front 0.1 s (err vs Cruchaga) | x_front 0.2 s (err) "
             "| RMS vs Martin & Moyce (T<=3) | wall s | particle-steps/s |",
             "|---|---|---|---|---|---|---|---|---|"]
    for case, boundary, variant, s in rows:
        if case != "dam_break":
            continue
        st = s["status"] if s["status"] == "completed" else f"{s['status']} (t = {s['t']:.3g} s)"
        lines.append(f"| {case} | {boundary} | {variant} | {st} | {fmt(s.get('front_gauge', {}).get('x_front_0.10s_m'))} m "
                     f"({fmt(s.get('front_gauge', {}).get('err_cruchaga_0.10s'), True)}) | {fmt(s.get('front_gauge', {}).get('x_front_0.20s_m'))} m "
                     f"({fmt(s.get('front_gauge', {}).get('err_cruchaga_0.20s'), True)}) | {fmt(s.get('front_gauge', {}).get('rms_rel_err_martin_moyce_T3'), True)} "
                     f"| {s['wall_time_s']:.1f} | {s['particle_steps_per_s']:.3g} |")
    lines += ["", "| case | boundary | variant | status | particles lost | max displacement (m) | surface drift (m) "
              "| worst layer pressure error (below top 2 layers) | wall s | particle-steps/s |",
              "|---|---|---|---|---|---|---|---|---|---|"]
    for case, boundary, variant, s in rows:
        if case == "dam_break":
            continue
        st = s["status"] if s["status"] == "completed" else f"{s['status']} (t = {s['t']:.3g} s)"
        lines.append(f"| {case} ({s['t']:.3g} s) | {boundary} | {variant} | {st} | {s.get('pressure_gauge', {}).get('particles_lost', '-')} "
                     f"| {fmt(s.get('pressure_gauge', {}).get('max_displacement_m'))} | {fmt(s.get('pressure_gauge', {}).get('surface_drift_m'))} "
                     f"| {fmt(s.get('pressure_gauge', {}).get('pressure_max_layer_err'), True)} | {s['wall_time_s']:.1f} "
                     f"| {s['particle_steps_per_s']:.3g} |")
    table = "\n".join(lines)
    print("\n" + table)
    Path(args.out).parent.mkdir(parents=True, exist_ok=True)
    Path(args.out).write_text("# Validation: the seed paper's cases with each boundary treatment\n\n"
                              f"Regenerate with `python validation/validate.py --tank-t-end {args.tank_t_end:g}`.\n\n"
                              + table + "\n")


if __name__ == "__main__":
    main()
