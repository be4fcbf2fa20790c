"""How strongly the tank at rest resists a column of particles sliding along a side wall.

    python validation/hydrostatic_tank/slide_stiffness.py [--h 1.3 1.5 1.7 2.0] [--case cases/hydrostatic_tank]

The plain-Tait tank (no modified pressure, hydrostatic start, density diffusion as in
docs/wall_pressure.md) at t = 0, one force evaluation per row: a whole column of particles
(the one next to the left wall, the second, one in the middle) is moved down by 1e-4 dx,
the density held (a frozen-density, instantaneous response), and the change of its
vertical acceleration, over the particles 0.3-0.7 m deep, gives the stiffness
k = -d a_y / d y of that column's slide, in g / dx (> 0: pushed back). Printed for the
reflective walls with the wall model (``wall_integral``) and with ghosts.

What it shows: in the interior the pair sum of a column pair is restoring or not depending
on the column spacing (at h = 1.5 dx the nearest column pushes the slide on, the next one
holds it back). A ghost is the mirror image of a fluid particle, so a column near a wall
feels its neighbours' mirror images as well; the wall model's terms depend on the
particle's distance to the wall and its own pressure only, so a column's slide relative to
its neighbours' images is not felt at all. This is an instantaneous measure; whether a
tank stays at rest also depends on the density's response over time (at h = 2 dx every
column here has k < 0, and the tank still stays within 0.17 dx).
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from sphcore.case.overrides import parse_set
from sphcore.run import runner
from sphcore.run.build import build

ROOT = Path(__file__).resolve().parents[2]  # the repository
BOUNDARIES = {"wall model": '["reflective","wall_integral"]', "ghosts": '["ghost","reflective"]'}


def stiffness(case_dir: Path, h: float, plugins: str) -> dict:
    """{column: k in g/dx} of the tank at t = 0 (see the module docstring)."""
    sets = ["physics.modified_pressure=false", f"kernel.h_over_dx={h}", "density_diffusion.delta=0.1",
            "density_diffusion.hydrostatic=true", f"plugins.use={plugins}"]
    case, pm = runner.load(case_dir, [parse_set(s) for s in sets])
    sim = build(case, pm)
    st, dx = sim.state, case.dx
    g = float(np.linalg.norm(case.gravity))

    def vertical_acc():
        acc, drho = np.zeros_like(st.vel), np.zeros(st.n)
        sim.forces.evaluate(acc, drho)
        return acc[:, 1].copy()

    a0 = vertical_acc()
    x, y = st.pos[:, 0], st.pos[:, 1]
    lo = float(x.min())
    deep = (y > 0.3) & (y < 0.7)
    columns = {"next to the wall": x < lo + 0.5 * dx, "second": np.abs(x - lo - dx) < 0.5 * dx,
               "middle": np.abs(x - x[np.argmin(np.abs(x - np.median(x)))]) < 0.5 * dx}
    out = {}
    eps = 1e-4 * dx
    for name, sel in columns.items():
        saved = st.pos.copy()
        st.pos[sel, 1] -= eps
        a1 = vertical_acc()
        st.pos[:] = saved
        out[name] = float(np.median(-(a1 - a0)[sel & deep] / eps)) * dx / g
    return out


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--h", type=float, nargs="+", default=[1.3, 1.5, 1.7, 2.0], help="h / dx")
    ap.add_argument("--case", type=Path, default=ROOT / "cases" / "hydrostatic_tank")
    a = ap.parse_args()
    print("slide stiffness of a column, k = -d a_y / d y in g / dx (> 0: restoring), tank at t = 0")
    print(f"{'h/dx':>5} {'boundary':>11} {'next to the wall':>17} {'second':>8} {'middle':>8}")
    for h in a.h:
        for label, plugins in BOUNDARIES.items():
            k = stiffness(a.case, h, plugins)
            print(f"{h:>5} {label:>11} {k['next to the wall']:>17.4f} {k['second']:>8.4f} {k['middle']:>8.4f}")


if __name__ == "__main__":
    main()
