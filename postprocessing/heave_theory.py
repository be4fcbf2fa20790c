"""Linear potential-flow heave of a floating rectangle in two dimensions, in water of constant
depth: the added mass a33 and radiation damping b33 per unit length of a box of beam B and
draft T heaving in depth h, the body's self-consistent natural period, and the free decay it
shows when released from rest out of its equilibrium.

No run is read here: a free-decay run of a floating box (postprocessing/body_motion.py gives
its extrema, period and logarithmic decrement) is compared with these. Every function takes
SI units (m, s, kg/m^3, kg/m) and g = 9.81 m/s^2 unless given; coefficients are per unit
length of the body, a33 in kg/m, b33 in N s/m^2.

Method: matched eigenfunction expansions for a heaving cylinder in water of finite depth
(Yeung, R.W. 1981, "Added mass and damping of a vertical cylinder in finite-depth waters",
Applied Ocean Research 3(3), 119-133), here in its two-dimensional form: outside the body the
propagating mode and the evanescent modes of finite depth, under it a cosine series plus the
particular solution that carries the body's velocity; the potential and its horizontal
derivative are matched on the vertical through the body's side. The free decay follows from
the frequency response H(omega) = 1 / (rho g B - omega^2 (m + a33) - i omega b33) (Cummins,
W.E. 1962, "The impulse response function and ship motions", Schiffstechnik 9, 101-109).
Nondimensional damping as in Vugts, J.H. 1968, "The hydrodynamic coefficients for swaying,
heaving and rolling cylinders in a free surface", International Shipbuilding Progress 15,
251-276: b' = b33 / (rho B T) sqrt(B / (2g)).

Prints  the natural period, a33 and C33 = a33 / (rho B T), b33 and b', the logarithmic
        decrement of small damping, and the extrema of the free decay x(t)/x0 (t in s) with
        the period and decrement they give, measured as postprocessing/body_motion.py
        measures a run's. These are what a run is compared with: a33 and b33 vary with the
        frequency, so the decay's period and decrement are not the undamped natural period
        and the small-damping decrement (for the box below they settle, after the first
        swings, at 0.676 s and 0.90 per cycle, against 0.697 s and 1.02).
A size that is not positive, or a draft not less than the depth: one line on stderr, exit
status 2.

    python postprocessing/heave_theory.py --beam 0.2 --draft 0.05 --depth 0.3 --mass 10
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

PROG = Path(__file__).name
G = 9.81
RHO = 1000.0
MODES = 80  # cosine terms under the body; the evanescent modes outside are modes * h / (h - T)


def check(beam, draft, depth, mass=None, rho=RHO, g=G, modes=MODES):
    """Raise ValueError naming the first argument outside the problem's range."""
    sizes = {"beam": beam, "draft": draft, "depth": depth, "mass": mass, "rho": rho, "g": g}
    for name, value in sizes.items():
        if value is not None and not (math.isfinite(value) and value > 0):
            raise ValueError(f"{name} = {value}: expected a positive number")
    if draft >= depth:
        raise ValueError(f"draft = {draft} m is not less than depth = {depth} m: the body must float clear of the floor")
    if int(modes) < 1:
        raise ValueError(f"modes = {modes}: expected at least 1")


def _lnsinh(x):
    """ln sinh x for x > 0, without overflow."""
    return x + np.log(-np.expm1(-2.0 * x)) - math.log(2.0)


def _lncosh(x):
    """ln cosh x, without overflow."""
    return x + np.log1p(np.exp(-2.0 * x)) - math.log(2.0)


def wavenumbers(omega, depth, n, g=G):
    """(k0, kn) in 1/m: the propagating wavenumber, k0 tanh(k0 h) = omega^2 / g, and the n
    evanescent ones, kn tan(kn h) = -omega^2 / g with kn h in ((n - 1/2) pi, n pi).

    Both by bisection to round-off, 100 halvings: k0 h on [0, y + 1], y = omega^2 h / g
    (x tanh x - y changes sign there); kn through d = n pi - kn h on (0, pi/2), where
    (n pi - d) tan d = y increases with d (its derivative is ((n pi - d) - sin d cos d) / cos^2 d > 0)."""
    y = omega * omega * depth / g
    lo, hi = 0.0, y + 1.0
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if mid * math.tanh(mid) < y else (lo, mid)
    k0 = 0.5 * (lo + hi) / depth
    npi = math.pi * np.arange(1, n + 1)
    lo, hi = np.zeros(n), np.full(n, 0.5 * math.pi)
    for _ in range(100):
        mid = 0.5 * (lo + hi)
        below = (npi - mid) * np.tan(mid) < y
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return k0, (npi - 0.5 * (lo + hi)) / depth


