"""The run's physical and numerical constants, derived once from the case.

:class:`Params` is a frozen named tuple of floats, ints, bools and small arrays, so it is
one argument to a numba kernel (``prm.h``, ``prm.c0`` inside ``@njit`` code) and the one
source of truth in Python: nothing copies these values elsewhere.
"""

from __future__ import annotations

import math
from typing import NamedTuple

import numpy as np

from sphcore.errors import CaseError
from sphcore.physics.eos import tait_b
from sphcore.physics.kernels import KERNEL_IDS, SUPPORT, lattice_moment
from sphcore.physics.particles import FLUID


class Params(NamedTuple):
    """Constants of one run (SI units). Built by :func:`derive`; never changed in a run."""

    dim: int  # spatial dimension, 2 or 3
    dx: float  # initial particle spacing (m)
    h: float  # smoothing length (m)
    support: float  # kernel support radius SUPPORT * h (m)
    kernel_id: int  # sphcore.physics.kernels.KERNEL_IDS value
    sph: bool  # SPH forces and density evolve (false: free particles + plugins)
    rho0: float  # reference density (kg/m^3)
    c0: float  # reference sound speed (m/s); 0 without SPH
    gamma: float  # Tait exponent
    tait_b: float  # Tait constant B = c0^2 rho0 / gamma (Pa)
    p_background: float  # constant added to the Tait pressure (Pa)
    alpha: float  # Monaghan artificial viscosity, linear coefficient
    beta: float  # Monaghan artificial viscosity, quadratic coefficient
    nu: float  # kinematic viscosity of the laminar term (m^2/s); 0 off
    delta: float  # density diffusion coefficient; 0 off
    diffusion_hydrostatic: bool  # density diffusion acts on the departure from hydrostatics (Fourtakas 2019)
    eta2: float  # 0.01 h^2, keeps the viscous denominators finite (m^2)
    gravity: np.ndarray  # (3,) body acceleration, zero-padded in 2D (m/s^2)
    g_abs: float  # |gravity| (m/s^2)
    up: np.ndarray  # (dim,) unit vector against gravity; zeros without gravity
    modified_pressure: bool  # Batchelor's modified pressure (EOS gives p - p_hydrostatic)
    rho_ref: float  # rho0 with modified pressure (buoyancy g (1 - rho0/rho)), else 0
    surface_level: float  # height of the highest block top along `up` (m): the hydrostatic reference
    kernel_gradient: bool  # Bonet & Lok corrected kernel gradient
    moment_norm: float  # lattice normalisation of the SPH first moment (sphcore.physics.kernels.lattice_moment)


def reference_sound_speed(case, state) -> float:
    """eos.c0, or c0_factor * sqrt(2 g H) with H the fluid's extent against gravity (m/s)."""
    c0 = case.config["eos"]["c0"]
    if c0 is not None:
        return c0
    g = np.linalg.norm(case.gravity)
    if g == 0:
        raise CaseError(case.file, "eos.c0", "required when gravity is zero (no height rule applies)")
    up = -case.gravity[: case.dim] / g
    z = state.pos[state.kind == FLUID] @ up
    height = (z.max() - z.min() + case.dx) if z.size else case.dx
    return case.config["eos"]["c0_factor"] * math.sqrt(2.0 * g * height)


def derive(case, state, surface_level: float = 0.0) -> Params:
    """Params of ``case`` with its initial particles ``state`` (the sound speed rule reads the
    fluid's height); ``surface_level`` is the hydrostatic reference height (m)."""
    cfg = case.config
    sph = cfg["physics"]["sph"]
    gravity = case.gravity
    g_abs = float(np.linalg.norm(gravity))
    up = -gravity[: case.dim] / g_abs if g_abs > 0 else np.zeros(case.dim)
    c0 = reference_sound_speed(case, state) if sph else 0.0
    gamma = cfg["eos"]["gamma"]
    rho0 = cfg["fluid"]["rho0"]
    modified = sph and cfg["physics"]["modified_pressure"]
    h = case.h
    return Params(
        dim=case.dim, dx=case.dx, h=h, support=SUPPORT * h, kernel_id=KERNEL_IDS[cfg["kernel"]["name"]],
        sph=sph, rho0=rho0, c0=c0, gamma=gamma, tait_b=tait_b(c0, rho0, gamma),
        p_background=cfg["eos"]["p_background"],
        alpha=cfg["viscosity"]["alpha"], beta=cfg["viscosity"]["beta"],
        nu=cfg["fluid"]["nu"] if sph else 0.0,
        delta=cfg["density_diffusion"]["delta"] if sph else 0.0,
        diffusion_hydrostatic=cfg["density_diffusion"]["hydrostatic"],
        eta2=0.01 * h * h, gravity=gravity, g_abs=g_abs, up=np.ascontiguousarray(up),
        modified_pressure=modified, rho_ref=rho0 if modified else 0.0, surface_level=float(surface_level),
        kernel_gradient=sph and cfg["corrections"]["kernel_gradient"],
        moment_norm=lattice_moment(KERNEL_IDS[cfg["kernel"]["name"]], h, case.dx, case.dim),
    )
