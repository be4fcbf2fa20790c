"""Linear theory of a wave maker in water of constant depth: the dispersion relation, the
transfer functions of a piston and of a flap hinged at the floor, the group velocity and the
piston's first-harmonic force (Havelock's, with the standing evanescent modes).

No run is read here: postprocessing/wave_flume.py measures a run of a flume against these,
and validation/pages/wave_flume.py tabulates them. Every function takes SI units (m, s,
kg/m^3) and g = 9.81 m/s^2 unless given.

    H/S (piston) = 2 (cosh 2kh - 1) / (sinh 2kh + 2kh)                       (Biesel & Suquet 1951)
    H/S (flap)   = 4 (sinh kh / kh) (kh sinh kh - cosh kh + 1) / (sinh 2kh + 2kh)
                                  (both: Dean & Dalrymple, Water Wave Mechanics for Engineers
                                   and Scientists, ch. 6)
"""

from __future__ import annotations

import math

import numpy as np


def wavenumber(omega, h, g=9.81):
    """k (1/m) solving omega^2 = g k tanh(k h), by bisection on kh in [0, omega^2 h / g + 1]
    (x tanh x - y changes sign there); omega may be an array."""
    y = np.asarray(omega, float) ** 2 * h / g
    lo, hi = np.zeros_like(y), y + 1.0
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        below = mid * np.tanh(mid) < y
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return 0.5 * (lo + hi) / h


def biesel(kh):
    """Biesel's piston transfer function H/S = 2 (cosh 2kh - 1) / (sinh 2kh + 2kh)."""
    x = 2.0 * np.asarray(kh, float)
    return 2.0 * (np.cosh(x) - 1.0) / (np.sinh(x) + x)


def flap(kh):
    """The transfer function of a flap hinged at the floor, H/S = 4 (sinh kh / kh)
    (kh sinh kh - cosh kh + 1) / (sinh 2kh + 2kh), S the stroke at the still-water level
    (Dean & Dalrymple, ch. 6; -> kh/2 in shallow water, -> 2 in deep)."""
    x = np.asarray(kh, float)
    return 4.0 * (np.sinh(x) / x) * (x * np.sinh(x) - np.cosh(x) + 1.0) / (np.sinh(2.0 * x) + 2.0 * x)


def group_velocity(k, h, g=9.81):
    """cg = c/2 (1 + 2kh / sinh 2kh), c = omega / k (m/s)."""
    kh = k * h
    c = math.sqrt(g * math.tanh(kh) / k)
    return 0.5 * c * (1.0 + 2.0 * kh / math.sinh(2.0 * kh))


def evanescent_wavenumbers(omega, h, n, g=9.81):
    """k_1 .. k_n (1/m) solving omega^2 = -g k tan(k h), k_j h in ((j - 1/2) pi, j pi): by
    bisection on d = j pi - k_j h in (0, pi/2), where (j pi - d) tan d = omega^2 h / g."""
    y, jpi = omega * omega * h / g, math.pi * np.arange(1, n + 1)
    lo, hi = np.zeros(n), np.full(n, 0.5 * math.pi)
    for _ in range(80):
        mid = 0.5 * (lo + hi)
        below = (jpi - mid) * np.tan(mid) < y
        lo, hi = np.where(below, mid, lo), np.where(below, hi, mid)
    return (jpi - 0.5 * (lo + hi)) / h