def evanescent_modes(modes, draft, depth):
    """N = round(M h / (h - T)), at least 1: the evanescent modes outside the body that end at
    the wavenumber of the M cosine terms under it, N pi / h = M pi / (h - T)."""
    return max(1, round(int(modes) * depth / (depth - draft)))


def heave_coefficients(omega, beam, draft, depth, modes=MODES, rho=RHO, g=G) -> dict:
    """Added mass a33 (kg/m) and radiation damping b33 (N s/m^2) of a rectangle of beam B and
    draft T heaving at omega (rad/s) in depth h, per unit length; also b33 from the energy
    the waves carry away (``b33_energy``, a check) and the wavenumber k0 (1/m).

    s is the height above the floor, x the distance from the centre line, a = B/2, c = h - T
    (the gap under the body); the body heaves with velocity Re(e^{-i omega t}), the potential
    is Re(phi e^{-i omega t}). By symmetry only x > 0:
      outside (x > a, 0 < s < h):  phi = A0 Z0(s) e^{i k0 (x - a)} + sum_n An Zn(s) e^{-kn (x - a)},
        Z0 = cosh(k0 s) / N0, Zn = cos(kn s) / Nn, orthonormal on (0, h)
        (N0^2 = h/2 + sinh(2 k0 h) / (4 k0), Nn^2 = h/2 + sin(2 kn h) / (4 kn));
      under the body (x < a, 0 < s < c):  phi = (s^2 - x^2) / (2c) + B0 + sum_m Bm cos(lm s) cosh(lm x) / cosh(lm a),
        lm = m pi / c; the first term gives dphi/ds = 1 on the body's bottom and 0 on the floor.
    On x = a, dphi/dx is matched on (0, c) and zero on the body's side (c, h), projected on
    each Zj; phi is matched on (0, c), projected on each cos(lm s). With
    I_jm = int_0^c Zj cos(lm s) ds (in closed form), t_m = lm tanh(lm a), kappa = (i k0, -kn):
      kappa_j Aj = -(a/c) I_j0 + sum_m I_jm t_m Bm,      sum_j I_jm Aj = nu_m Bm + P_m,
      nu_0 = c, nu_m = c/2, P_0 = c^2/6 - a^2/2, P_m = (-1)^m / lm^2;
    eliminating Aj leaves M + 1 equations for Bm. The pressure p = i omega rho phi on the bottom
    gives the force i omega rho F = i omega a33 - b33 with
      F = int_{-a}^{a} phi(x, c) dx = 2 [(c^2 a - a^3/3) / (2c) + B0 a + sum_m Bm (-1)^m tanh(lm a) / lm],
      a33 = rho Re F,  b33 = rho omega Im F.
    The waves going out on both sides, amplitude eta = omega |A0| Z0(h) / g, carry the power
    rho g eta^2 cg = b33 / 2, cg = omega / (2 k0) (1 + 2 k0 h / sinh 2 k0 h): b33_energy. The
    two agree at any truncation (the truncated solution satisfies Green's identity exactly),
    so their agreement checks the algebra, not the convergence.

    ``modes`` = M cosine terms under the body and N = round(M h / c) evanescent modes, so that
    both series end at the same wavenumber, M pi / c = N pi / h; the corner of the body makes
    the error fall as 1/M^2 (for the box B = 0.2 m, T = 0.05 m, h = 0.3 m at its natural
    frequency, a33 and b33 within 9e-5 and 1.5e-4 of their limits at M = 40, 2e-5 and 4e-5 at 80)."""
    check(beam, draft, depth, rho=rho, g=g, modes=modes)
    a, c, h = 0.5 * beam, depth - draft, depth
    n_cos = int(modes) + 1
    n_ev = evanescent_modes(modes, draft, depth)
    k0, kn = wavenumbers(omega, h, n_ev, g)
    lam = math.pi * np.arange(n_cos) / c
    sign = (-1.0) ** np.arange(n_cos)
    ln_n0 = 0.5 * np.logaddexp(math.log(0.5 * h), _lnsinh(2.0 * k0 * h) - math.log(4.0 * k0))
    d = math.pi * np.arange(1, n_ev + 1) - kn * h  # sin 2kn h = -sin 2d, without cancellation
    nn = np.sqrt(0.5 * h - np.sin(2.0 * d) / (4.0 * kn))
    # I_jm: int_0^c cosh(k0 s) cos(lm s) ds = (-1)^m k0 sinh(k0 c) / (k0^2 + lm^2) and
    # int_0^c cos(kn s) cos(lm s) ds = kn sin((kn - lm) c) / ((kn - lm)(kn + lm)), (-1)^m sin(kn c) = sin((kn - lm) c)
    i0 = sign * k0 * math.exp(_lnsinh(k0 * c) - ln_n0) / (k0 * k0 + lam * lam)
    kk, ll = kn[:, None], lam[None, :]
    iev = kk * c * np.sinc((kk - ll) * c / math.pi) / (kk + ll) / nn[:, None]
    t = lam * np.tanh(lam * a)
    nu = np.full(n_cos, 0.5 * c)
    nu[0] = c
    p = np.zeros(n_cos)
    p[0] = c * c / 6.0 - a * a / 2.0
    p[1:] = sign[1:] / lam[1:] ** 2
    # sum_j I_jm I_jk / kappa_j: the propagating mode's term is imaginary, the evanescent ones' real
    gram = np.outer(i0, i0) / (1j * k0) - iev.T @ (iev / kn[:, None])
    gq = i0 * i0[0] / (1j * k0) - iev.T @ (iev[:, 0] / kn)
    bm = np.linalg.solve(gram * t[None, :] - np.diag(nu), p + (a / c) * gq)
    a0 = (-(a / c) * i0[0] + i0 @ (t * bm)) / (1j * k0)
    tail = sign[1:] * np.tanh(lam[1:] * a) / lam[1:]
    f = 2.0 * ((c * c * a - a ** 3 / 3.0) / (2.0 * c) + bm[0] * a + np.sum(bm[1:] * tail))
    eta = omega / g * abs(a0) * math.exp(_lncosh(k0 * h) - ln_n0)
    cg = 0.5 * omega / k0 * (1.0 + math.exp(math.log(2.0 * k0 * h) - _lnsinh(2.0 * k0 * h)))
    return {"a33": float(rho * f.real), "b33": float(rho * omega * f.imag),
            "b33_energy": float(2.0 * rho * g * eta * eta * cg), "k0": k0}


