"""The simulation: builds the particles and the run context, and steps them.

A step reads: reorder (when due) -> dt -> integrator (rates, free motion,
``sph_after_integrate``) -> checks -> ``sph_after_step`` -> ``sph_output``. Only the
physics a case asks for runs; ``ctx.counters`` records which kernels ran, for tests and
for the run summary.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from sphcore.errors import CaseError, Instability
from sphcore.physics import checks, eos
from sphcore.physics.forces import Forces, PressureField
from sphcore.physics.integrators import SCHEMES
from sphcore.physics.params import derive
from sphcore.physics.particles import FLUID, SPHERE, ParticleState, lattice, make_block
from sphcore.physics.timestep import adaptive_dt, max_norms
from sphcore.plugin.context import RunContext
from sphcore.plugin.pluginhost import HookRelay
from sphcore.run import checkpoint, relax

CORE = "core"  # the core's own figures in the stats namespaces (energy reference, growth)

KIND_CODES = {"fluid": FLUID, "sphere": SPHERE}  # case.toml block kind -> state.kind
INSIDE_TOL = 1e-9  # relative to the radius: a particle at d = r - ulp still counts as inside


def block_positions(case, k, b):
    """Centres of block k: its lattice, less the particles a finite wall removes (closer
    than a radius to a face, or in a solid); (positions, removed count). A centre beyond
    a wall plane is an error naming the block."""
    dx, r = case.dx, case.radius
    pos = lattice(b["min"], b["max"], dx, b["count"])
    if pos.shape[0] == 0:
        raise CaseError(case.file, f"blocks[{k}]", f"the block holds no particle at dx = {dx} m")
    d = case.planes.distances(pos)
    bad = np.argwhere(d < r * (1.0 - INSIDE_TOL))
    if bad.size:
        i, p = bad[0]
        raise CaseError(case.file, f"blocks[{k}]", f"particle at {pos[i].round(9).tolist()} is outside wall plane {p} "
                        f"(distance {d[i, p]:.6g} m < radius {r:.6g} m){_rounding_hint(k, b, dx, pos[i])}")
    if case.faces.count == 0:
        return pos, 0
    keep = (case.faces.distances(pos) >= r * (1.0 - INSIDE_TOL)) & case.faces.in_fluid(pos)
    if not keep.any():
        raise CaseError(case.file, f"blocks[{k}]", "every particle of the block lies in a solid wall or "
                        "closer than a radius to a wall face")
    return np.ascontiguousarray(pos[keep]), int(pos.shape[0] - keep.sum())


def _rounding_hint(k, b, dx, x) -> str:
    """When the block's extent is not a whole number of dx and rounding up put the row of
    the particle x past the block's max (and so into a wall): what to change (a dx changed
    with --set meets this first)."""
    if b.get("count") is not None:
        return ""
    lo, hi = np.asarray(b["min"], float), np.asarray(b["max"], float)
    cells = (hi - lo) / dx
    up = np.nonzero((np.rint(cells) > cells + 1e-9) & (x + 0.5 * dx > hi + 1e-9 * dx))[0]
    if up.size == 0:
        return ""
    a = int(up[0])
    fit = hi.copy()
    fit[a] = lo[a] + np.floor(cells[a] + 1e-9) * dx
    vec = ", ".join(f"{v:.9g}" for v in fit)
    return (f"; the block's extent along axis {a}, {hi[a] - lo[a]:.6g} m, is {cells[a]:.4g} dx, rounded up to "
            f"{int(np.rint(cells[a]))} rows: give max[{a}] = {fit[a]:.9g} (--set 'blocks[{k}].max=[{vec}]') "
            f"or a dx that divides the extent")


def build_state(case) -> ParticleState:
    """Particles of every [[blocks]] entry; each must lie inside every wall plane, and those a
    finite wall covers are not created (``state.removed_by_walls`` counts them)."""
    r, rho0 = case.radius, case.config["fluid"]["rho0"]
    state = ParticleState.empty(case.dim)
    removed = 0
    for k, b in enumerate(case.blocks):
        pos, m = block_positions(case, k, b)
        removed += m
        state.append(make_block(pos, b["velocity"], rho0, case.dx, r, KIND_CODES[b["kind"]]))
    state.removed_by_walls = removed
    return state


def block_tops(case, state) -> np.ndarray:
    """For each particle, the height (m, along -g) of the top of its block: its free surface
    at rest. Blocks are appended in order, so particle ids run block by block."""
    g = np.linalg.norm(case.gravity)
    up = -case.gravity[: case.dim] / g if g > 0 else np.zeros(case.dim)
    z = state.pos @ up
    tops = np.empty(state.n)
    start = 0
    for k, b in enumerate(case.blocks):
        n_b = block_positions(case, k, b)[0].shape[0]
        tops[start:start + n_b] = z[start:start + n_b].max() + 0.5 * case.dx
        start += n_b
    return tops


class Simulation:
    """One run: the particles, the run context handed to plugins, the force evaluation and
    the integrator, and the step loop. ``pm`` is the run's pluggy PluginManager.

    A step reads: reorder (when due) -> density filter (when due) -> dt -> integrator
    (free motion, ``sph_after_integrate``, rates) -> checks -> ``sph_after_step``;
    the runner then calls :meth:`output`.
    """

    def __init__(self, case, pm, output_dir: Path | None = None, restarting: bool = False, relaxing: bool = False,
                 settle: bool = True):
        self.case, self.pm = case, pm
        self.relaxing = relaxing  # a copy of the run settling its start (sphcore.run.relax): no sph_after_step
        state = build_state(case)
        cfg = case.config
        sph = cfg["physics"]["sph"]
        surface = 0.0
        tops = None
        if sph and np.linalg.norm(case.gravity) > 0:
            tops = block_tops(case, state)
            surface = float(tops.max())  # hydrostatic reference of the modified pressure (m)
        prm = derive(case, state, surface)
        self.ctx = ctx = RunContext(case, prm, state, output_dir, restarting,
                                    plugin_name=lambda plugin: pm.get_name(plugin) or type(plugin).__name__)
        if tops is not None and cfg["physics"]["hydrostatic_init"] and not prm.modified_pressure:
            _hydrostatic_start(case, prm, state, tops)
        saved = checkpoint.read(output_dir) if restarting else None
        relaxed = None
        if settle and not (saved or relaxing) and cfg["relax"]["time"] > 0:  # settle=False: sph check
            relaxed = relax.settle(case, state)  # positions and densities at rest in the scheme's equilibrium
        if saved:  # constants above come from the case's initial particles, as in the first run
            checkpoint.restore_state(ctx, *saved)
        self.pressure = PressureField(prm)
        ctx._pressure = self.pressure
        self.hooks = HookRelay(pm)  # the per-step hooks (no pluggy call where none is implemented)
        self.forces = Forces(ctx, self.hooks, self.pressure)
        self.integrator = SCHEMES[cfg["integrator"]["scheme"]](
            ctx.state, self.forces, self._after_drift, self.update_pressure, evolves_density=sph)
        ctx._rates = self.integrator
        if relaxed is not None:
            ctx.stats(CORE)["relax"] = relaxed
        pm.hook.sph_setup(ctx=ctx)  # every ctx attribute is usable here
        self.integrator.resize()  # a plugin may have added particles
        if saved:
            checkpoint.restore_rates(self, *saved)
        self.update_pressure()
        # energy can only fall unless a plugin does work on the particles (adds accelerations);
        # a plugin that adds them says whether they are conservative through sph_energy
        working = sorted({i.plugin_name for i in pm.hook.sph_accelerations.get_hookimpls()}
                         - {i.plugin_name for i in pm.hook.sph_energy.get_hookimpls()})
        self.check_energy = cfg["checks"]["energy_growth"] > 0 and not working
        ctx.stats(CORE)["energy_check"] = (
            "on" if self.check_energy else "off: checks.energy_growth = 0" if not working else
            f"off: plugin(s) {', '.join(working)} add accelerations and report no energy (sph_energy)")
        self._energy_reference()

    # -- what plugins and the runner read ----------------------------------------------

    @property
    def state(self):
        return self.ctx.state

    @property
    def params(self):
        return self.ctx.params

    @property
    def t(self):
        return self.ctx.t

    @property
    def step(self):
        return self.ctx.step

    @property
    def dt(self):
        return self.ctx.dt

    @property
    def t_end(self):
        return self.ctx.t_end

    @property
    def counters(self):
        return self.ctx.counters

    # -- pieces of a step ---------------------------------------------------------------

    def _after_drift(self, pos0, pos, vel, acc, dt):
        self.hooks.sph_after_integrate(ctx=self.ctx, pos0=pos0, pos=pos, vel=vel, acc=acc, dt=dt)

    def update_pressure(self):
        self.pressure.update(self.ctx.state, self.ctx.counters)

    def reorder(self):
        """Sort particles by cell so that neighbours are near in memory (ids keep identity);
        nothing to do when they are in the kept pair list's order already."""
        order = self.forces.reorder_plan(self.state.pos)
        if order is None:
            return
        self.state.permute(order)
        self.integrator.permute(order)
        self.forces.reordered(order)
        self.update_pressure()  # derived arrays (modified pressure) follow the new order
        self.counters["reorder"] += 1

    def shepard_filter(self):
        """Density <- Shepard-filtered density (:meth:`sphcore.physics.forces.Forces.shepard_density`)."""
        self.forces.shepard_density(self.state.rho)
        self.update_pressure()
        self.integrator.invalidate()
        self.counters["shepard_filter"] += 1

    def choose_dt(self) -> float:
        tcfg, prm = self.case.config["time"], self.params
        if tcfg["dt"] is not None:
            dt = tcfg["dt"]
        else:
            vmax, amax = max_norms(self.state.vel, self.integrator.acc)
            dt = adaptive_dt(prm.h, prm.c0, prm.nu, vmax, amax, tcfg["cfl"], tcfg["force_factor"],
                             tcfg["viscous_factor"])
            if tcfg["dt_max"] is not None:
                dt = min(dt, tcfg["dt_max"])
        bounds = [b for b in self.hooks.sph_max_dt(ctx=self.ctx) if b is not None]
        if bounds:
            dt = min(dt, min(bounds))
        if not math.isfinite(dt):
            raise CaseError(self.case.file, "time.dt", "required: no sound speed, velocity or force limits the step")
        remaining = self.t_end - self.t
        # land exactly on t_end instead of taking a sliver of a step at the end
        return remaining if remaining <= dt * (1.0 + 1e-6) else dt

    def advance(self):
        """One complete step."""
        ctx, cfg = self.ctx, self.case.config
        if ctx.step % cfg["neighbours"]["sort_every"] == 0 and ctx.params.sph:
            self.reorder()
        shepard_every = cfg["corrections"]["shepard_every"] if ctx.params.sph else 0
        if shepard_every and ctx.step > 0 and ctx.step % shepard_every == 0:
            self.shepard_filter()
        self.integrator.rates()  # dt needs the current accelerations (force limit)
        ctx.dt = self.choose_dt()
        if ctx.t + ctx.dt == ctx.t:  # a step below the round-off of t would hang the run
            raise Instability(ctx.step, ctx.t, -1, f"time step {ctx.dt:.3g} s is below the round-off of t: "
                              "time cannot advance")
        self.integrator.step(ctx.dt)
        ctx.t += ctx.dt
        ctx.step += 1
        if ctx.step % cfg["checks"]["every"] == 0:
            self.check()
        if not self.relaxing:  # gauges and probes sample the run, not its relaxation
            self.hooks.sph_after_step(ctx=ctx)

    # -- checks -----------------------------------------------------------------------

    def energy(self) -> float:
        """Kinetic + potential + Tait internal energy (J; J/m in 2D); see checks.total_energy,
        plus what plugins that store energy report (``sph_energy``)."""
        st, prm = self.state, self.params
        e = checks.total_energy(st.pos, st.vel, st.rho, st.m, prm.gravity, prm.rho0, prm.c0 or 1.0,
                                prm.gamma, prm.sph)
        return e + sum(x for x in self.hooks.sph_energy(ctx=self.ctx) if x is not None)

    def _energy_reference(self):
        """E at the start of the run (kept in the core's stats, so a restart checks against
        the same reference) and the scale growth is measured in: M |g| H + the start's
        kinetic energy."""
        st, prm, core = self.state, self.params, self.ctx.stats(CORE)
        if "energy_start" not in core:
            z = st.pos @ prm.up if prm.g_abs > 0 else np.zeros(st.n)
            kinetic = 0.5 * float(np.sum(st.m * np.einsum("ij,ij->i", st.vel, st.vel)))
            core["energy_start"] = self.energy()
            core["energy_scale"] = float(st.m.sum()) * prm.g_abs * float(np.ptp(z) + self.case.dx) + kinetic

    def check(self):
        st, ck, prm, core = self.state, self.case.config["checks"], self.params, self.ctx.stats(CORE)
        walls = self.ctx.walls
        code, i, value = checks.scan(st.pos, st.vel, st.rho, ck["rho_min"] * prm.rho0, ck["rho_max"] * prm.rho0,
                                     prm.sph, walls.normals, walls.offsets)
        self.counters["checks"] += 1
        if code != checks.OK:
            detail = f"{checks.REASONS[code]}: value {value:.6g}"
            if code in (checks.RHO_LOW, checks.RHO_HIGH):
                detail += f" kg/m^3, bounds [{ck['rho_min'] * prm.rho0:.6g}, {ck['rho_max'] * prm.rho0:.6g}]"
            raise Instability(self.step, self.t, int(st.id[i]), detail)
        # the energy sum (a power per particle) costs ~6% of a step at 10^5 particles;
        # every 10th check is soon enough for a growth that builds over many steps
        if self.check_energy and core["energy_scale"] > 0 and self.counters["checks"] % 10 == 0:
            growth = (self.energy() - core["energy_start"]) / core["energy_scale"]
            core["energy_growth_max"] = max(core.get("energy_growth_max", 0.0), growth)
            if growth > ck["energy_growth"]:
                fastest = int(st.id[np.argmax(np.einsum("ij,ij->i", st.vel, st.vel))])
                raise Instability(self.step, self.t, fastest,
                                  f"total energy grew by {100 * growth:.2f}% of its scale (limit "
                                  f"{100 * ck['energy_growth']:g}%): numerical instability, e.g. a time step "
                                  f"too large or too little dissipation")

    def output(self, final=False):
        self.hooks.sph_output(ctx=self.ctx, final=final)

    def done(self) -> bool:
        return self.t_end - self.t <= 1e-9 * (self.dt or self.t_end)


