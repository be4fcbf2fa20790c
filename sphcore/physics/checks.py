"""Instability detection after a step: non-finite values, density out of bounds, particles
outside the walls. One pass (cheap next to the force kernel; parallel for large runs) that
returns the worst offender, so the message can name it."""

from __future__ import annotations

import math

import numpy as np
from numba import njit, prange

from sphcore.geometry.planes import plane_distance
from sphcore.jit.parallel import CHUNKS, by_size
from sphcore.physics.eos import energy_potential, tait_b

OK, NONFINITE, RHO_LOW, RHO_HIGH, OUTSIDE = 0, 1, 2, 3, 4
REASONS = {
    NONFINITE: "non-finite position, velocity or density",
    RHO_LOW: "density below the lower bound",
    RHO_HIGH: "density above the upper bound",
    OUTSIDE: "a particle left the domain (its centre crossed a wall plane)",
}


@by_size
def scan(pos, vel, rho, rho_lo, rho_hi, check_rho, normals, offsets):
    """(code, index, value) of the worst problem; code OK when there is none. The particles
    are scanned in CHUNKS ranges (in parallel from PARALLEL_MIN particles,
    :class:`sphcore.jit.parallel.by_size`), combined in order so that the answer is the serial
    scan's: the first non-finite particle, else the one farthest outside, else the lowest
    or highest density, the first of equals."""
    n = pos.shape[0]
    index = np.full((CHUNKS, 4), -1, np.int64)  # per chunk: non-finite, outside, low, high
    value = np.empty((CHUNKS, 4))
    for k in prange(CHUNKS):
        _scan_range(k * n // CHUNKS, (k + 1) * n // CHUNKS, pos, vel, rho, rho_lo, rho_hi, check_rho, normals,
                    offsets, index[k], value[k])
    worst = np.array([0.0, 0.0, rho_lo, rho_hi])
    found = np.full(4, -1, np.int64)
    for k in range(CHUNKS):
        if index[k, 0] >= 0:
            return NONFINITE, index[k, 0], value[k, 0]
        for c in range(1, 4):
            better = value[k, c] > worst[c] if c == 3 else value[k, c] < worst[c]
            if index[k, c] >= 0 and better:
                worst[c], found[c] = value[k, c], index[k, c]
    for c, code in ((1, OUTSIDE), (2, RHO_LOW), (3, RHO_HIGH)):
        if found[c] >= 0:
            return code, found[c], worst[c]
    return OK, -1, 0.0


@njit(cache=True)
def _scan_range(first, end, pos, vel, rho, rho_lo, rho_hi, check_rho, normals, offsets, index, value):
    """Scan particles first <= i < end into index / value (see :func:`scan`): the first
    non-finite one (and stop), the farthest outside a wall plane, the lowest density below
    rho_lo and the highest above rho_hi (-1: none)."""
    dim = pos.shape[1]
    worst_lo, worst_hi, worst_out = rho_lo, rho_hi, 0.0
    i_lo, i_hi, i_out = -1, -1, -1
    for i in range(first, end):
        s = rho[i]
        for d in range(dim):
            s += pos[i, d] + vel[i, d]
        if not math.isfinite(s):
            index[0] = i
            value[0] = s
            return
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
    index[1], index[2], index[3] = i_out, i_lo, i_hi
    value[1], value[2], value[3] = worst_out, worst_lo, worst_hi


@njit(cache=True)
def total_energy(pos, vel, rho, m, gravity, rho0, c0, gamma, with_internal):
    """Kinetic + potential + Tait internal energy (J, or J/m in 2D).

    The internal energy per unit mass is the Tait fluid's (:func:`sphcore.physics.eos.internal_energy`,
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
