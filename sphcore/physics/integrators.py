"""Time integrators. Each step: free motion (no walls), then the ``sph_after_integrate``
hook (where the reflective boundary corrects positions and velocities) and the equation of
state, then the rates at the new state (the simulation calls the stages in that order).

- ``euler``: explicit Euler as in the paper: x1 = x0 + dt v0, v1 = v0 + dt a0, rho1 = rho0 + dt drho0;
  first order; rates are evaluated at the start of each step.
- ``leapfrog`` (default): kick-drift-kick velocity Verlet, second order, one rate evaluation
  per step (Monaghan 2005, section 6; the density is kicked like the velocity). With the
  rates a_n, D_n at the start of the step:

      x_{n+1} = x_n + dt (v_n + dt/2 a_n)                     drift (free motion)
      v* = v_n + dt a_n,  rho* = rho_n + dt D_n              predicted end-of-step values
      [hook: walls correct x_{n+1}, v*]
      a_{n+1}, D_{n+1} = rates(x_{n+1}, v*, rho*)
      v_{n+1} = v* + dt/2 (a_{n+1} - a_n),  rho_{n+1} = rho* + dt/2 (D_{n+1} - D_n)

  which is the kick-drift-kick sequence written around the predicted state. For a
  constant acceleration it is exact, so a ball under gravity keeps its energy to round-off
  between wall contacts, and the rates at the end of a step are reused at the start of the next.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from sphcore.jit.parallel import by_size

# Element-wise updates, compiled serial and parallel (:class:`sphcore.jit.parallel.by_size`,
# parallel from PARALLEL_MIN particles): each particle's update is independent of the
# others', so both builds give the same bits. 2D still water at 10^5 particles, two
# threads (`benchmarks/speed/bench_pairs.py`): the step outside the timed stages, mostly these
# updates, 2.3-2.7 -> 1.06-1.09 ms of an 11-13 ms step.


@by_size
def _drift_kick(pos0, pos, vel, acc, rho, drho, dt, half_kick, evolve_density):
    """pos0 <- pos; pos += dt (vel + half_kick * dt/2 * acc); vel += dt * acc; and with
    ``evolve_density`` rho += dt * drho. One pass over the particles."""
    n, dim = pos.shape
    for i in prange(n):
        for d in range(dim):
            x = pos[i, d]
            v = vel[i, d]
            pos0[i, d] = x
            pos[i, d] = x + dt * (v + half_kick * 0.5 * dt * acc[i, d])
            vel[i, d] = v + dt * acc[i, d]
        if evolve_density:
            rho[i] += dt * drho[i]


@by_size
def _correct(vel, acc_new, acc_old, rho, drho_new, drho_old, half_dt, evolve_density):
    """vel += half_dt * (acc_new - acc_old); with ``evolve_density`` the same for rho."""
    n, dim = vel.shape
    for i in prange(n):
        for d in range(dim):
            vel[i, d] += half_dt * (acc_new[i, d] - acc_old[i, d])
        if evolve_density:
            rho[i] += half_dt * (drho_new[i] - drho_old[i])


class SchemeBase:
    """What both schemes share: the free-motion stage and the scratch arrays.

    A scheme is built with the run state (``run.particles`` and ``run.rates``, see
    :class:`sphcore.run.state.RunState`) and one rates function, ``rates_fn(acc, drho)``,
    which writes the rates of the current particles into the arrays it is given; it calls
    nothing else. A step is :meth:`free_motion` (the drift and the predicted kick), then the
    caller's wall correction and equation of state, then :meth:`finish` (the rates at the
    new state and, for the leapfrog, the corrector). :meth:`finish` returns whether the
    density changed again, so that the caller applies the equation of state once more.
    """

    name = ""
    half_kick = 0.0  # weight of dt/2 * a in the drift: 0 for Euler, 1 for the leapfrog

    def __init__(self, run, rates_fn, evolves_density: bool):
        self.run, self.rates_fn = run, rates_fn
        self.evolves_density = evolves_density
        self.pos0 = np.zeros((0, 0))  # allocated by resize()
        self._drho_spare = np.zeros(0)
        self.resize()

    # -- arrays -----------------------------------------------------------------------

    @property
    def acc(self) -> np.ndarray:
        """The accelerations of the run state (m/s^2), read only."""
        return self.run.rates.acc

    @property
    def drho(self) -> np.ndarray:
        """The density rates of the run state (kg/m^3/s), read only."""
        return self.run.rates.drho

    @property
    def fresh(self) -> bool:
        return self.run.rates.fresh

    def resize(self):
        """(Re)allocate the per-particle arrays when the particle count changed (set-up)."""
        n, dim = self.run.particles.n, self.run.particles.dim
        self.run.fit_rates()
        if self.pos0.shape != (n, dim):
            self.pos0 = np.zeros((n, dim))
            self._drho_spare = np.zeros(n)
            self._extra_arrays(n, dim)

    def _extra_arrays(self, n, dim):
        pass

    def reorder_plan(self, forces):
        """The permutation that puts the particles in cell order, or None when they are in it
        (:meth:`sphcore.physics.forces.Forces.reorder_plan`; a scheme that bins the particles
        itself gives its own)."""
        return forces.reorder_plan(self.run.particles.pos)

    def permute(self, order):
        """Follow a reordering of the particles (the rates move with them): gathered into
        the scratch arrays, which then swap roles (no allocation)."""
        r = self.run.rates
        np.take(r.acc, order, axis=0, out=self.pos0, mode="clip")  # pos0: rewritten by every drift
        r.acc, self.pos0 = self.pos0, r.acc
        np.take(r.drho, order, out=self._drho_spare, mode="clip")  # "raise" would buffer
        r.drho, self._drho_spare = self._drho_spare, r.drho

    def restored(self):
        """The run state was put back from a snapshot: forget what was derived from the state
        since it was taken (nothing here; a scheme that keeps more says what)."""

    def invalidate(self):
        """The state changed outside a step (density filter): recompute rates first."""
        self.run.rates.fresh = False

    def rates(self):
        """Make the run state's rates those of the current particles."""
        r = self.run.rates
        if not r.fresh:
            self.rates_fn(r.acc, r.drho)
            r.fresh = True

    # -- stages -----------------------------------------------------------------------

    def free_motion(self, dt):
        """x += dt (v + half_kick dt/2 a), v += dt a, rho += dt D, with the rates of the
        step's start (``pos0`` keeps the positions before it, for the walls)."""
        st, r = self.run.particles, self.run.rates
        self.rates()
        _drift_kick(self.pos0, st.pos, st.vel, r.acc, st.rho, r.drho, dt, self.half_kick, self.evolves_density)


class Euler(SchemeBase):
    """Explicit (forward) Euler, the paper's scheme; rates at the start of each step."""

    name = "euler"

    def finish(self, dt) -> bool:
        self.run.rates.fresh = False
        return False


class Leapfrog(SchemeBase):
    """Kick-drift-kick leapfrog (see module docstring); rates from the previous step are reused."""

    name = "leapfrog"
    half_kick = 1.0

    def _extra_arrays(self, n, dim):
        self.acc_old = np.zeros((n, dim))
        self.drho_old = np.zeros(n)

    def finish(self, dt) -> bool:
        st, r = self.run.particles, self.run.rates
        # the rates of the step's start become the old ones by swapping the arrays (the
        # evaluation overwrites every row), not by copying them
        r.acc, self.acc_old = self.acc_old, r.acc
        if self.evolves_density:
            r.drho, self.drho_old = self.drho_old, r.drho
        self.rates_fn(r.acc, r.drho)
        _correct(st.vel, r.acc, self.acc_old, st.rho, r.drho, self.drho_old, 0.5 * dt, self.evolves_density)
        r.fresh = True
        return self.evolves_density


SCHEMES = {"euler": Euler, "leapfrog": Leapfrog}