def _hydrostatic_start(case, prm, st, tops):
    """Each fluid block at rest in the discrete equilibrium of the SPH sums: the exact
    hydrostatic pressure of the Tait fluid below the block's top
    (:func:`sphcore.physics.eos.hydrostatic_pressure`), the density from the inverse Tait equation,
    and the mass of each particle scaled by rho / rho0, since the particles stand on a
    uniform lattice: the fluid's extra mass at depth is in the masses, not in a closer
    spacing.

    Until 2026-11-24 the pressure was rho0 g d and the masses rho0 dx^dim. The pressure
    sums of a uniform lattice of equal masses then see the density stratification only
    through the p_j / rho_j^2 of the momentum equation: in a 1 m tank of plain Tait water at
    h = 1.5 dx the interior's vertical acceleration drifted from -0.004 g under the free
    surface to -0.018 g at the bottom, and a particle along a side wall differed from its
    interior neighbours by up to 0.004 g (a shear the wall's terms do not carry). Now both
    are -0.0026 g everywhere below the free surface's reach ((lambda - 1) g, the lattice
    normalisation), walls included (``tests/test_hydrostatic_start.py``).
    """
    fluid = st.kind == FLUID
    p = eos.hydrostatic_pressure(tops[fluid] - st.pos[fluid] @ prm.up, prm.rho0, prm.c0, prm.gamma, prm.g_abs)
    if not np.all(np.isfinite(p)):
        raise CaseError(case.file, "eos.gamma", f"a Tait exponent {prm.gamma:g} with c0 = {prm.c0:g} m/s "
                        "cannot hold the fluid's depth at rest (the hydrostatic density diverges); "
                        "raise eos.gamma or the sound speed, or set physics.hydrostatic_init = false")
    rho = eos.density_of(p, prm.rho0, prm.c0, prm.gamma)
    st.rho[fluid] = rho
    st.m[fluid] *= rho / prm.rho0
