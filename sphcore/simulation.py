"""The simulation: particle state, physics constants, work arrays and the step.

A step reads: reorder (when due) -> dt -> integrator (rates, free motion,
``sph_after_integrate``) -> checks -> ``sph_after_step`` -> ``sph_output``. Only the
physics a case asks for runs; ``counters`` records which kernels ran, for tests and
for the run summary.
"""

from __future__ import annotations

import math
from collections import Counter
from pathlib import Path

import numpy as np

from . import checkpoint, checks
from .equations import neighbour_sums, sph_rates, tait_pressure, uniform_acceleration
from .errors import CaseError, Instability
from .integrators import SCHEMES
from .kernels import KERNEL_IDS, SUPPORT
from .neighbours import CellGrid
from .particles import FLUID, SPHERE, ParticleState, lattice, make_block
from .timestep import adaptive_dt, max_norms

KIND_CODES = {"fluid": FLUID, "sphere": SPHERE}  # case.toml block kind -> state.kind
INSIDE_TOL = 1e-9  # relative to the radius: a particle at d = r - ulp still counts as inside


def build_state(case) -> ParticleState:
    """Particles of every [[blocks]] entry; each must lie inside every wall plane."""
    dx, r, rho0 = case.dx, case.radius, case.config["fluid"]["rho0"]
    state = ParticleState.empty(case.dim)
    for k, b in enumerate(case.blocks):
        pos = lattice(b["min"], b["max"], dx, b["count"])
        if pos.shape[0] == 0:
            raise CaseError(case.file, f"blocks[{k}]", f"the block holds no particle at dx = {dx} m")
        d = case.planes.distances(pos)
        bad = np.argwhere(d < r * (1.0 - INSIDE_TOL))
        if bad.size:
            i, p = bad[0]
            raise CaseError(case.file, f"blocks[{k}]", f"particle at {pos[i].round(9).tolist()} is outside wall plane {p} "
                            f"(distance {d[i, p]:.6g} m < radius {r:.6g} m)")
        state.append(make_block(pos, b["velocity"], rho0, dx, r, KIND_CODES[b["kind"]]))
    return state


def block_tops(case, state) -> np.ndarray:
    """For each particle, the height (m, along -g) of the top of its block: its free surface
    at rest. Blocks are appended in order, so particle ids run block by block."""
    g = np.linalg.norm(case.gravity)
    up = -case.gravity[: case.dim] / g if g > 0 else np.zeros(case.dim)
    z = state.pos @ up
    tops = np.empty(state.n)
    start = 0
    for b in case.blocks:
        n_b = lattice(b["min"], b["max"], case.dx, b["count"]).shape[0]
        tops[start:start + n_b] = z[start:start + n_b].max() + 0.5 * case.dx
        start += n_b
    return tops


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


