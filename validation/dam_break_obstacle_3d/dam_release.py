"""The first instants of a dam break: the incompressible initial acceleration of a released
column, and the clock of a record (experiment or run) measured against it.

    python validation/dam_break_obstacle_3d/dam_release.py [RUN_DIR] [--probe H4] [--windows 0-0.1 0.04-0.12 ...]

The theory (the leading-order problem of Korobkin & Yilmaz, "The initial stage of
dam-break flow", J. Eng. Math. 63 (2009) 293-308; derived here for a reservoir of finite
length). A rectangular reservoir of depth H and length L, at rest, its face x = 0 removed
at t = 0 (x measured from the face into the water, z up from the floor). At t = 0+ every
velocity is zero, so the acceleration is a = g - grad(p) / rho with div(a) = 0: the
pressure is harmonic, p = 0 on the free surface z = H and on the released face, and the
walls stop the normal acceleration, dp/dz = -rho g on the floor and dp/dx = 0 on the back
wall x = L. Writing p = rho g (H - z) + rho g q, q is harmonic with dq/dz = 0 on the floor,
q = 0 on top, dq/dx = 0 at x = L and q = -(H - z) on the face; separation of variables
gives

    q = sum_n A_n cos(k_n z) cosh(k_n (L - x)) / cosh(k_n L),
    k_n = (2 n + 1) pi / (2 H),   A_n = -2 / (H k_n^2)

(A_n from int_0^H (H - z) cos(k_n z) dz = 1 / k_n^2). The free surface's vertical
acceleration a_z = -g dq/dz at z = H is

    a_z(x) = -g sum_n (-1)^n 2 / (H k_n) cosh(k_n (L - x)) / cosh(k_n L)      (1)

At the face's top corner (x = 0) the sum is (4 / pi) (1 - 1/3 + 1/5 - ...) = 1: the corner
falls freely; far from the face it decays like exp(-pi x / (2 H)). With the velocity zero
at t = 0 the surface at x drops as

    eta(t) = a_z(x) t^2 / 2 + O(t^4)                                          (2)

(the next term comes from the nonlinear and moving-boundary corrections, both O(t^2) in
the pressure). A weakly compressible fluid reaches (1) after a few acoustic transits L / c0.
At leading order (while the water is nearly at rest) an instantaneous release is the
fastest one: where a door still stands it pushes on the water (p >= 0, so q >= -(H - z)
there), and the difference of the two q is harmonic, zero on top, without normal
derivative on floor and back wall and >= 0 on the face, hence >= 0 everywhere (maximum
principle) and its z-derivative at the surface <= 0: under a door pulled up in a finite
time the surface starts to fall more slowly, never faster, than (1) says.

The clock. A record's depth h(t) at a probe in the reservoir is fitted, over a window
t0 <= t <= t1, by h0 + a_z t'^2 / 2 with t' = max(t - tau, 0), a_z from (1) at the probe:
tau is when the record's water started to move, on its own clock, if (2) held (least
squares over h0 and tau, tau on a 0.5 ms grid from -60 to +60 ms). (2) overestimates the
fall as t grows (the next order), so tau drifts with the window even for a record that
starts exactly at t = 0; a run and the experiment fitted on the same window share that
drift, and their difference is the experiment's lead on the run. Printed for the
experiment shipped with sphcore (SPHERIC test 2, Kleefsman et al. 2005, probe H4, 0.646 m
from the face) and for RUN_DIR/probes.csv when given, for each of ``--windows``.

A missing directory or file, or a probe the record lacks: one line on stderr, exit 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

from sphcore_plugins.gauges.reference import kleefsman

G = 9.81
# SPHERIC test 2 (the data file's header): water 0.55 m deep, 1.228 m long, its face at
# x = 1.992 m; depth probe H4 at x = 2.638 m.
DEPTH, LENGTH, FACE_X = 0.55, 1.228, 1.992
PROBES = {"H4": 2.638}


def surface_acceleration(x, depth=DEPTH, length=LENGTH, g=G, terms=20000):
    """Eq. (1): vertical acceleration (m/s^2, negative: down) of the free surface at
    distance ``x`` (m, scalar or array, 0 <= x <= length) from the released face, at t = 0+."""
    x = np.atleast_1d(np.asarray(x, dtype=float))
    if not np.all((x >= 0) & (x <= length)):
        raise ValueError(f"x must lie in the reservoir, 0 <= x <= {length} m")
    n = np.arange(terms)
    k = (2 * n + 1) * np.pi / (2 * depth)
    # cosh(k (L - x)) / cosh(k L) without overflow
    ratio = np.exp(-np.outer(x, k)) * (1 + np.exp(-2 * np.outer(length - x, k))) / (1 + np.exp(-2 * k * length))
    out = -g * (ratio * ((-1.0) ** n * 2 / (depth * k))).sum(axis=1)
    return out if out.size > 1 else float(out[0])


def face_q(z, depth=DEPTH, terms=20000):
    """q(0, z) of the series (the pressure's departure from hydrostatic over rho g, on the
    released face, where the cosh ratio is 1 whatever L); the boundary condition is
    q(0, z) = -(H - z). For the tests."""
    z = np.atleast_1d(np.asarray(z, dtype=float))
    n = np.arange(terms)
    k = (2 * n + 1) * np.pi / (2 * depth)
    return (np.cos(np.outer(z, k)) * (-2 / (depth * k**2))).sum(axis=1)


def surface_drop(x, t, **kw):
    """Eq. (2) at leading order: how far (m, positive: down) the surface at ``x`` has
    dropped at time ``t`` after an instantaneous release."""
    return -0.5 * surface_acceleration(x, **kw) * np.asarray(t, dtype=float) ** 2


TAUS = np.arange(-0.06, 0.06 + 1e-12, 0.0005)  # the start times tried (s)


def fit_start(t, h, a_z, t0, t1, taus=TAUS):
    """Least-squares fit of h(t), t0 <= t <= t1, by h0 + a_z max(t - tau, 0)^2 / 2.
    Returns (tau, h0, rms): tau in s, h0 and the rms residual in m. A window holding
    fewer than 3 finite samples, or a best tau on the edge of ``taus`` (the record is not
    this shape there), raises ValueError."""
    t, h = np.asarray(t, float), np.asarray(h, float)
    sel = (t >= t0) & (t <= t1) & np.isfinite(h)
    t, h = t[sel], h[sel]
    if t.size < 3:
        raise ValueError(f"fewer than 3 samples in [{t0:g}, {t1:g}] s")
    best = (np.inf, np.nan, np.nan)
    for tau in taus:
        shape = 0.5 * a_z * np.clip(t - tau, 0.0, None) ** 2
        h0 = float(np.mean(h - shape))
        rms = float(np.sqrt(np.mean((h - shape - h0) ** 2)))
        if rms < best[0]:
            best = (rms, float(tau), h0)
    if best[1] in (float(taus[0]), float(taus[-1])):
        raise ValueError(f"the best start, {1000 * best[1]:+.1f} ms, is the edge of the times tried")
    return best[1], best[2], best[0]


def read_depth(path: Path, probe: str):
    """(t in s, depth in m) of the depth probe ``probe`` in a probes plugin's probes.csv
    (columns time_s, then <name>_m or <name>_pa); ValueError naming the file otherwise."""
    try:
        data = np.genfromtxt(path, delimiter=",", names=True, ndmin=1)
    except (OSError, ValueError) as err:
        raise ValueError(f"{path}: cannot read: {err}") from None
    names = data.dtype.names or ()
    if "time_s" not in names or f"{probe}_m" not in names:
        raise ValueError(f"{path}: expected the columns time_s and {probe}_m (a depth probe named {probe})")
    return data["time_s"], data[f"{probe}_m"]


def _window(text):
    try:
        t0, t1 = (float(v) for v in text.split("-"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r}: expected T0-T1 in s, e.g. 0.04-0.12") from None
    if not 0 <= t0 < t1:
        raise argparse.ArgumentTypeError(f"{text!r}: expected 0 <= T0 < T1")
    return t0, t1


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run_dir", type=Path, nargs="?", help="a run of cases/dam_break_obstacle_3d (its probes.csv)")
    ap.add_argument("--probe", default="H4", choices=sorted(PROBES), help="the depth probe in the reservoir")
    ap.add_argument("--windows", type=_window, nargs="+",
                    default=[(0, 0.08), (0, 0.1), (0, 0.12), (0.02, 0.1), (0.04, 0.1), (0.04, 0.12), (0.05, 0.15)],
                    help="fitted spans T0-T1 (s); (2) holds while g t^2 / 2 << H (at 0.1 s: 0.09 H)")
    args = ap.parse_args(argv)
    run = None
    if args.run_dir is not None:
        path = args.run_dir / "probes.csv"
        if not path.is_file():
            print(f"dam_release: {path}: no such file (run cases/dam_break_obstacle_3d first)", file=sys.stderr)
            return 2
        try:
            run = read_depth(path, args.probe)
        except ValueError as err:
            print(f"dam_release: {err}", file=sys.stderr)
            return 2
    x = PROBES[args.probe] - FACE_X
    a = surface_acceleration(x)
    print(f"Instantaneous release, H = {DEPTH} m, L = {LENGTH} m: surface at {args.probe}, {x:.3f} m from the face, "
          f"starts at a_z = {a / G:.4f} g; drop a_z t^2 / 2 at 0.05/0.1/0.15/0.2 s: "
          + " / ".join(f"{1000 * surface_drop(x, s):.1f}" for s in (0.05, 0.1, 0.15, 0.2)) + " mm")
    exp = kleefsman()
    records = [("experiment", exp["t"], exp[args.probe])]
    if run is not None:
        records.append(("run", *run))
    print("window (s)   " + "   ".join(f"{name}: start (ms), level (m), rms (mm)" for name, _, _ in records)
          + ("   experiment's lead on the run (ms)" if run is not None else ""))
    for t0, t1 in args.windows:
        cells, taus = [], []
        for _, t, h in records:
            try:
                tau, h0, rms = fit_start(t, h, a, t0, t1)
            except ValueError as err:
                cells.append(f"({err})")
                taus.append(np.nan)
                continue
            cells.append(f"{1000 * tau:+6.1f} {h0:.4f} {1000 * rms:4.2f}")
            taus.append(tau)
        lead = f"   {1000 * (taus[1] - taus[0]):+6.1f}" if run is not None else ""
        print(f"{t0:5.3g}-{t1:<5.3g}  " + "   ".join(cells) + lead)
    return 0


if __name__ == "__main__":
    sys.exit(main())
