"""Dam break: the surge front x_front(t) from a run's frames, against experiment.

Reads   RUN, the output directory of a 2D dam-break run (or its .pvd / particles.nc): every
        frame (the vtu or netcdf plugin) and summary.json (the column width a and the far
        wall, unless given).
Writes  RUN/wavefront.csv (columns t_s, x_front_m; one row per frame) and RUN/wavefront.png
        (the front against Cruchaga et al. 2007, the seed paper's SPH values, and Martin &
        Moyce 1952, n^2 = 2, scaled with a: Z = x/a, T = t sqrt(2 g / a)); prints the errors
        against them (nan where the run does not reach an experiment's time).

The front (a connected chain of particles along the floor, so isolated splashes do not
count; x_front = tip centre + radius) and the comparison are those of the front_gauge
plugin (sphcore_plugins.gauges.front), so post-processing and the in-run gauge agree.
A path that is not a dam-break run: one line on stderr, exit status 2.

    python postprocessing/wavefront.py cases/dam_break/output
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from runs import RunError, open_run, pyplot, refuse

from sphcore_plugins.gauges import reference
from sphcore_plugins.gauges.front import compare, front_position

PROG = Path(__file__).name
G = 9.81
SEED_COLUMN_M, SEED_TANK_M = 0.114, 0.42  # the seed's column width and tank length: runs without a config


def plot(t, x, a, png):
    plt = pyplot()
    cru, mm = reference.cruchaga(), reference.martin_moyce()
    fig, ax = plt.subplots(figsize=(6, 4))
    ax.plot(t, x, "-", label="sphcore")
    ax.plot(mm[:, 0] / math.sqrt(2 * G / a), mm[:, 1] * a, "s", mfc="none", label=f"Martin & Moyce 1952, n²=2, a={a} m")
    ax.plot(cru[:, 0], cru[:, 1], "o", ms=8, label="Cruchaga et al. 2007 (experiment)")
    ax.plot(cru[:, 0], cru[:, 2], "x", ms=8, label="seed paper SPH")
    ax.set_xlabel("t [s]")
    ax.set_ylabel("x_front [m]")
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="a dam-break run's output directory, .pvd or particles.nc")
    ap.add_argument("--a", type=float, help="initial column width (m); default: the run's first fluid block")
    ap.add_argument("--band", type=float, default=2.0, help="floor band height in particle spacings")
    ap.add_argument("--gap", type=float, default=2.0, help="largest gap in the connected front, in spacings")
    ap.add_argument("--csv", help="output CSV (default RUN/wavefront.csv)")
    ap.add_argument("--png", help="output PNG (default RUN/wavefront.png)")
    ap.add_argument("--x-wall", type=float, help="opposite wall (m): Martin & Moyce points beyond it are left out; "
                    "default: the run's domain")
    args = ap.parse_args(argv)
    try:
        run = open_run(args.run, "dam_break")
        a, x_wall = args.a, args.x_wall
        if run.config:
            lo, hi = run.block_extent(run.first_block())
            a = hi[0] - lo[0] if a is None else a
            x_wall = float(run.config["domain"]["max"][0]) if x_wall is None else x_wall
        a = SEED_COLUMN_M if a is None else a
        x_wall = SEED_TANK_M if x_wall is None else x_wall
        series, radius = [], None
        for t, pos, fields in run.frames():
            series.append((t, front_position(pos, fields["radius"], band=args.band, gap=args.gap)))
            radius = fields["radius"] if radius is None else radius
        if not series:
            raise RunError(f"{run.frames_file()}: no frame written yet")
    except RunError as err:
        return refuse(PROG, err)
    t, x = np.array(series).T
    csv_path = Path(args.csv or run.dir / "wavefront.csv")
    np.savetxt(csv_path, np.c_[t, x], delimiter=",", header="t_s,x_front_m", comments="", fmt="%.6g")
    plot(t, x, a, args.png or run.dir / "wavefront.png")
    res = compare(t, x, a, x_wall - 2 * float(np.median(radius)))
    for k, v in res.items():
        print(f"{k:32s} {v:.4f}" if isinstance(v, float) else f"{k:32s} {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
