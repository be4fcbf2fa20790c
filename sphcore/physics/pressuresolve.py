"""The iterations of the divergence-free scheme's two solves (:mod:`sphcore.physics.incompressible`).

Each solve finds kappa such that the density predicted from the velocities after the
pressure kick meets its target: rho_i + dt D rho_i = rho0 (the density solve) or
D rho_i = 0 (the divergence solve). One iteration is two passes over the pairs
(:mod:`sphcore.physics.solvepairs`): the density rate of the current velocities, then the
pressure kick of kappa's change.

The iteration is projected Jacobi accelerated by Chebyshev polynomials (Saad 2003,
Algorithm 12.1) on an interval of the diagonal-scaled operator's spectrum; kappa may rise
and fall, never below zero, and the error counts compression and expansion alike (a
particle at zero pressure that expands is at the free surface and counts none), or
compression only (``[scheme] error = "compression"``). Plain
Jacobi diverges here, since that operator's largest eigenvalue exceeds 2 on the lattice
(:func:`sphcore.physics.solvepairs.lattice_eigenvalue`), and weighted Jacobi damps the long
waves too slowly to converge. Bender & Koschier's one-sided Jacobi (only a compressed
particle raises its kappa, only compression counts, as SPlisHSPlasH runs it) took as many
iterations on the 3D dam break at h = dx (11.7 a step) and was unstable there by 0.22 s; on
the 2D seed dam break its front missed Martin & Moyce by 30 % RMS (the expansion it leaves
is never corrected).

A warm-started density solve needs its error cut about fourfold, and the recursion on this
interval cuts its slowest mode by T_k(theta / delta) after k iterations (4.3 at k = 7): the
3D dam break's 7.6 iterations a step are that bound. Fewer need a method that resolves the
long waves below the interval. Conjugate gradients would, but kappa >= 0 must hold inside
the iteration: on the particles free at a solve's start, clamping the tension CG left
afterwards made the 3D dam break unstable within ten steps; a bound-constrained CG (MPRGP,
Dostal & Schoberl 2005, the Jacobi weights as preconditioner) took 28 iterations a step on
the still tank where this one takes 49, but 20 where it takes 7.6 on the 3D dam break, whose
many particles near zero pressure at the free surface cut nearly every conjugate step short.
"""

from __future__ import annotations

import numpy as np

from sphcore.errors import Instability
from sphcore.physics import solvepairs as sp

# the interval [low, high] lambda_max the Chebyshev acceleration is built for: above the
# lattice's largest eigenvalue with room for particles off the lattice, and low enough for
# the long waves a warm-started solve leaves. Density iterations a step over whole runs
# (low 0.01 / 0.03 / 0.05 / 0.1): the 3D dam break at h = dx 10.1 / 6.4 / 5.6 / 5.0, with
# 387 / 390 / 400 / 470 steps; the 2D seed dam break 6.4 / 4.4 (0.01 / 0.03), the fronts
# within 0.5 % of each other (measured before the walls' rate was made the kick's adjoint;
# with it, 7.4 and 8.2 at 0.03, in 345 and 588 steps). The first steps from the hydrostatic
# start need the long waves: a solve not converged in CHEBYSHEV_CYCLE iterations widens the interval.
CHEBYSHEV_LOW = 0.03
CHEBYSHEV_HIGH = 1.3
# a solve not converged after this many iterations restarts the recursion with the
# interval's low end a quarter as high: what is left are waves longer than it was built for
CHEBYSHEV_CYCLE = 40
CHEBYSHEV_FLOOR = 0.0025  # at most two widenings: wider, the walls' modes grew (the still tank at h = 2 dx)


def chebyshev_interval(lam: float) -> tuple[float, float]:
    """The Chebyshev interval for an operator whose lattice eigenvalue is at most ``lam``."""
    return CHEBYSHEV_LOW * lam, CHEBYSHEV_HIGH * lam


def solve(scheme, kappa, base, dt, tol, min_it, what, alpha):
    """Iterate one solve of ``scheme`` (a :class:`sphcore.physics.incompressible.DivergenceFree`,
    whose pair list, wall terms and scratch arrays it uses) from the warm start ``kappa``
    (updated in place): the velocities take the pressure of the warm start, then of each
    change, until the mean error (of rho0) is below ``tol`` after at least ``min_it``
    iterations. ``base``: rho (density solve) or rho0 (divergence solve); ``alpha``: the
    Jacobi weights, 0 for a particle the solve leaves alone. Returns (iterations, mean
    error); a solve not converged in ``scheme.max_iterations`` raises Instability."""
    st, rho0 = scheme.run.particles, scheme.ctx.params.rho0
    rows = (scheme.pairs.start, scheme.pairs.end, scheme.pairs.nb, scheme.pairs.g)
    m = scheme.masses()
    kr = scheme.kick_ratio  # kappa / rho of the kick, per particle (one division each, not one per pair)
    np.divide(kappa, st.rho, out=kr)
    sp.run_pass(sp.pressure_kick, st.vel, *rows, m, kr, scheme.grad, rho0, dt)
    scale = 1.0 / (dt * dt)
    lmin, lmax = scheme.spectrum
    cycle = 0  # iterations since the recursion (re)started
    n = max(st.n, 1)
    d, z, err_i = scheme.step_d, scheme.dkappa, scheme.err
    it = 0
    while True:
        sp.run_pass(sp.density_rate, scheme.rate, *rows, m, st.vel, scheme.grad, scheme.flux, rho0, scheme.inv_sigma)
        sp.particle_pass(sp.residual, z, err_i, base, scheme.rate, dt, rho0, kappa, alpha, scale,
                         scheme.compression_only)
        err = float(err_i.sum()) / (n * rho0)
        if it >= min_it and err <= tol:
            return it, err
        if it >= scheme.max_iterations:
            worst = int(np.argmax(err_i))
            hint = "raise scheme.max_iterations or lower scheme.cfl"
            if not scheme.forces.wants_walls:
                hint = "the walls carry no pressure: add wall_integral to plugins.use"
            raise Instability(scheme.ctx.step, scheme.ctx.t, int(st.id[worst]),
                              f"the {what} solve did not converge in {scheme.max_iterations} iterations: mean error "
                              f"{err:.3g} of rho0 against scheme.{what}_tolerance = {tol:g} ({hint})")
        if cycle == CHEBYSHEV_CYCLE:  # the long waves left: restart on a wider interval
            lmin = max(0.25 * lmin, CHEBYSHEV_FLOOR * lmax / CHEBYSHEV_HIGH)
            cycle = 0
        if cycle == 0:
            theta, delta = 0.5 * (lmax + lmin), 0.5 * (lmax - lmin)
            sigma = theta / delta
            rk = 1.0 / sigma
            c_old, c_new = 0.0, 1.0 / theta
        else:
            rn = 1.0 / (2.0 * sigma - rk)
            c_old, c_new = rn * rk, 2.0 * rn / delta
            rk = rn
        cycle += 1
        sp.particle_pass(sp.projected_step, d, z, kappa, c_old, c_new, st.rho, kr)
        sp.run_pass(sp.pressure_kick, st.vel, *rows, m, kr, scheme.grad, rho0, dt)
        it += 1
