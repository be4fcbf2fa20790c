"""The wall model's load on a box held at its draft, part by part, against the hydrostatic
load on its bottom: how many particles must span the draft.

    python validation/floating_bodies/held_load.py {2d,3d-small,3d-large} [--first 100] [--steps 400]

A box of density 500 is held (``release`` beyond the run) at the draft its density gives,
in water 0.3 m deep, with the reflective walls and the wall model (h_sml = 2 dx):

- ``2d``: the box of ``cases/floating_box`` (0.2 x 0.1 m, dx = 0.01 m), drawn 5 mm above
  its draft, so that its bottom sits a full dx above the first fluid row;
- ``3d-small``: a 0.2 x 0.2 x 0.1 m box in a 0.6 m square tank, dx = 0.0125 m, draft
  0.0375 m (3 dx), 54,528 particles;
- ``3d-large``: a 0.4 x 0.4 x 0.2 m box in a 1 m square tank, dx = 0.0125 m, draft 0.1 m
  (8 dx), 145,408 particles.

Every fifth step from ``--first`` to ``--steps``, the load the box takes (minus the sum of
m_i w_i times the acceleration the wall completion gave the particles its faces reach, w_i
the box's share of their wall gradient: exactly what the body is kicked with) is split by
where the particles are (under the box's bottom, beside its sides above the bottom, and
beside them below it: the edges) and by term (the wall pressure, 2 p/rho G_w; the first
moment, the rest); the means are printed against rho g d A, the hydrostatic load on the
bottom. A study, not a test: minutes for the 2D box, tens of minutes in 3D on two cores.
"""

from __future__ import annotations

import argparse
import sys
import tempfile
from pathlib import Path

import numpy as np

from sphcore.physics.pairterms import W_GAMMA
from sphcore.run import runner
from sphcore.run.build import build

TANK = """
[case]
name = "held_box"
dim = {dim}
[domain]
min = {zero}
max = {top}
[[domain.walls]]
shape = "box"
min = {lo}
max = {hi}
[[bodies]]
wall = 0
density = 500.0
release = 1000.0
[[blocks]]
min = {zero}
max = {water}
[particles]
dx = {dx}
[kernel]
h_over_dx = 2.0
[viscosity]
alpha = 0.02
[density_diffusion]
delta = 0.1
hydrostatic = true
[time]
t_end = 1000.0
[physics]
gravity = {gravity}
[plugins]
use = ["reflective", "wall_integral"]
"""

# name: (dim, tank side, box min, box max, dx)
BOXES = {
    "2d": (2, 1.0, [0.4, 0.255], [0.6, 0.355], 0.01),
    "3d-small": (3, 0.6, [0.2, 0.2, 0.2625], [0.4, 0.4, 0.3625], 0.0125),
    "3d-large": (3, 1.0, [0.3, 0.3, 0.2], [0.7, 0.7, 0.4], 0.0125),
}
DEPTH = 0.3


def case_text(name: str) -> str:
    dim, side, lo, hi, dx = BOXES[name]
    top = [side] * (dim - 1) + [0.6]
    return TANK.format(dim=dim, zero=[0.0] * dim, top=top, lo=lo, hi=hi, water=[side] * (dim - 1) + [DEPTH],
                       dx=dx, gravity=[0.0, -9.81, 0.0] if dim == 2 else [0.0, 0.0, -9.81])


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("box", choices=sorted(BOXES))
    ap.add_argument("--first", type=int, default=100, help="first step of the means")
    ap.add_argument("--steps", type=int, default=400, help="last step")
    args = ap.parse_args(argv)
    dim, _, lo, hi, _ = BOXES[args.box]
    lo, hi, up = np.array(lo), np.array(hi), dim - 1
    with tempfile.TemporaryDirectory() as tmp:
        (Path(tmp) / "case.toml").write_text(case_text(args.box))
        case, pm = runner.load(Path(tmp))
        sim = build(case, pm)
        sums, count, side = {}, 0, np.zeros(dim - 1)
        for step in range(args.steps):
            sim.advance()
            if step < args.first or step % 5:
                continue
            st, react = sim.state, sim.forces.wall_react()
            idx, w = sim.ctx.wall_members["bodies[0]"]
            wall, work = sim.forces.wall_terms_last(), sim.forces.work_last()
            fill, gam = wall.fill[idx], work[idx, W_GAMMA]
            phi = np.where(fill > 0, np.minimum(1.0, gam / np.where(fill > 0, fill, 1.0)), 1.0)
            pressure = -(2.0 * st.p[idx] / st.rho[idx] * phi)[:, None] * wall.grad[idx]
            mw = (st.m[idx] * w)[:, None]
            load, load_p = -mw * react[idx], -mw * pressure
            p = st.pos[idx]
            inside = np.all((p[:, :up] > lo[:up]) & (p[:, :up] < hi[:up]), axis=1)
            below = p[:, up] < lo[up]
            for part, m in (("under the bottom", inside & below), ("beside, above the bottom", ~inside & ~below),
                            ("beside, below the bottom", ~inside & below)):
                s = sums.setdefault(part, np.zeros(3))
                s += [load[m, up].sum(), load_p[m, up].sum(), m.sum()]
            side += load[:, :up].sum(axis=0)
            count += 1
        n, t = sim.state.n, sim.t
    area = float(np.prod(hi[:up] - lo[:up]))
    bottom = 1000.0 * 9.81 * (DEPTH - lo[up]) * area
    total = sum(s[0] for s in sums.values()) / count
    unit = "N/m" if dim == 2 else "N"
    print(f"{args.box}: {n} particles, draft {DEPTH - lo[up]:.4g} m, means of {count} samples "
          f"(steps {args.first}-{args.steps}, t <= {t:.3f} s)")
    print(f"{'particles':26s} {'count':>7s} {'load':>10s} {'pressure':>10s} {'moment':>10s}  [{unit}, up]")
    for part, s in sums.items():
        print(f"{part:26s} {s[2] / count:7.0f} {s[0] / count:10.3f} {s[1] / count:10.3f} {(s[0] - s[1]) / count:10.3f}")
    print(f"{'total':26s} {'':7s} {total:10.3f}")
    print(f"{'across (' + ', '.join('xy'[:up]) + ')':26s} {'':7s} " + " ".join(f"{v / count:10.5f}" for v in side))
    print(f"hydrostatic on the bottom, rho g d A: {bottom:.3f} {unit}; total / it - 1: {100 * (total / bottom - 1):+.1f} %")
    return 0


if __name__ == "__main__":
    sys.exit(main())