def coefficient_table(omegas, beam, draft, depth, modes=MODES, rho=RHO, g=G):
    """(a33, b33) arrays at each of ``omegas`` (rad/s, > 0)."""
    rows = [heave_coefficients(float(w), beam, draft, depth, modes, rho, g) for w in omegas]
    return np.array([r["a33"] for r in rows]), np.array([r["b33"] for r in rows])


def natural_period(mass, beam, draft, depth, rho=RHO, g=G, modes=MODES) -> dict:
    """The undamped natural period of heave with the added mass at its own frequency:
    omega^2 (m + a33(omega)) = rho g B, T = 2 pi / omega, solved by bisection on omega (the
    left side grows from 0 past rho g B; the bracket starts at sqrt(rho g B / m) and is widened
    if a33 < 0 there). Returns period (s), omega (rad/s), a33, b33, C33 = a33 / (rho B T),
    b' = b33 / (rho B T) sqrt(B / (2g)), zeta = b33 / (2 sqrt((m + a33) rho g B)) and the
    logarithmic decrement of small damping, delta = 2 pi zeta = pi b33 / sqrt((m + a33) rho g B)."""
    check(beam, draft, depth, mass, rho, g, modes)
    stiffness = rho * g * beam

    def excess(w):
        return w * w * (mass + heave_coefficients(w, beam, draft, depth, modes, rho, g)["a33"]) - stiffness

    lo, hi = 0.0, math.sqrt(stiffness / mass)
    while excess(hi) < 0.0:
        lo, hi = hi, 2.0 * hi
    while hi - lo > 1e-12 * hi:
        mid = 0.5 * (lo + hi)
        lo, hi = (mid, hi) if excess(mid) < 0.0 else (lo, mid)
    omega = 0.5 * (lo + hi)
    r = heave_coefficients(omega, beam, draft, depth, modes, rho, g)
    a33, b33, area = r["a33"], r["b33"], rho * beam * draft
    zeta = b33 / (2.0 * math.sqrt((mass + a33) * stiffness))
    return {"period": 2.0 * math.pi / omega, "omega": omega, "a33": a33, "b33": b33, "C33": a33 / area,
            "b_vugts": b33 / area * math.sqrt(beam / (2.0 * g)), "zeta": zeta, "delta": 2.0 * math.pi * zeta}


