"""The density rate a divergence-free flow onto a wall gives the layers next to it, at t = 0.

A box filled with the initial lattice (no gravity) is given the stagnation flow u = a x
along the floor and w = -a z across it (x, z from the box's centre line and floor; a =
1/s): divergence-free and impermeable at the floor, so drho/dt = 0 is the exact answer at
every particle. Prints drho/dt / (rho0 a) layer by layer from the floor (mean over the
particles far from the side walls), with the reflective walls alone and with the wall
model, 2D and 3D, h = 1.3 and 2 dx. What the figures mean is in docs/wall_pressure.md, "The
floor layer's excess: the continuity's wall completion".

    python validation/dam_break_buchner/wall_divergence.py [--layers K]
"""

from __future__ import annotations

import argparse
import tempfile
from pathlib import Path

import numpy as np

from sphcore.run import runner
from sphcore.run.build import build
from sphcore.testing import write_case

BOX = """
[case]
dim = {dim}
[domain]
min = {lo}
max = {hi}
[[blocks]]
min = {lo}
max = {hi}
[particles]
dx = {dx}
[kernel]
h_over_dx = {hdx}
[physics]
gravity = {g}
hydrostatic_init = false
[eos]
c0 = 20.0
[viscosity]
alpha = 0.0
[time]
t_end = 0.01
[plugins]
use = {use}
"""

SIDE = 0.4  # m, the box's edge
DX = 0.02  # m


def layer_rates(dim: int, hdx: float, use: str, layers: int, work: Path) -> list[float]:
    """drho/dt / rho0 per layer from the floor, for the stagnation flow with a = 1/s."""
    lo, hi = [0.0] * dim, [SIDE] * dim
    text = BOX.format(dim=dim, lo=lo, hi=hi, dx=DX, hdx=hdx, g=[0.0] * dim, use=use)
    case, pm = runner.load(write_case(work / f"box{dim}_{hdx}_{len(use)}", text))
    sim = build(case, pm)
    st = sim.ctx.state
    x = st.pos
    st.vel[:] = 0.0
    st.vel[:, 0] = x[:, 0] - 0.5 * SIDE
    st.vel[:, -1] = -x[:, -1]
    sim.integrator.invalidate()
    sim.integrator.rates()
    drho = sim.integrator.drho / case.config["fluid"]["rho0"]
    far = np.all(np.abs(x[:, :-1] - 0.5 * SIDE) < 0.5 * SIDE - 2.0 * hdx * DX - 1e-9, axis=1)
    out = []
    for k in range(layers):
        m = far & (np.abs(x[:, -1] - (k + 0.5) * DX) < 1e-9)
        out.append(float(drho[m].mean()))
    return out


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--layers", type=int, default=5, help="layers from the floor to print")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        for dim in (2, 3):
            for hdx in (1.3, 2.0):
                for name, use in (("reflective", '["reflective"]'),
                                  ("reflective + wall model", '["reflective", "wall_integral"]')):
                    rates = layer_rates(dim, hdx, use, args.layers, Path(tmp))
                    print(f"{dim}D h = {hdx} dx, {name:24s} drho/dt / (rho0 a), layers from the floor: "
                          + " ".join(f"{r:+.3f}" for r in rates))
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
