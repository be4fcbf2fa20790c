"""Dam-break surge front x_front(t) from a run, compared with experiment.

    python postprocessing/wavefront.py RUN_OUTPUT [--a 0.114] [--csv F] [--png F]

Definition of the front (robust to splashes): take the particles whose centre lies within
``band`` particle spacings of the floor (y - y_floor < band * dx, default 2 dx: the two
lowest layers); sort them by x from the back wall; walk along them while consecutive
centres are at most ``gap`` spacings apart (default 2 dx). The last particle of that
connected chain is the tip, and x_front = its centre + its radius (the water's edge, not
the particle centre). A drop separated from the chain by more than ``gap`` does not count.

Reference data (postprocessing/data/, see its README): Cruchaga et al. (2007) points and
the seed paper's own SPH values; Martin & Moyce (1952) n^2 = 2 front, scaled with the
column width a (Z = x/a, T = t sqrt(2 g / a)).
"""

from __future__ import annotations

import argparse
import csv
import math
from pathlib import Path

import numpy as np

try:
    from frames import frames
except ImportError:  # imported as postprocessing.wavefront
    from .frames import frames

DATA = Path(__file__).parent / "data"
G = 9.81


def front_position(pos, radius, floor=0.0, band=2.0, gap=2.0, axis=0, up=1):
    """x of the connected surge tip (m); see the module docstring."""
    dx = 2.0 * float(np.median(radius))
    near = pos[:, up] - floor < band * dx
    if not near.any():
        return float("nan")
    order = np.argsort(pos[near, axis])
    xs = pos[near, axis][order]
    rs = radius[near][order]
    breaks = np.nonzero(np.diff(xs) > gap * dx)[0]
    tip = breaks[0] if breaks.size else xs.size - 1
    return float(xs[tip] + rs[tip])


def read_reference():
    def rows(name):
        with open(DATA / name) as f:
            return list(csv.DictReader(line for line in f if not line.startswith("#")))

    cru = rows("cruchaga_2007_front_from_seed.csv")
    mm = rows("martin_moyce_1952_n2-2_front.csv")
    return (np.array([[float(r["t_s"]), float(r["x_front_experiment_m"]), float(r["x_front_seed_sph_m"])] for r in cru]),
            np.array([[float(r["T_A"]), float(r["Z_A"])] for r in mm]))


def compare(t, x, a=0.114):
    """Errors against Cruchaga (relative, at its times) and Martin & Moyce (RMS relative, T <= 3)."""
    cru, mm = read_reference()
    out = {}
    for tc, xe, xs in cru:
        xi = float(np.interp(tc, t, x)) if t[0] <= tc <= t[-1] else float("nan")
        out[f"x_front_{tc:.2f}s_m"] = xi
        out[f"err_cruchaga_{tc:.2f}s"] = (xi - xe) / xe
        out[f"err_seed_sph_{tc:.2f}s"] = (xs - xe) / xe
    big_t = t * math.sqrt(2 * G / a)
    sel = (mm[:, 0] <= 3.0) & (mm[:, 0] <= big_t[-1])
    z_sim = np.interp(mm[sel, 0], big_t, x / a)
    out["rms_rel_err_martin_moyce_T3"] = float(np.sqrt(np.mean(((z_sim - mm[sel, 1]) / mm[sel, 1]) ** 2)))
    out["martin_moyce_points"] = int(sel.sum())
    return out


def plot(t, x, a, png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    cru, mm = read_reference()
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
    ap.add_argument("--a", type=float, default=0.114, help="initial column width (m)")
    ap.add_argument("--band", type=float, default=2.0, help="floor band height in particle spacings")
    ap.add_argument("--gap", type=float, default=2.0, help="largest gap in the connected front, in spacings")
    ap.add_argument("--csv", help="output CSV (default RUN/wavefront.csv)")
    ap.add_argument("--png", help="output PNG (default RUN/wavefront.png)")
    args = ap.parse_args(argv)
    run = Path(args.run)
    outdir = run if run.is_dir() else run.parent
    series = [(t, front_position(p, f["radius"], band=args.band, gap=args.gap)) for t, p, f in frames(run)]
    t, x = np.array(series).T
    csv_path = Path(args.csv or outdir / "wavefront.csv")
    np.savetxt(csv_path, np.c_[t, x], delimiter=",", header="t_s,x_front_m", comments="", fmt="%.6g")
    plot(t, x, args.a, args.png or outdir / "wavefront.png")
    res = compare(t, x, args.a)
    for k, v in res.items():
        print(f"{k:32s} {v:.4f}" if isinstance(v, float) else f"{k:32s} {v}")
    return res


if __name__ == "__main__":
    main()