def cubic(x, xp, fp):
    """fp(xp) interpolated at x by piecewise cubic Hermite polynomials whose slopes are the
    second-order differences of fp (np.gradient); xp increasing, x clamped to [xp[0], xp[-1]]."""
    x = np.clip(np.asarray(x, float), xp[0], xp[-1])
    slope = np.gradient(fp, xp, edge_order=2)
    k = np.clip(np.searchsorted(xp, x, side="right") - 1, 0, len(xp) - 2)
    h = xp[k + 1] - xp[k]
    s = (x - xp[k]) / h
    h00, h10, h01, h11 = (1 + 2 * s) * (1 - s) ** 2, s * (1 - s) ** 2, s * s * (3 - 2 * s), s * s * (s - 1)
    return h00 * fp[k] + h10 * h * slope[k] + h01 * fp[k + 1] + h11 * h * slope[k + 1]


def extrema(t, x):
    """(times, values) of the local extrema of x(t): where its slope changes sign, refined by
    the vertex of the parabola through the sample and its two neighbours."""
    t, x = np.asarray(t, float), np.asarray(x, float)
    dx = np.diff(x)
    k = np.flatnonzero(dx[:-1] * dx[1:] < 0.0) + 1
    t0, t1, t2, x0, x1, x2 = t[k - 1], t[k], t[k + 1], x[k - 1], x[k], x[k + 1]
    f01, f12 = (x1 - x0) / (t1 - t0), (x2 - x1) / (t2 - t1)
    f012 = (f12 - f01) / (t2 - t0)  # x ~ x0 + f01 (t - t0) + f012 (t - t0)(t - t1)
    tv = 0.5 * (t0 + t1) - 0.5 * f01 / f012
    return tv, x0 + f01 * (tv - t0) + f012 * (tv - t0) * (tv - t1)


