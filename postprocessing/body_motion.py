"""A floating body's free motion: its period, damping and equilibrium from a run's loads file.

Reads   RUN/wall_loads.csv, written by the wall_loads plugin: each body's position (x, y, z),
        rotation vector (rx, ry, rz), velocities and fluid load, one row per sample.
Writes  RUN/body_<name>_<axis>.png: the coordinate against time, its extrema marked, and the
        damped oscillation the printed figures describe.
Prints  the extrema after the release (or ``--after``) up to ``--until``, the period (twice
        the mean time between successive extrema), the logarithmic decrement per cycle
        (delta = 2 ln(e_k / e_k+1) for successive extrema e_k measured from the equilibrium,
        their mean) and the equilibrium (the midpoints of successive extrema, their mean;
        or ``--equilibrium``).

A body released from rest at the window's start (its velocity there zero) starts at an
extremum, which counts. Extrema are the samples where the coordinate's slope changes sign, refined by the parabola
through the sample and its two neighbours; half-swings smaller than ``--noise`` (m or rad)
are skipped. A missing file, a body the file does not hold, or fewer than three extrema in
the window: one line on stderr, exit status 2.

    python postprocessing/body_motion.py cases/floating_box/output --axis y
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from runs import RunError, open_run, pyplot, refuse

PROG = Path(__file__).name
CSV = "wall_loads.csv"
AXES = ("x", "y", "z", "rx", "ry", "rz")
VELOCITY = {"x": "vx", "y": "vy", "z": "vz", "rx": "wx", "ry": "wy", "rz": "wz"}


def read(run_dir: Path) -> dict:
    """The columns of RUN/wall_loads.csv by name ({"t": ..., "bodies[0].y": ...})."""
    path = run_dir / CSV
    if not path.is_file():
        raise RunError(f"{path}: no such file (expected a run with the wall_loads plugin and a moving body)")
    try:
        lines = [ln for ln in path.read_text().splitlines() if not ln.startswith("#")]
        header = lines[0].split(",")
        data = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    except (OSError, IndexError, ValueError) as err:
        raise RunError(f"{path}: cannot read the loads: {err}") from None
    if header[0] != "t" or data.shape[1] != len(header):
        raise RunError(f"{path}: expected a header t,<group>.Fx,... and one row per sample")
    return {name: data[:, k] for k, name in enumerate(header)}


def bodies(columns: dict) -> list[str]:
    """The groups whose position the file holds (moving walls and bodies), in file order."""
    return [name[:-2] for name in columns if name.endswith(".x")]


def extrema(t, y, noise: float = 0.0):
    """(times, values) of the local extrema of y(t), maxima and minima alternating: where
    the slope changes sign, refined by the parabola through the sample and its neighbours.
    Two extrema of the same kind in a row keep the farther one; a swing smaller than
    ``noise`` is dropped with both its ends' lesser one (ripples on a slow swing)."""
    found = []  # (t, y, is_max)
    for k in range(1, len(y) - 1):
        y0, y1, y2 = y[k - 1], y[k], y[k + 1]
        if not ((y1 - y0) * (y2 - y1) < 0 or (y1 != y0 and y2 == y1)):
            continue
        den = y0 - 2 * y1 + y2
        s = max(-1.0, min(1.0, 0.5 * (y0 - y2) / den)) if den != 0 else 0.0
        h = t[k + 1] - t[k] if s > 0 else t[k] - t[k - 1]
        ext = (t[k] + s * h, y1 - 0.25 * (y0 - y2) * s, y1 > y0)
        if found and found[-1][2] == ext[2]:  # same kind: keep the farther
            if (ext[1] > found[-1][1]) == ext[2]:
                found[-1] = ext
            continue
        if found and abs(ext[1] - found[-1][1]) < noise:
            continue  # a ripple: the next extremum of this kind decides
        found.append(ext)
    return np.array([e[0] for e in found]), np.array([e[1] for e in found])


def decay(te, ye, equilibrium: float | None = None) -> dict:
    """Period, logarithmic decrements and equilibrium of a free decay from its extrema."""
    mids = 0.5 * (ye[1:] + ye[:-1])
    eq = float(np.mean(mids)) if equilibrium is None else float(equilibrium)
    amp = np.abs(ye - eq)
    deltas = 2.0 * np.log(amp[:-1] / amp[1:])
    return {"period": 2.0 * float(np.mean(np.diff(te))), "half_periods": np.diff(te), "deltas": deltas,
            "delta": float(np.mean(deltas)), "equilibrium": eq, "midpoints": mids, "amplitudes": amp}


