"""Dam-break surge front x_front(t) from a run's frames, compared with experiment.

    python postprocessing/wavefront.py RUN_OUTPUT [--a 0.114] [--csv F] [--png F]

The front definition (a connected chain along the floor, so isolated splashes do not
count; x_front = tip centre + radius) and the comparison are those of the ``front_gauge``
plugin (``sphcore_plugins.gauges.front``), so post-processing and in-run gauges agree.
Reference data: Cruchaga et al. (2007) and the seed paper's SPH values; Martin & Moyce
(1952) n^2 = 2, scaled with the column width a (Z = x/a, T = t sqrt(2 g / a)).
"""

from __future__ import annotations

import argparse
import math
from pathlib import Path

import numpy as np

from sphcore_plugins.gauges import reference
from sphcore_plugins.gauges.front import compare, front_position

try:
    from frames import frames
    from runs import open_run
except ImportError:  # imported as postprocessing.wavefront
    from .frames import frames
    from .runs import open_run

G = 9.81


def plot(t, x, a, png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

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


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", help="a run's output directory, .pvd or particles.nc")
    ap.add_argument("--a", type=float, help="initial column width (m); default: the run's first fluid block")
    ap.add_argument("--band", type=float, default=2.0, help="floor band height in particle spacings")
    ap.add_argument("--gap", type=float, default=2.0, help="largest gap in the connected front, in spacings")
    ap.add_argument("--csv", help="output CSV (default RUN/wavefront.csv)")
    ap.add_argument("--png", help="output PNG (default RUN/wavefront.png)")
    ap.add_argument("--x-wall", type=float, help="opposite wall (m): Martin & Moyce points beyond it are left out; "
                    "default: the run's domain")
    args = ap.parse_args(argv)
    found = open_run(args.run, "wavefront.py", "dam_break")
    run, outdir = found.frames, found.dir
    if found.config:
        block, dom = found.first_block(), found.config["domain"]
        if args.a is None:
            args.a = float(block["max"][0] - block["min"][0]) if block.get("max") is not None \
                else block["count"][0] * found.config["particles"]["dx"]
        if args.x_wall is None:
            args.x_wall = float(dom["max"][0])
    args.a = 0.114 if args.a is None else args.a  # the seed's column, for runs of older versions
    args.x_wall = 0.42 if args.x_wall is None else args.x_wall
    series = [(t, front_position(p, f["radius"], band=args.band, gap=args.gap)) for t, p, f in frames(run)]
    t, x = np.array(series).T
    csv_path = Path(args.csv or outdir / "wavefront.csv")
    np.savetxt(csv_path, np.c_[t, x], delimiter=",", header="t_s,x_front_m", comments="", fmt="%.6g")
    plot(t, x, args.a, args.png or outdir / "wavefront.png")
    radius = next(frames(run))[2]["radius"]
    res = compare(t, x, args.a, args.x_wall - 2 * float(np.median(radius)))
    for k, v in res.items():
        print(f"{k:32s} {v:.4f}" if isinstance(v, float) else f"{k:32s} {v}")
    return res


if __name__ == "__main__":
    main()