def free_decay(mass, beam, draft, depth, t, rho=RHO, g=G, modes=MODES, omega_max=None, n_omega=241,
               d_omega=None) -> dict:
    """x(t)/x0 of the linear free heave decay of the body released from rest at x0 (t >= 0, s),
    with its extrema after the release.

    Held at x0 by a force rho g B x0 that is removed at t = 0, the body moves as
      x(t) / x0 = (2 rho g B / pi) int_0^inf Im H(omega) / omega cos(omega t) d omega,
      Im H / omega = b33 / ((rho g B - omega^2 (m + a33))^2 + omega^2 b33^2),
    H being causal (its step response subtracted from the static one; x(0) = 1 is the
    Kramers-Kronig relation between a33 and b33, a check of both). a33 and b33 are computed at
    ``n_omega`` frequencies equally spaced on [0, omega_max] (the one at 0 taken at a thousandth
    of the step, where they have reached their long-wave limits), interpolated by :func:`cubic`
    onto a grid of step ``d_omega`` and integrated by the trapezoid rule. omega_max defaults to
    sqrt(max(20 g / T, 25 rho g B / m)): b33 falls as e^{-2 k T}, k = omega^2 / g, e^{-40} there,
    and it is 5 times the natural frequency of the body without added mass. d_omega defaults to
    min(omega_max / 4000, 0.2 / t_end): 30 steps or more per period of cos(omega t).

    Returns t, x, the extrema (``t_extrema``, ``x_extrema``), the half-cycle decrements
    2 ln(|x_k| / |x_k+1|) of successive extrema (``deltas``), and the frequency table (``omega``,
    ``a33``, ``b33``)."""
    check(beam, draft, depth, mass, rho, g, modes)
    t = np.asarray(t, float)
    stiffness = rho * g * beam
    if omega_max is None:
        omega_max = math.sqrt(max(20.0 * g / draft, 25.0 * stiffness / mass))
    omegas = np.linspace(0.0, omega_max, n_omega)
    a33, b33 = coefficient_table(np.maximum(omegas, 1e-3 * omegas[1]), beam, draft, depth, modes, rho, g)
    t_end = float(np.max(np.abs(t))) if t.size else 1.0
    if d_omega is None:
        d_omega = min(omega_max / 4000.0, 0.2 / max(t_end, 1e-12))
    w = np.linspace(0.0, omega_max, math.ceil(omega_max / d_omega) + 1)
    a, b = cubic(w, omegas, a33), cubic(w, omegas, b33)
    f = b / ((stiffness - w * w * (mass + a)) ** 2 + (w * b) ** 2)
    weight = np.full(w.size, w[1] - w[0])
    weight[[0, -1]] *= 0.5
    fw = (2.0 * stiffness / math.pi) * f * weight
    x = np.empty(t.size)
    block = max(1, 2_000_000 // w.size)
    for i in range(0, t.size, block):
        x[i:i + block] = np.cos(np.outer(t[i:i + block], w)) @ fw
    te, xe = extrema(t, x)
    deltas = 2.0 * np.log(np.abs(xe[:-1]) / np.abs(xe[1:]))
    return {"t": t, "x": x, "t_extrema": te, "x_extrema": xe, "deltas": deltas, "omega": omegas, "a33": a33,
            "b33": b33}


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__.split("\n")[0])
    ap.add_argument("--beam", type=float, required=True, help="B, the body's width (m)")
    ap.add_argument("--draft", type=float, required=True, help="T, the depth of its bottom below the still water (m)")
    ap.add_argument("--depth", type=float, required=True, help="h, the water's depth (m)")
    ap.add_argument("--mass", type=float, help="m per unit length (kg/m; default rho B T, floating free)")
    ap.add_argument("--rho", type=float, default=RHO, help=f"water density (kg/m^3, default {RHO:g})")
    ap.add_argument("--g", type=float, default=G, help=f"gravity (m/s^2, default {G})")
    ap.add_argument("--modes", type=int, default=MODES, help=f"cosine terms under the body (default {MODES})")
    ap.add_argument("--periods", type=float, default=3.25,
                    help="length of the free decay, in natural periods (default 3.25)")
    args = ap.parse_args(argv)
    try:
        check(args.beam, args.draft, args.depth, args.mass, args.rho, args.g, args.modes)
        if not (math.isfinite(args.periods) and args.periods > 0):
            raise ValueError(f"periods = {args.periods}: expected a positive number")
    except ValueError as err:
        print(f"{PROG}: error: {err}", file=sys.stderr)
        return 2
    beam, draft, depth, rho, g = args.beam, args.draft, args.depth, args.rho, args.g
    mass = rho * beam * draft if args.mass is None else args.mass
    nat = natural_period(mass, beam, draft, depth, rho, g, args.modes)
    t = np.linspace(0.0, args.periods * nat["period"], round(1000 * args.periods) + 1)
    dec = free_decay(mass, beam, draft, depth, t, rho, g, args.modes)
    n_ev = evanescent_modes(args.modes, draft, depth)
    print(f"2D rectangle heaving: B = {beam:g} m, T = {draft:g} m, h = {depth:g} m, m = {mass:g} kg/m "
          f"(rho B T = {rho * beam * draft:g}), rho = {rho:g}, g = {g:g}; {args.modes} + {n_ev} modes")
    print(f"natural period  {nat['period']:.4f} s (omega = {nat['omega']:.4f} rad/s, "
          f"omega^2 B/(2g) = {nat['omega'] ** 2 * beam / (2 * g):.4f}; undamped, a33 at its own frequency)")
    print(f"added mass      a33 = {nat['a33']:.4f} kg/m, C33 = a33/(rho B T) = {nat['C33']:.4f}")
    print(f"damping         b33 = {nat['b33']:.4f} N s/m^2, b' = b33/(rho B T) sqrt(B/(2g)) = {nat['b_vugts']:.4f}")
    print(f"log decrement   pi b33 / sqrt((m + a33) rho g B) = {nat['delta']:.4f} per cycle (zeta = {nat['zeta']:.4f})")
    print("free decay from rest at x0: extrema of x/x0 (delta: 2 ln of successive |x/x0|)")
    print("  t [s]     x/x0      delta")
    te, xe = np.r_[0.0, dec["t_extrema"]], np.r_[1.0, dec["x_extrema"]]
    deltas = 2.0 * np.log(np.abs(xe[:-1]) / np.abs(xe[1:]))
    for tk, xk, dk in zip(te[1:], xe[1:], deltas):
        print(f"  {tk:7.4f}  {xk:+.4f}   {dk:.3f}")
    print("period and log decrement as body_motion.py measures them (twice the mean interval, the mean delta):")
    for first, label in ((0, "from the release"), (1, "from the first extremum")):
        if len(te) - first > 1:
            print(f"  {label:24s} {2.0 * np.mean(np.diff(te[first:])):.4f} s, {np.mean(deltas[first:]):.4f} per cycle")
    return 0


if __name__ == "__main__":
    sys.exit(main())