def plot(t, y, te, ye, fit, name, axis, png):
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.5))
    ax.plot(t, y, "-", lw=1, label="sphcore")
    ax.plot(te, ye, "o", ms=4, label="extrema")
    ax.axhline(fit["equilibrium"], color="0.5", lw=0.8, ls="--", label="equilibrium")
    t0 = te[0]
    omega, zeta_w = 2 * math.pi / fit["period"], fit["delta"] / fit["period"]
    tt = np.linspace(t0, te[-1], 400)
    ax.plot(tt, fit["equilibrium"] + (ye[0] - fit["equilibrium"]) * np.exp(-zeta_w * (tt - t0))
            * np.cos(omega * (tt - t0)), "k:", lw=1,
            label=f"T = {fit['period']:.3f} s, delta = {fit['delta']:.3f}")
    ax.set_xlabel("t [s]")
    ax.set_ylabel(f"{name}.{axis} [{'rad' if axis.startswith('r') else 'm'}]")
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="a run's output directory")
    ap.add_argument("--body", help="the group name (default: the only body or moving wall in the file)")
    ap.add_argument("--axis", default="y", choices=AXES, help="the coordinate (default y)")
    ap.add_argument("--after", type=float, help="start of the window in s (default: the body's release, else 0)")
    ap.add_argument("--until", type=float, default=math.inf, help="end of the window in s (default: the run's end)")
    ap.add_argument("--equilibrium", type=float, help="the equilibrium the amplitudes are measured from")
    ap.add_argument("--noise", type=float, default=0.0, help="smallest half-swing counted (m or rad)")
    args = ap.parse_args(argv)
    try:
        run = open_run(args.run)
        cols = read(run.dir)
        names = bodies(cols)
        name = args.body or (names[0] if len(names) == 1 else None)
        if name is None or name not in names:
            raise RunError(f"{run.dir / CSV}: " + (f"no group {args.body!r}" if args.body else "several groups")
                           + f" (it holds {', '.join(names) or 'none'}; pick one with --body)")
        after = args.after
        if after is None:
            after = 0.0
            for k, b in enumerate(run.config.get("bodies") or []):
                if name == f"bodies[{k}]":
                    after = float(b.get("release") or 0.0)
        t, y = cols["t"], cols[f"{name}.{args.axis}"]
        keep = (t >= after) & (t <= args.until) & np.isfinite(y)
        te, ye = extrema(t[keep], y[keep], args.noise)
        speed = cols.get(f"{name}.{VELOCITY[args.axis]}")
        first = int(np.flatnonzero(keep)[0]) if keep.any() else None
        if first is not None and speed is not None and speed[first] == 0.0 and len(te) \
                and te[0] > t[first]:  # released from rest: the window starts at an extremum
            te, ye = np.r_[t[first], te], np.r_[y[first], ye]
        if len(te) < 3:
            raise RunError(f"{run.dir / CSV}: {len(te)} extrema of {name}.{args.axis} in "
                           f"[{after}, {args.until}] s (a decay needs at least 3)")
    except RunError as err:
        return refuse(PROG, err)
    fit = decay(te, ye, args.equilibrium)
    print(f"{name}.{args.axis} from t = {after} s: {len(te)} extrema")
    print("  t [s]      value      from equilibrium")
    for tk, yk in zip(te, ye):
        print(f"  {tk:8.4f}  {yk:+.6f}  {yk - fit['equilibrium']:+.6f}")
    print(f"period        {fit['period']:.4f} s (half-periods {', '.join(f'{h:.3f}' for h in fit['half_periods'])})")
    print(f"log decrement {fit['delta']:.4f} per cycle (each: {', '.join(f'{d:.3f}' for d in fit['deltas'])})")
    print(f"equilibrium   {fit['equilibrium']:+.6f}" + (" (given)" if args.equilibrium is not None else
                                                          " (mean of the extrema's midpoints)"))
    png = run.dir / f"body_{name.replace('[', '').replace(']', '')}_{args.axis}.png"
    plot(t[keep], y[keep], te, ye, fit, name, args.axis, png)
    print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