class Simulation:
    """State plus the plugins of one run. ``pm`` is the run's pluggy PluginManager."""

    def __init__(self, case, pm, output_dir: Path | None = None, restarting: bool = False):
        self.case, self.pm = case, pm
        self.output_dir = output_dir
        self.restarting = restarting
        self.t, self.step, self.dt = 0.0, 0, 0.0
        self.t_end = case.config["time"]["t_end"]
        self.stats: dict = {"escaped": 0}
        self.counters: Counter = Counter()
        self.state = build_state(case)
        cfg = case.config
        self.sph = cfg["physics"]["sph"]
        self.evolves_density = self.sph
        self.h = case.h
        self.kernel_id = KERNEL_IDS[cfg["kernel"]["name"]]
        self.gravity = case.gravity
        self.rho0 = cfg["fluid"]["rho0"]
        self.nu = cfg["fluid"]["nu"] if self.sph else 0.0
        self.alpha, self.beta = cfg["viscosity"]["alpha"], cfg["viscosity"]["beta"]
        self.delta = cfg["density_diffusion"]["delta"]
        self.c0 = reference_sound_speed(case, self.state) if self.sph else 0.0
        self.gamma, self.p_background = cfg["eos"]["gamma"], cfg["eos"]["p_background"]
        self.g_abs = float(np.linalg.norm(self.gravity))
        self.up = -self.gravity[: case.dim] / self.g_abs if self.g_abs > 0 else np.zeros(case.dim)
        self.modified_pressure = self.sph and cfg["physics"]["modified_pressure"]
        self.kernel_gradient = self.sph and cfg["corrections"]["kernel_gradient"]
        self.shepard_every = cfg["corrections"]["shepard_every"] if self.sph else 0
        if self.sph and self.g_abs > 0:
            tops = block_tops(case, self.state)
            self.surface_level = float(tops.max())  # hydrostatic reference of the modified pressure (m)
            if cfg["physics"]["hydrostatic_init"] and not self.modified_pressure:
                self._hydrostatic_start(tops)
        self.integrator = SCHEMES[cfg["integrator"]["scheme"]]()
        self.normals = np.ascontiguousarray(case.planes.normals)
        self.offsets = np.ascontiguousarray(case.planes.offsets)
        self.n_sources = 0
        saved = checkpoint.read(output_dir) if restarting else None
        if saved:  # constants above come from the case's initial particles, as in the first run
            checkpoint.restore_state(self, *saved)
        pm.hook.sph_setup(sim=self)
        self._allocate()
        if saved:
            checkpoint.restore_rates(self, *saved)
        self.update_pressure()
        # energy can only fall unless a plugin does work on the particles (adds accelerations)
        self.check_energy = (cfg["checks"]["energy_growth"] > 0
                             and not pm.hook.sph_accelerations.get_hookimpls())
        self._energy_reference()

    def _hydrostatic_start(self, tops):
        """p = rho0 g (top - z) below each block's top, rho from the inverse Tait equation."""
        st = self.state
        fluid = st.kind == FLUID
        p = self.rho0 * self.g_abs * (tops - st.pos @ self.up)
        b = self.c0 ** 2 * self.rho0 / self.gamma
        st.rho[fluid] = self.rho0 * (p[fluid] / b + 1.0) ** (1.0 / self.gamma)

    # -- work arrays ------------------------------------------------------------------

    def _allocate(self):
        n, dim = self.state.n, self.state.dim
        self.acc = np.zeros((n, dim))
        self.pos0 = np.zeros((n, dim))
        self.acc_old = np.zeros((n, dim)) if self.integrator.name == "leapfrog" else self.acc
        self.drho = np.zeros(n) if self.evolves_density else None
        self.drho_old = np.zeros(n) if self.evolves_density and self.integrator.name == "leapfrog" else None
        self.p_dyn = np.zeros(n) if self.modified_pressure else None
        self.L = np.zeros((n if self.kernel_gradient else 1, 3, 3))
        self.shepard = np.zeros(n if self.shepard_every else 1)

    def reorder(self):
        """Sort particles by cell so that neighbours are near in memory (ids keep identity)."""
        order = self._grid(self.state.pos, count=False).order
        self.state.permute(order)
        self.acc[:] = self.acc[order]
        if self.drho is not None:
            self.drho[:] = self.drho[order]
        self.update_pressure()  # derived arrays (modified pressure) follow the new order
        self.counters["reorder"] += 1

    # -- rates ------------------------------------------------------------------------

    def compute_rates(self):
        """acc (and drho) at the current state: SPH terms, gravity, plugin accelerations."""
        st = self.state
        self.counters["rates"] += 1
        if not self.sph:
            uniform_acceleration(self.gravity, self.acc)
        else:
            self.pm.hook.sph_before_forces(sim=self)
            pos, vel, rho, p, m = self._sources()
            grid = self._grid(pos)
            if self.kernel_gradient:
                neighbour_sums(st.n, pos, rho, m, grid.order, grid.cell_start, grid.lo, grid.cell_size, grid.ncell,
                               self.kernel_id, self.h, True, self.L, False, self.shepard)
                self.counters["kernel_gradient_correction"] += 1
            sph_rates(st.n, pos, vel, rho, p, m, grid.order, grid.cell_start, grid.lo, grid.cell_size, grid.ncell,
                      self.kernel_id, self.h, self.c0, self.alpha, self.beta, self.nu, self.delta,
                      self.gravity, self.modified_pressure, self.rho0, self.kernel_gradient, self.L,
                      self.acc, self.drho)
            self.counters["continuity"] += 1
            self.counters["momentum"] += 1
            if self.alpha > 0 or self.beta > 0:
                self.counters["artificial_viscosity"] += 1
            if self.nu > 0:
                self.counters["laminar_viscosity"] += 1
            if self.delta > 0:
                self.counters["density_diffusion"] += 1
        self.pm.hook.sph_accelerations(sim=self, acc=self.acc)

    def _grid(self, pos, count=True):
        try:
            grid = CellGrid(pos, SUPPORT * self.h)
        except OverflowError as e:
            far = int(np.argmax(np.abs(pos - np.median(pos, axis=0)).sum(axis=1)))
            pid = int(self.state.id[far]) if far < self.state.n else -1
            raise Instability(self.step, self.t, pid, f"particles spread far apart ({e})") from None
        if count:
            self.counters["neighbour_search"] += 1
        return grid

    def _sources(self):
        """The fluid followed by any plugin source particles (ghosts); the pressure is the
        one the momentum equation uses (``force_pressure``)."""
        st = self.state
        extra = [s for s in self.pm.hook.sph_extra_sources(sim=self) if s is not None and s.n]
        self.n_sources = sum(s.n for s in extra)
        fluid = (st.pos, st.vel, st.rho, self.force_pressure, st.m)
        if not extra:
            return fluid
        self.counters["extra_sources"] += 1
        return tuple(np.concatenate([a] + [getattr(s, f) for s in extra])
                     for a, f in zip(fluid, ("pos", "vel", "rho", "p", "m")))

    @property
    def force_pressure(self) -> np.ndarray:
        """Pressure in the momentum equation (Pa): the Tait pressure, or with modified
        pressure its dynamic part P = p - rho0 g (surface_level - z) (hydrostatic removed)."""
        return self.p_dyn if self.modified_pressure else self.state.p

    def update_pressure(self):
        """Equation of state; with modified pressure, state.p is the physical pressure
        P + rho0 g (surface_level - z), for output."""
        if not self.evolves_density:
            return
        st = self.state
        tait_pressure(st.rho, self.rho0, self.c0, self.gamma, self.p_background, self.force_pressure)
        if self.modified_pressure:
            st.p[:] = self.p_dyn + self.rho0 * self.g_abs * (self.surface_level - st.pos @ self.up)
        self.counters["eos"] += 1

    def shepard_filter(self):
        """Density <- Shepard-filtered density (Chen et al. 1999, CSPH zeroth order), over
        the fluid and any plugin sources (ghosts complete the sums at walls)."""
        st = self.state
        pos, vel, rho, p, m = self._sources()
        grid = self._grid(pos)
        neighbour_sums(st.n, pos, rho, m, grid.order, grid.cell_start, grid.lo, grid.cell_size,
                       grid.ncell, self.kernel_id, self.h, False, self.L, True, self.shepard)
        st.rho[:] = self.shepard
        self.update_pressure()
        self.integrator.invalidate()
        self.counters["shepard_filter"] += 1

    def after_integrate(self, dt):
        self.pm.hook.sph_after_integrate(sim=self, pos0=self.pos0, pos=self.state.pos, vel=self.state.vel,
                                         acc=self.acc, dt=dt)

    # -- stepping ---------------------------------------------------------------------

    def choose_dt(self) -> float:
        tcfg = self.case.config["time"]
        if tcfg["dt"] is not None:
            dt = tcfg["dt"]
        else:
            vmax, amax = max_norms(self.state.vel, self.acc)
            dt = adaptive_dt(self.h, self.c0, self.nu, vmax, amax, tcfg["cfl"], tcfg["force_factor"],
                             tcfg["viscous_factor"])
            if tcfg["dt_max"] is not None:
                dt = min(dt, tcfg["dt_max"])
        bounds = [b for b in self.pm.hook.sph_max_dt(sim=self) if b is not None]
        if bounds:
            dt = min(dt, min(bounds))
        if not math.isfinite(dt):
            raise CaseError(self.case.file, "time.dt", "required: no sound speed, velocity or force limits the step")
        remaining = self.t_end - self.t
        # land exactly on t_end instead of taking a sliver of a step at the end
        return remaining if remaining <= dt * (1.0 + 1e-6) else dt

    def advance(self):
        """One complete step."""
        if self.step % self.case.config["neighbours"]["sort_every"] == 0 and self.sph:
            self.reorder()
        if self.shepard_every and self.step > 0 and self.step % self.shepard_every == 0:
            self.shepard_filter()
        if not self.integrator.fresh:  # dt needs the current accelerations (force limit)
            self.compute_rates()
            self.integrator.fresh = True
        self.dt = self.choose_dt()
        if self.t + self.dt == self.t:  # issue 13: a step below the round-off of t would hang the run
            raise Instability(self.step, self.t, -1, f"time step {self.dt:.3g} s is below the round-off of t: "
                              "time cannot advance")
        self.integrator.step(self, self.dt)
        self.t += self.dt
        self.step += 1
        if self.step % self.case.config["checks"]["every"] == 0:
            self.check()
        self.pm.hook.sph_after_step(sim=self)

    def energy(self) -> float:
        """Kinetic + potential + Tait internal energy (J; J/m in 2D); see checks.total_energy."""
        st = self.state
        return checks.total_energy(st.pos, st.vel, st.rho, st.m, self.gravity, self.rho0, self.c0 or 1.0,
                                   self.gamma, self.evolves_density)

    def _energy_reference(self):
        """E at the start of the run (kept in stats, so a restart checks against the same
        reference) and the scale growth is measured in: M |g| H + the start's kinetic energy."""
        st = self.state
        if "energy_start" not in self.stats:
            z = st.pos @ self.up if self.g_abs > 0 else np.zeros(st.n)
            kinetic = 0.5 * float(np.sum(st.m * np.einsum("ij,ij->i", st.vel, st.vel)))
            self.stats["energy_start"] = self.energy()
            self.stats["energy_scale"] = float(st.m.sum()) * self.g_abs * float(np.ptp(z) + self.case.dx) + kinetic

    def check(self):
        st, ck = self.state, self.case.config["checks"]
        code, i, value = checks.scan(st.pos, st.vel, st.rho, ck["rho_min"] * self.rho0, ck["rho_max"] * self.rho0,
                                     self.evolves_density, self.normals, self.offsets)
        self.counters["checks"] += 1
        if code != checks.OK:
            detail = f"{checks.REASONS[code]}: value {value:.6g}"
            if code in (checks.RHO_LOW, checks.RHO_HIGH):
                detail += f" kg/m^3, bounds [{ck['rho_min'] * self.rho0:.6g}, {ck['rho_max'] * self.rho0:.6g}]"
            raise Instability(self.step, self.t, int(st.id[i]), detail)
        # the energy sum (a power per particle) costs ~6% of a step at 10^5 particles;
        # every 10th check is soon enough for a growth that builds over many steps
        if self.check_energy and self.stats["energy_scale"] > 0 and self.counters["checks"] % 10 == 0:
            growth = (self.energy() - self.stats["energy_start"]) / self.stats["energy_scale"]
            self.stats["energy_growth_max"] = max(self.stats.get("energy_growth_max", 0.0), growth)
            if growth > ck["energy_growth"]:
                fastest = int(st.id[np.argmax(np.einsum("ij,ij->i", st.vel, st.vel))])
                raise Instability(self.step, self.t, fastest,
                                  f"total energy grew by {100 * growth:.2f}% of its scale (limit "
                                  f"{100 * ck['energy_growth']:g}%): numerical instability, e.g. a time step "
                                  f"too large or too little dissipation")

    def output(self, final=False):
        self.pm.hook.sph_output(sim=self, final=final)

    def done(self) -> bool:
        return self.t_end - self.t <= 1e-9 * (self.dt or self.t_end)
