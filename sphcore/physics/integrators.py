"""Time integrators. Each step: free motion (no walls), then the ``sph_after_integrate``
hook (where the reflective boundary corrects positions and velocities), then rates.

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
# threads (`benchmarks/bench_pairs.py`): the step outside the timed stages, mostly these
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


class _Scheme:
    """What both schemes share: the rates of the current state (``acc``, ``drho``, computed
    once and reused while ``fresh``), the scratch arrays, and the free-motion stage that
    ends in the boundary correction.

    A scheme is built with the particles, the force evaluation (``forces.evaluate(acc,
    drho)``), ``after_drift(pos0, pos, vel, acc, dt)`` (the walls) and ``eos()`` (pressure
    from density); it calls nothing else.
    """

    name = ""
    half_kick = 0.0  # weight of dt/2 * a in the drift: 0 for Euler, 1 for the leapfrog

    def __init__(self, state, forces, after_drift, eos, evolves_density: bool):
        self.state, self.forces, self.after_drift, self.eos = state, forces, after_drift, eos
        self.evolves_density = evolves_density
        self.fresh = False  # are acc/drho the rates of the current state?
        self.acc = np.zeros((0, state.dim))
        self.drho = np.zeros(0)
        self.pos0 = np.zeros((0, state.dim))
        self.resize()

    # -- arrays -----------------------------------------------------------------------

    def resize(self):
        """(Re)allocate the per-particle arrays when the particle count changed (set-up)."""
        n, dim = self.state.n, self.state.dim
        if self.acc.shape[0] != n:
            self.acc = np.zeros((n, dim))
            self.drho = np.zeros(n)
            self.pos0 = np.zeros((n, dim))
            self._drho_spare = np.zeros(n)
            self._extra_arrays(n, dim)
            self.fresh = False

    def _extra_arrays(self, n, dim):
        pass

    def permute(self, order):
        """Follow a reordering of the particles (the rates move with them): gathered into
        the scratch arrays, which then swap roles (no allocation)."""
        np.take(self.acc, order, axis=0, out=self.pos0, mode="clip")  # pos0: rewritten by every drift
        self.acc, self.pos0 = self.pos0, self.acc
        np.take(self.drho, order, out=self._drho_spare, mode="clip")  # "raise" would buffer
        self.drho, self._drho_spare = self._drho_spare, self.drho

    def invalidate(self):
        """The state changed outside a step (density filter): recompute rates first."""
        self.fresh = False

    def rates(self):
        """Make ``acc``/``drho`` the rates of the current state."""
        if not self.fresh:
            self.forces.evaluate(self.acc, self.drho)
            self.fresh = True

    def checkpoint(self) -> dict:
        """Arrays and flags a restart needs to continue bit for bit."""
        return {"acc": self.acc, "drho": self.drho, "fresh": self.fresh}

    def restore(self, saved: dict):
        self.resize()
        self.acc[:] = saved["acc"]
        if "drho" in saved and saved["drho"].shape == self.drho.shape:
            self.drho[:] = saved["drho"]
        self.fresh = bool(saved["fresh"])

    # -- stages -----------------------------------------------------------------------

    def free_motion(self, dt):
        """x += dt (v + half_kick dt/2 a), v += dt a, rho += dt D; then walls and EOS."""
        st = self.state
        self.rates()
        _drift_kick(self.pos0, st.pos, st.vel, self.acc, st.rho, self.drho, dt, self.half_kick, self.evolves_density)
        self.after_drift(self.pos0, st.pos, st.vel, self.acc, dt)
        self.eos()


class Euler(_Scheme):
    """Explicit (forward) Euler, the paper's scheme; rates at the start of each step."""

    name = "euler"

    def step(self, dt):
        self.free_motion(dt)
        self.fresh = False


class Leapfrog(_Scheme):
    """Kick-drift-kick leapfrog (see module docstring); rates from the previous step are reused."""

    name = "leapfrog"
    half_kick = 1.0

    def _extra_arrays(self, n, dim):
        self.acc_old = np.zeros((n, dim))
        self.drho_old = np.zeros(n)

    def step(self, dt):
        st = self.state
        self.free_motion(dt)
        # the rates of the step's start become the old ones by swapping the arrays (the
        # evaluation overwrites every row), not by copying them
        self.acc, self.acc_old = self.acc_old, self.acc
        if self.evolves_density:
            self.drho, self.drho_old = self.drho_old, self.drho
        self.forces.evaluate(self.acc, self.drho)
        _correct(st.vel, self.acc, self.acc_old, st.rho, self.drho, self.drho_old, 0.5 * dt, self.evolves_density)
        if self.evolves_density:
            self.eos()
        self.fresh = True


SCHEMES = {"euler": Euler, "leapfrog": Leapfrog}
