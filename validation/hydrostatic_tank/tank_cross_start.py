"""Is one boundary's equilibrium of a tank at rest an equilibrium of another's?

    python validation/hydrostatic_tank/tank_cross_start.py [--case cases/hydrostatic_tank] [--relax-with ghost]
                                              [--run-with wall_integral] [--h 2.0] [--relax 10] [--time 5]
                                              [--run-set KEY=VALUE ...]

Relaxes the case (plain Tait pressure, ``kernel.h_over_dx = H``) with ``reflective`` and the
boundary plugin ``--relax-with`` (:mod:`sphcore.run.relax`, ``--relax`` seconds), then starts a
second run of the same case with ``reflective`` and ``--run-with`` from those positions and
densities, at rest, and runs it for ``--time`` seconds, with the overrides ``--run-set`` (each
like ``sph run --set``; for the second run only, e.g. a density diffusion the relaxation did
not have). Prints

- the accelerations (in g) the second boundary gives the first one's equilibrium, per
  layer of one dx from the top and per column from the left wall (the first six columns
  and the middle one): where the two boundaries disagree;
- at the end: the largest displacement (dx), and the pressure error of the top ten layers
  (the layer mean against rho0 g (H - y), in % of the hydrostatic pressure, as the
  ``pressure_gauge`` plugin measures it).

The validation page "The tank at rest" (docs/validation/hydrostatic_tank.md) cites what it
finds for the wall model against the ghosts.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from sphcore.case.overrides import parse_set
from sphcore.errors import CaseError
from sphcore.run import runner
from sphcore.run.build import build
from sphcore_plugins.gauges.hydrostatic import layer_errors

ROOT = Path(__file__).resolve().parents[2]  # the repository


def load(case_dir, boundary: str, h: float, relax: float, t_end: float | None = None, extra=()):
    sets = ["physics.modified_pressure=false", f"kernel.h_over_dx={h!r}",
            f'plugins.use=["reflective","{boundary}"]', f"relax.time={relax!r}"]
    if t_end is not None:
        sets.append(f"time.t_end={t_end!r}")
    return runner.load(case_dir, [parse_set(s) for s in sets] + [parse_set(s, "--run-set") for s in extra])


def by_id(st):
    return np.argsort(st.id)


def layer_table(pos, field, dx, top, columns):
    """Mean of ``field`` rows (n, k) per (layer from the top, column) of one dx."""
    col = np.floor((pos[:, 0] - pos[:, 0].min()) / dx + 0.5).astype(int)
    lay = np.floor((top - pos[:, 1]) / dx).astype(int)
    rows = []
    for k in range(10):
        row = []
        for c in columns:
            sel = (col == c) & (lay == k)
            row.append(field[sel].mean(axis=0) if sel.any() else np.full(field.shape[1], np.nan))
        rows.append(row)
    return rows


def cross_start(case_dir, relax_with, run_with, h, relax, time, run_sets=()):
    """Relax with ``relax_with``, run with ``run_with`` from there (module docstring).
    Returns the second boundary's start accelerations (layers from the top x ``columns``
    x 2, in g), the columns, the largest displacement at the end (dx) and the layers'
    pressure errors at the end (fractions, top layer first)."""
    first = build(*load(case_dir, relax_with, h, relax))
    case, pm = load(case_dir, run_with, h, 0.0, time, run_sets)
    sim = build(case, pm)
    a, b = by_id(sim.state), by_id(first.state)
    if not np.array_equal(sim.state.id[a], first.state.id[b]):
        raise ValueError("the two runs do not hold the same particles")
    st = sim.state
    st.pos[a] = first.state.pos[b]
    st.rho[a] = first.state.rho[b]
    st.vel[:] = 0.0
    sim.integrator.invalidate()
    sim.update_pressure()
    prm = sim.ctx.params
    dx, g = prm.dx, prm.g_abs
    acc, drho = np.zeros_like(st.pos), np.zeros(st.n)
    sim.forces.evaluate(acc, drho)
    pos0 = st.pos[a].copy()
    top = pos0[:, 1].max() + 0.5 * dx
    ncol = int(round((pos0[:, 0].max() - pos0[:, 0].min()) / dx)) + 1
    columns = list(range(min(6, ncol))) + [ncol // 2]
    table = np.array(layer_table(pos0, acc[a] / g, dx, top, columns))
    while not sim.done():
        sim.advance()
    a = by_id(st)
    moved = np.linalg.norm(st.pos[a] - pos0, axis=1).max() / dx
    floor = pos0[:, 1].min() - 0.5 * dx  # blocks are filled dx/2 from their faces
    rows = layer_errors(st.pos[a, 1] - floor, st.p[a], dx, top - floor, prm.rho0, g)
    return table, columns, moved, rows[::-1, 3], sim.t


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", type=Path, default=ROOT / "cases" / "hydrostatic_tank")
    ap.add_argument("--relax-with", default="ghost")
    ap.add_argument("--run-with", default="wall_integral")
    ap.add_argument("--h", type=float, default=2.0, help="kernel.h_over_dx")
    ap.add_argument("--relax", type=float, default=10.0, help="relaxation time (s) with --relax-with")
    ap.add_argument("--time", type=float, default=5.0, help="run time (s) with --run-with")
    ap.add_argument("--run-set", action="append", default=[], metavar="KEY=VALUE",
                    help="an override of the second run only (as sph run --set); repeatable")
    args = ap.parse_args(argv)
    if args.relax <= 0 or args.time <= 0:
        print("--relax and --time must be positive", file=sys.stderr)
        return 2
    try:
        table, columns, moved, errors, t = cross_start(args.case, args.relax_with, args.run_with, args.h,
                                                       args.relax, args.time, args.run_set)
    except (CaseError, ValueError) as e:  # a case or a plugin name that cannot run
        print(e, file=sys.stderr)
        return 2
    print(f"{args.run_with} from the equilibrium of {args.relax_with} (h = {args.h:g} dx, relaxed {args.relax:g} s): "
          f"accelerations (x, y) in g, layers from the top, columns from the left wall {columns}")
    for k, row in enumerate(table):
        print(f"  layer {k}: " + "  ".join(f"{v[0]:+.3f},{v[1]:+.3f}" for v in row))
    print(f"after {t:g} s: largest displacement {moved:.4g} dx; layer pressure errors from the top (%):")
    print("  " + " ".join(f"{100 * e:+.2f}" for e in errors[:10]))
    return 0


if __name__ == "__main__":
    sys.exit(main())
