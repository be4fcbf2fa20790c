"""Tank at rest: pressure against depth, layer by layer, against the hydrostatic rho g (H - y).

Reads   RUN, the output directory of a 2D tank-at-rest run (or its .pvd / particles.nc):
        its last frame (or the one nearest --time) and summary.json (the still-water depth
        H and the density rho0, unless given).
Writes  RUN/pressure_profile.csv (columns y_m, p_mean_pa, p_min_pa, p_max_pa,
        p_hydrostatic_pa, rel_err; one row per horizontal particle layer, layers one
        spacing dx = 2 r apart counted from the floor) and RUN/pressure_profile.png; prints
        the largest layer error below the top two layers, the criterion of the validation.

``--column XA XB`` (repeatable) also prints, for the particles with XA <= x < XB, layer by
layer from the top: the mean pressure's departure from rho0 g (H - y) in units of
rho0 g dx, and the mean height's departure from the layer's lattice height (k + 1/2) dx in
units of dx (a pattern of the layers that the means over the whole width average away).
The layer means and errors are the pressure_gauge plugin's (one definition).
A path that is not a tank-at-rest run: one line on stderr, exit status 2.

    python postprocessing/pressure_profile.py cases/hydrostatic_tank/output --column 0.5 0.52
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
from runs import RunError, open_run, pyplot, refuse

from sphcore_plugins.gauges.hydrostatic import layer_errors

PROG = Path(__file__).name
G = 9.81


def layer_profile(pos, p, radius, H, rho0, floor=0.0, up=1):
    """Rows (y, p_mean, p_min, p_max, p_hydrostatic, rel_err) per particle layer, and dx;
    the layer means and errors are the ``pressure_gauge`` plugin's (one definition)."""
    dx = 2.0 * float(np.median(radius))
    y = pos[:, up] - floor
    rows = layer_errors(y, p, dx, H, rho0, G)
    layer = np.floor(y / dx).astype(int)
    spread = np.array([(p[layer == k].min(), p[layer == k].max()) for k in np.unique(layer)])
    return np.c_[rows[:, 0], rows[:, 1], spread, rows[:, 2], rows[:, 3]], dx


def column_profile(pos, p, dx, H, rho0, xa, xb, up=1, across=0):
    """Rows (layer from the top, 1-based; pressure departure / (rho0 g dx); height departure
    / dx) of the particles with xa <= x < xb, from the top layer down; the layers and their
    means are the ``pressure_gauge`` plugin's, as in :func:`layer_profile`."""
    sel = (pos[:, across] >= xa) & (pos[:, across] < xb)
    rows = layer_errors(pos[sel, up], p[sel], dx, H, rho0, G)  # (mean y, mean p, rho0 g (H - mean y), err)
    k = np.floor(rows[:, 0] / dx)  # the layer's index from the floor
    out = np.c_[np.rint(H / dx) - k, (rows[:, 1] - rows[:, 2]) / (rho0 * G * dx), (rows[:, 0] - (k + 0.5) * dx) / dx]
    return out[::-1]


def plot(prof, t, worst, png):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(4.5, 5))
    ax.fill_betweenx(prof[:, 0], prof[:, 2], prof[:, 3], alpha=0.25, label="min-max in layer")
    ax.plot(prof[:, 1], prof[:, 0], "o-", ms=3, label="layer mean")
    ax.plot(prof[:, 4], prof[:, 0], "k--", label=r"$\rho g (H - y)$")
    ax.set_xlabel("p [Pa]")
    ax.set_ylabel("y [m]")
    ax.set_title(f"t = {t:.3g} s, worst layer error {100 * worst:.2f}%", fontsize=9)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="a tank-at-rest run's output directory, .pvd or particles.nc")
    ap.add_argument("--H", type=float, help="still-water depth (m); default: the run's fluid block")
    ap.add_argument("--rho0", type=float, help="reference density (kg/m^3); default: the run's")
    ap.add_argument("--time", type=float, help="frame time (s); default: the last frame")
    ap.add_argument("--column", type=float, nargs=2, action="append", metavar=("XA", "XB"),
                    help="also print the layers of the particles with XA <= x < XB (m): pressure and height "
                         "departures (repeatable)")
    args = ap.parse_args(argv)
    for xa, xb in args.column or ():
        if not xa < xb:
            ap.error(f"--column {xa:g} {xb:g}: expected XA < XB (m)")
    try:
        run = open_run(args.run, "tank_at_rest")
        H, rho0 = args.H, args.rho0
        if run.config:
            _, hi = run.block_extent(run.first_block())
            H = hi[1] - float(run.config["domain"]["min"][1]) if H is None else H
            rho0 = float(run.config["fluid"]["rho0"]) if rho0 is None else rho0
        H = 1.0 if H is None else H  # the seed's tank: runs without a config
        rho0 = 1000.0 if rho0 is None else rho0
        chosen = None
        for frame in run.frames():
            if chosen is None or args.time is None or abs(frame[0] - args.time) < abs(chosen[0] - args.time):
                chosen = frame
        if chosen is None:
            raise RunError(f"{run.frames_file()}: no frame written yet")
    except RunError as err:
        return refuse(PROG, err)
    t, pos, f = chosen
    prof, dx = layer_profile(pos, f["pressure"], f["radius"], H, rho0)
    np.savetxt(run.dir / "pressure_profile.csv", prof, delimiter=",", comments="", fmt="%.6g",
               header="y_m,p_mean_pa,p_min_pa,p_max_pa,p_hydrostatic_pa,rel_err")
    below = prof[:, 0] < H - 2 * dx
    worst = float(np.nanmax(np.abs(prof[below, 5])))
    plot(prof, t, worst, run.dir / "pressure_profile.png")
    print(f"t = {t:.6g} s: largest layer-mean error below the top two layers: {100 * worst:.3f}%")
    for xa, xb in args.column or ():
        rows = column_profile(pos, f["pressure"], dx, H, rho0, xa, xb)
        print(f"x in [{xa:g}, {xb:g}) m, layer from the top: (p - rho0 g (H - y)) / (rho0 g dx), "
              f"(y - lattice height) / dx")
        for k, dp, dy in rows:
            print(f"  {int(k):4d}  {dp:+.4f}  {dy:+.3e}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
