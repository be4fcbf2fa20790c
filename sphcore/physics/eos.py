"""The Tait equation of state (Monaghan 1994; Batchelor 1967), in one place.

    p(rho) = B ((rho / rho0)^gamma - 1) + p_b,        B = c0^2 rho0 / gamma   (Pa)
    rho(p) = rho0 ((p - p_b) / B + 1)^(1/gamma)                               (kg/m^3)
    u(rho) = int p / rho^2 d rho  (relative to u(rho0)), the internal energy per unit mass
           = B (rho^(gamma-1) / (rho0^gamma (gamma-1)) + 1/rho) - (the same at rho0)   (J/kg)

The scalar functions are numba functions usable inside kernels; the array functions fill
preallocated outputs. Every module that needs the EOS calls these (the core, the ghost
plugin, the energy check, the wall model).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from sphcore.jit.parallel import by_size

#: the base (p - p_b)/B + 1 of the inverse is clamped here so a density stays positive
#: (>= 0.37 rho0 for gamma = 7) under strong tension
BASE_MIN = 1e-3


@njit(cache=True, inline="always")
def tait_b(c0, rho0, gamma):
    """B = c0^2 rho0 / gamma (Pa)."""
    return c0 * c0 * rho0 / gamma


@njit(cache=True, inline="always")
def tait_power(x, gamma):
    """x^gamma; for the usual gamma = 7 four multiplications instead of libm's pow (which
    costs ~8x more; the two differ by a few units in the last place)."""
    if gamma == 7.0:
        x2 = x * x
        return x2 * x2 * x2 * x
    return x ** gamma


@njit(cache=True, inline="always")
def pressure(rho, rho0, b, gamma, p_background):
    """p(rho) (Pa) for one density (kg/m^3); b from :func:`tait_b`."""
    return b * (tait_power(rho / rho0, gamma) - 1.0) + p_background


@njit(cache=True, inline="always")
def density(p, rho0, b, inv_gamma, p_background):
    """rho(p) (kg/m^3), the inverse of :func:`pressure`, base clamped at BASE_MIN."""
    return rho0 * max((p - p_background) / b + 1.0, BASE_MIN) ** inv_gamma


@njit(cache=True, inline="always")
def energy_potential(rho, rho0, b, gamma):
    """B (rho^(gamma-1) / (rho0^gamma (gamma-1)) + 1/rho) (J/kg): u(rho) up to a constant."""
    return b * (rho ** (gamma - 1.0) / (rho0 ** gamma * (gamma - 1.0)) + 1.0 / rho)


@njit(cache=True, inline="always")
def internal_energy(rho, rho0, b, gamma):
    """u(rho) - u(rho0) (J/kg), the work done compressing unit mass from rho0 to rho."""
    return energy_potential(rho, rho0, b, gamma) - energy_potential(rho0, rho0, b, gamma)


@by_size
def fill_pressure(rho, rho0, c0, gamma, p_background, p):
    """p[i] = p(rho[i]) for every particle (element-wise; parallel from PARALLEL_MIN
    particles, :class:`sphcore.jit.parallel.by_size`: the same bits either way)."""
    b = tait_b(c0, rho0, gamma)
    for i in prange(rho.shape[0]):
        p[i] = pressure(rho[i], rho0, b, gamma, p_background)


def hydrostatic_pressure(depth, rho0, c0, gamma, g):
    """Gauge pressure (Pa) at ``depth`` (m, array) below the free surface of a Tait fluid at rest.

    Hydrostatics dp/dd = rho(p) g with the Tait density rho = rho0 (1 + p/B)^(1/gamma),
    B = rho0 c0^2 / gamma, integrates in closed form (p = 0 at d = 0):

        p(d) = B [(1 + (1 - 1/gamma) rho0 g d / B)^(gamma / (gamma - 1)) - 1],

    and p = B (exp(rho0 g d / B) - 1) for gamma = 1. It exceeds the incompressible rho0 g d
    by the fraction g d / (2 c0^2) to first order (0.25 % at the bottom of a column with
    c0 = 10 sqrt(2 g H)). Evaluated with log1p / expm1, exact to round-off for small depths.
    """
    b = tait_b(c0, rho0, gamma)
    x = rho0 * g * np.asarray(depth, float) / b
    e = 1.0 - 1.0 / gamma
    if abs(e) < 1e-12:
        return b * np.expm1(x)
    with np.errstate(invalid="ignore", divide="ignore"):
        return b * np.expm1(np.log1p(e * x) / e)


def density_of(p, rho0, c0, gamma, p_background=0.0):
    """rho(p) (kg/m^3) of a numpy array of pressures (Pa), base clamped at BASE_MIN.

    numpy's vectorised power and libm's ``pow`` (used by numba) may differ in the last bit;
    set-up code keeps using this one so that results stay bit-for-bit what they were.
    """
    b = c0 * c0 * rho0 / gamma
    return rho0 * np.maximum((np.asarray(p, float) - p_background) / b + 1.0, BASE_MIN) ** (1.0 / gamma)