def havelock(omega, h, S, g=9.81, rho=1000.0, n=100) -> dict:
    """The first-harmonic horizontal force per unit width of linear theory on a piston of stroke
    S, X(t) = S/2 sin(omega t), in water of depth h (Havelock 1929, Phil. Mag. 8, 569; Dean &
    Dalrymple, Water Wave Mechanics for Engineers and Scientists, ch. 6, piston wave maker).

    With U0 = omega S / 2, the velocity U = U0 cos(omega t) = Re(U0 e^{i omega t}) and the
    piston's face at x = 0, z from -h (floor) to 0 (still water):
      phi = Re(Phi e^{i omega t}),  Phi = a0 cosh k(h+z) e^{-ikx} + sum_j aj cos kj(h+z) e^{-kj x}
      omega^2 = g k tanh kh (the wave going out), omega^2 = -g kj tan kj h (j = 1..n, standing).
    The modes are orthogonal on -h < z < 0; dPhi/dx = U0 at x = 0 projected on each gives
      a0 = i U0 P0 / (k N0),   aj = -U0 Pj / (kj Nj),
      P0 = sinh kh / k,   N0 = (sinh 2kh + 2kh) / (4k),   Pj = sin kj h / kj,   Nj = (sin 2kj h + 2kj h) / (4kj).
    (a0 gives H/S = 2 (omega/g) |a0| cosh kh / S = Biesel's.) The force the piston exerts on the water,
      F = int_{-h}^{0} p dz,  p = -rho dphi/dt  (linear dynamic pressure, at x = 0),
    is F = Re(-i omega rho (a0 P0 + sum aj Pj) e^{i omega t}) = B U + ma dU/dt with
      B  = rho omega P0^2 / (k N0) = rho omega (H/S) / k^2          (radiation damping, N s/m^2)
      ma = rho sum_j Pj^2 / (kj Nj)
         = rho h^2 sum_j 4 sin^2 kj h / ((kj h)^2 (sin 2kj h + 2kj h))  (added mass, kg/m):
    the wave going out is in phase with the velocity (a0 is imaginary): all the added mass is
    the standing modes'. Its terms fall as 1/j^5: the tail after n is about y^2 / (2 pi^5 n^4) rho h^2,
    y = omega^2 h / g (n = 100, kh = 1: 1e-11 rho h^2, a part in 1e9).
    F(t) = amplitude sin(omega t + phase) with amplitude cos(phase) = -ma omega^2 S/2 and
    amplitude sin(phase) = B omega S/2 (phase from 90 to 180 degrees); the mean power is B U0^2/2.

    First order throughout: p integrated to z = 0, not to the surface eta (the rest, int_0^eta p dz
    and the shift of the face by X, are O(S^2)); p = -rho g z - rho dphi/dt, whose hydrostatic
    part gives the constant rho g h^2 / 2 (not included) and whose dynamic part includes the
    first-order rise of the water at the face (rho g eta = -rho dphi/dt at z = 0). The water's
    force on the piston is -F, plus the constant. Limits: B -> rho h sqrt(gh) (kh -> 0),
    2 rho g^2 / omega^3 (deep); ma/(rho h^2) -> 2 zeta(5) (kh)^4 / pi^5 (kh -> 0),
    14 zeta(3) / pi^3 = 0.5428 as kh -> infinity (Westergaard's rigid dam, incompressible)."""
    k = float(wavenumber(omega, h, g))
    kh = k * h
    kj = evanescent_wavenumbers(omega, h, n, g)
    d = math.pi * np.arange(1, n + 1) - kj * h  # sin^2 kj h = sin^2 d, sin 2kj h = -sin 2d: no cancellation
    ma = rho * h * h * float(np.sum(4.0 * np.sin(d) ** 2 / ((kj * h) ** 2 * (2.0 * kj * h - np.sin(2.0 * d)))))
    hs = 2.0 * math.tanh(kh) / (1.0 + 2.0 * kh / math.sinh(min(2.0 * kh, 700.0)))  # Biesel's H/S
    B = rho * omega * hs / (k * k)
    inertia, radiation = ma * omega * omega * 0.5 * S, B * omega * 0.5 * S
    return {"k": k, "kh": kh, "kj": kj, "added_mass": ma, "damping": B, "inertia": inertia,
            "radiation": radiation, "amplitude": math.hypot(inertia, radiation),
            "phase": math.atan2(radiation, -inertia), "power": 0.5 * B * (0.5 * omega * S) ** 2, "HS": hs}


def recorded_elevation(t, stroke, h, x, transfer=flap, g=9.81, n_fft=None):
    """The linear free-surface elevation (m) at distance x (m) down the flume from a wave
    maker whose stroke at the still-water level (m, positive towards the water) was
    recorded at the uniformly spaced times t: each Fourier component X e^{i omega t} of the
    stroke makes the progressive wave (H/S)(kh) X i e^{i (omega t - k x)}, as the regular
    wave of Dean & Dalrymple (ch. 6) does for X = S/2 sin(omega t): eta = H/2 cos(kx - omega t).
    The evanescent modes are left out (they are gone a depth or two from the maker). The
    record is zero-padded to n_fft samples (by default a power of two at least twice its
    length, so that slow components do not come round again within it); returns eta at t."""
    t = np.asarray(t, float)
    n = t.size
    dt = float(t[1] - t[0])
    if n_fft is None:
        n_fft = 1 << int(math.ceil(math.log2(2 * n)))
    c = np.fft.rfft(np.asarray(stroke, float), n_fft)
    omega = 2.0 * math.pi * np.fft.rfftfreq(n_fft, dt)
    k = np.zeros_like(omega)
    k[1:] = wavenumber(omega[1:], h, g)
    kh = np.minimum(k * h, 20.0)  # no overflow; waves shorter than h / 3 carry H/S of kh = 20 (flap: 1.9, not 2)
    ratio = np.zeros_like(kh)
    ratio[1:] = transfer(kh[1:])
    return np.fft.irfft(1j * ratio * c * np.exp(-1j * k * x), n_fft)[:n]
