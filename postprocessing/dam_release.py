"""The first instants of a dam break: the incompressible initial acceleration of a released
column, and the clock of a record (experiment or run) measured against it.

    python postprocessing/dam_release.py [RUN_DIR] [--probe H4] [--fit-until 0.1]

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
An instantaneous release is the fastest one: where a door still stands it pushes on the
water (p >= 0, so q >= -(H - z) there), and the difference of the two q is harmonic, zero
on top, without normal derivative on floor and back wall and >= 0 on the face, hence
>= 0 everywhere (maximum principle) and its z-derivative at the surface <= 0: under a
door pulled up in a finite time the surface starts to fall more slowly, never faster,
than (1) says.

The clock. A record's depth h(t) at a probe in the reservoir is fitted, over
0 <= t <= ``--fit-until``, by h0 - a_z t'^2 / 2 with t' = t - tau for t > tau (h0 before),
a_z from (1) at the probe: tau is when that record's water started to move, on its own
clock (least squares over h0 and tau, tau on a 0.5 ms grid). Printed for the experiment
shipped with sphcore (SPHERIC test 2, Kleefsman et al. 2005, probe H4, 0.646 m from the
face) and for RUN_DIR/probes.csv when given.

A missing directory or file, or a probe the record lacks: one line on stderr, exit 2.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np

G = 9.81
# SPHERIC test 2 (the data file's header): water 0.55 m deep, 1.228 m long, its face at
# x = 1.992 m; depth probe H4 at x = 2.638 m.
DEPTH, LENGTH, FACE_X = 0.55, 1.228, 1.992
PROBES = {"H4": 2.638}


def surface_acceleration(x, depth=DEPTH, length=LENGTH, g=G, terms=20000):
    """Eq. (1): vertical acceleration (m/s^2, negative: down) of the free surface at
    distance ``x`` (m, scalar or array) from the released face, at t = 0+."""
    x = np.atleast_1d(np.asarray(x, dtype=float))
    n = np.arange(terms)
    k = (2 * n + 1) * np.pi / (2 * depth)
    # cosh(k (L - x)) / cosh(k L) without overflow
    ratio = np.exp(-np.outer(x, k)) * (1 + np.exp(-2 * np.outer(length - x, k))) / (1 + np.exp(-2 * k * length))
    out = -g * (ratio * ((-1.0) ** n * 2 / (depth * k))).sum(axis=1)
    return out if out.size > 1 else float(out[0])


def face_potential(z, depth=DEPTH, length=LENGTH, terms=20000):
    """q(0, z) of the series (the pressure's departure from hydrostatic over rho g, on the
    released face); the boundary condition is q(0, z) = -(H - z). For the tests."""
    z = np.atleast_1d(np.asarray(z, dtype=float))
    n = np.arange(terms)
    k = (2 * n + 1) * np.pi / (2 * depth)
    return (np.cos(np.outer(z, k)) * (-2 / (depth * k**2))).sum(axis=1)


def surface_drop(x, t, **kw):
    """Eq. (2) at leading order: how far (m, positive: down) the surface at ``x`` has
    dropped at time ``t`` after an instantaneous release."""
    return -0.5 * surface_acceleration(x, **kw) * np.asarray(t, dtype=float) ** 2


def fit_start(t, h, a_z, until, taus=None):
    """Least-squares fit of h(t), 0 <= t <= until, by h0 + a_z max(t - tau, 0)^2 / 2.
    Returns (tau, h0, rms): tau in s, h0 and the rms residual in m."""
    t, h = np.asarray(t, float), np.asarray(h, float)
    sel = (t >= 0) & (t <= until)
    t, h = t[sel], h[sel]
    if taus is None:
        taus = np.arange(-0.06, 0.06 + 1e-12, 0.0005)
    best = (np.inf, np.nan, np.nan)
    for tau in taus:
        shape = 0.5 * a_z * np.clip(t - tau, 0.0, None) ** 2
        h0 = float(np.mean(h - shape))
        rms = float(np.sqrt(np.mean((h - shape - h0) ** 2)))
        if rms < best[0]:
            best = (rms, float(tau), h0)
    return best[1], best[2], best[0]


def _report(name, t, h, x, until):
    a = surface_acceleration(x)
    tau, h0, rms = fit_start(t, h, a, until)
    drops = [h0 - float(np.interp(s, t, h)) for s in (0.05, 0.1, 0.15, 0.2)]
    print(f"  {name}: water starts to move at t = {1000 * tau:+.1f} ms on its clock (fit over 0-{until:g} s, "
          f"level {h0:.4f} m, rms {1000 * rms:.2f} mm); drop below that level at 0.05/0.1/0.15/0.2 s: "
          + " / ".join(f"{1000 * d:.1f}" for d in drops) + " mm")
    return tau


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run_dir", type=Path, nargs="?", help="a run of cases/dam_break_obstacle_3d (its probes.csv)")
    ap.add_argument("--probe", default="H4", choices=sorted(PROBES), help="the depth probe in the reservoir")
    ap.add_argument("--fit-until", type=float, default=0.1,
                    help="end of the fitted span (s); (2) holds while g t^2 / 2 << H (default 0.1 s: 0.09 H)")
    args = ap.parse_args(argv)
    run = None
    if args.run_dir is not None:
        path = args.run_dir / "probes.csv"
        if not path.is_file():
            print(f"dam_release: {path}: no such file (run cases/dam_break_obstacle_3d first)", file=sys.stderr)
            return 2
        sys.path.insert(0, str(Path(__file__).resolve().parent))
        from spheric_test2 import read_probes

        run = read_probes(path)
        if args.probe not in run:
            print(f"dam_release: {path}: no column {args.probe}", file=sys.stderr)
            return 2
    from sphcore_plugins.gauges.reference import kleefsman

    x = PROBES[args.probe] - FACE_X
    a = surface_acceleration(x)
    print(f"Instantaneous release, H = {DEPTH} m, L = {LENGTH} m: surface at {args.probe}, {x:.3f} m from the face, "
          f"starts at a_z = {a / G:.4f} g; drop a_z t^2 / 2 at 0.05/0.1/0.15/0.2 s: "
          + " / ".join(f"{1000 * surface_drop(x, s):.1f}" for s in (0.05, 0.1, 0.15, 0.2)) + " mm")
    exp = kleefsman()
    tau_exp = _report("experiment (Kleefsman et al. 2005)", exp["t"], exp[args.probe], x, args.fit_until)
    if run is not None:
        tau_run = _report(f"run {args.run_dir}", run["time"], run[args.probe], x, args.fit_until)
        print(f"  the run's water starts {1000 * (tau_run - tau_exp):+.1f} ms after the experiment's, each on its clock")
    return 0


if __name__ == "__main__":
    sys.exit(main())
