"""Instability detection after a step: non-finite values, density out of bounds, particles
outside the walls. One serial pass (cheap next to the force kernel) that returns the worst
offender, so the message can name it."""

from __future__ import annotations

import math

from numba import njit

from .eos import energy_potential, tait_b
from .geometry import plane_distance

OK, NONFINITE, RHO_LOW, RHO_HIGH, OUTSIDE = 0, 1, 2, 3, 4
REASONS = {
    NONFINITE: "non-finite position, velocity or density",
    RHO_LOW: "density below the lower bound",
    RHO_HIGH: "density above the upper bound",
    OUTSIDE: "a particle left the domain (its centre crossed a wall plane)",
}


@njit(cache=True)
def scan(pos, vel, rho, rho_lo, rho_hi, check_rho, normals, offsets):
    """(code, index, value) of the worst problem; code OK when there is none."""
    n, dim = pos.shape
    worst_lo, i_lo = rho_lo, -1
    worst_hi, i_hi = rho_hi, -1
    worst_out, i_out = 0.0, -1
    for i in range(n):
        s = rho[i]
        for d in range(dim):
            s += pos[i, d] + vel[i, d]
        if not math.isfinite(s):
            return NONFINITE, i, s
        if check_rho:
            if rho[i] < worst_lo:
                worst_lo, i_lo = rho[i], i
            if rho[i] > worst_hi:
                worst_hi, i_hi = rho[i], i
        x0, x1 = pos[i, 0], pos[i, 1]
        x2 = pos[i, 2] if dim == 3 else 0.0  # read once: a branch per plane costs 3x (measured)
        for k in range(normals.shape[0]):
            dist = plane_distance(normals, offsets, k, x0, x1, x2)
            if dist < worst_out:
                worst_out, i_out = dist, i
    if i_out >= 0:
        return OUTSIDE, i_out, worst_out
    if i_lo >= 0:
        return RHO_LOW, i_lo, worst_lo
    if i_hi >= 0:
        return RHO_HIGH, i_hi, worst_hi
    return OK, -1, 0.0


@njit(cache=True)
def total_energy(pos, vel, rho, m, gravity, rho0, c0, gamma, with_internal):
    """Kinetic + potential + Tait internal energy (J, or J/m in 2D).

    The internal energy per unit mass is the Tait fluid's (:func:`sphcore.eos.internal_energy`,
    with its reference value taken once).
    """
    n, dim = pos.shape
    b = tait_b(c0, rho0, gamma)
    u0 = energy_potential(rho0, rho0, b, gamma)  # once, not per particle
    e = 0.0
    for i in range(n):
        k = 0.0
        pe = 0.0
        for d in range(dim):
            k += vel[i, d] * vel[i, d]
            pe -= gravity[d] * pos[i, d]
        u = 0.0
        if with_internal:
            u = energy_potential(rho[i], rho0, b, gamma) - u0
        e += m[i] * (0.5 * k + pe + u)
    return e
