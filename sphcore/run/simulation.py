"""The simulation: the run state wired to the physics and the plugins, and one step.

A step reads: reorder (when due) -> density filter (when due) -> rates -> dt -> free motion
-> ``sph_after_integrate`` (walls) -> equation of state -> rates at the new state (and the
leapfrog's corrector) -> checks (when due) -> ``sph_after_step``. Only the physics a case
asks for runs; ``ctx.counters`` records which kernels ran, for tests and for the run
summary. A Simulation is made by :func:`sphcore.run.build.build` from a case.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from sphcore.errors import CaseError, Instability
from sphcore.physics import checks
from sphcore.physics.forces import Forces, PressureField
from sphcore.physics.incompressible import DivergenceFree, SolvedPressure
from sphcore.physics.integrators import SCHEMES
from sphcore.geometry.motion import wall_speed
from sphcore.physics.timestep import adaptive_dt, max_norms
from sphcore.plugin.context import RunContext
from sphcore.plugin.pluginhost import HookRelay
from sphcore.run.activities import Activity, StepInterval
from sphcore.run.state import RunState, Snapshot

CORE = "core"  # the core's own figures in the stats namespaces (energy reference, growth)


class Simulation:
    """One run: the particles, the run context handed to plugins, the force evaluation and
    the integrator, and the step loop. ``pm`` is the run's pluggy PluginManager.

    ``params``: the run's constants (:class:`sphcore.physics.params.Params`); ``run``: its
    state (:class:`sphcore.run.state.RunState`), from the case or a checkpoint. A step is
    :meth:`advance` (module docstring); the runner then calls :meth:`output`.
    """

    def __init__(self, case, pm, params, run: RunState, output_dir: Path | None = None, restarting: bool = False,
                 relaxing: bool = False):
        self.case, self.pm = case, pm
        self.relaxing = relaxing  # the relaxation's own run (sphcore.run.relax): no sph_after_step
        self.run = run
        self.incompressible = case.config["scheme"]["name"] == "dfsph"
        self.pressure = (SolvedPressure if self.incompressible else PressureField)(params)
        self.ctx = ctx = RunContext(case, params, run, pressure=self.pressure, output_dir=output_dir,
                                    restarting=restarting,
                                    plugin_name=lambda plugin: pm.get_name(plugin) or type(plugin).__name__)
        self.hooks = HookRelay(pm)  # the per-step hooks (no pluggy call where none is implemented)
        # dfsph lists its pairs every step (sphcore.physics.solvepairs): no Verlet list beside
        self.forces = Forces(ctx, self.hooks, self.pressure, keep_pairs=not self.incompressible)
        run.attach_pairs(self.forces.pairs)  # a restart's lists are rebuilt from its anchor
        if self.incompressible:
            if "sph_extra_sources" in self.hooks.implemented:
                raise CaseError(case.file, "plugins.use", "dfsph takes the walls' pressure from wall_integral into its "
                                "solves; plugin source particles (ghost) are not part of them")
            self.integrator = DivergenceFree(run, self.forces, ctx, case.config["scheme"])
        else:
            self.integrator = SCHEMES[case.config["integrator"]["scheme"]](run, self.forces.evaluate,
                                                                          evolves_density=params.sph)
        # floating bodies: wall groups whose motion the fluid's loads advance (not while relaxing:
        # the relaxation settles the fluid around the bodies where case.toml draws them); a
        # restart puts them where the checkpoint has them before any plugin looks at the walls
        self.bodies = [] if relaxing else [(g.name, g.motion) for g in case.moving if hasattr(g.motion, "begin_step")]
        kept = run.kept.get("bodies", {})
        for name, motion in self.bodies:
            if name in kept:
                motion.restore(kept[name])
                f = kept[name]["fluid_load"]
                ctx.wall_forces[name] = (np.asarray(f[:3]), np.asarray(f[3:]))
        pm.hook.sph_setup(ctx=ctx)  # every ctx attribute is usable here
        self.integrator.resize()  # a plugin may have added particles
        self.update_pressure()
        # energy can only fall unless a plugin does work on the particles (adds accelerations);
        # a plugin that adds them says whether they are conservative through sph_energy
        working = sorted({i.plugin_name for i in pm.hook.sph_accelerations.get_hookimpls()}
                         - {i.plugin_name for i in pm.hook.sph_energy.get_hookimpls()})
        moving = [g.name for g in case.moving]  # moving walls do work on the fluid
        self.check_energy = case.config["checks"]["energy_growth"] > 0 and not working and not moving
        ctx.stats(CORE)["energy_check"] = (
            "on" if self.check_energy else "off: checks.energy_growth = 0"
            if case.config["checks"]["energy_growth"] <= 0 else
            f"off: plugin(s) {', '.join(working)} add accelerations and report no energy (sph_energy)" if working
            else f"off: walls move ({', '.join(moving)}) and do work on the fluid")
        self._energy_reference()
        # what a step does before it moves the particles, on step counts (sphcore.run.activities)
        cfg = case.config
        self.before_step = []
        if params.sph:
            self.before_step.append(Activity("reorder", StepInterval(cfg["neighbours"]["sort_every"]),
                                             Simulation.reorder))
            if cfg["corrections"]["shepard_every"] and not self.incompressible:
                self.before_step.append(Activity("density_filter",
                                                 StepInterval(cfg["corrections"]["shepard_every"], skip_first=True),
                                                 Simulation.shepard_filter))
        self.checks_due = StepInterval(cfg["checks"]["every"])

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

    # -- the state as a whole ---------------------------------------------------------------

    def snapshot(self) -> Snapshot:
        """A copy of the run state, and of the force pressure derived from it."""
        snap = self.run.snapshot()
        snap.extra["force_pressure"] = self.ctx.force_pressure.copy()
        return snap

    def restore(self, snap: Snapshot) -> None:
        """Put a :meth:`snapshot` back: the run continues exactly as from where it was taken."""
        self.run.restore(snap)
        self.ctx.force_pressure[...] = snap.extra["force_pressure"]
        self.forces.forget_wall_terms()
        self.integrator.restored()

    # -- pieces of a step ---------------------------------------------------------------

    def update_pressure(self):
        self.pressure.update(self.ctx.state, self.ctx.counters)

    def reorder(self):
        """Sort particles by cell so that neighbours are near in memory (ids keep identity);
        nothing to do when they are in the kept pair list's order already."""
        order = self.integrator.reorder_plan(self.forces)
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
            if self.case.moving:  # a wall's speed limits the step as a particle's does
                vmax = max(vmax, wall_speed(self.case.moving, self.t, self.state.pos))
            # the incompressible scheme's step follows the flow: no sound speed, its own CFL number
            scheme = self.case.config["scheme"]
            c0, cfl, force = ((0.0, scheme["cfl"], scheme["force_factor"]) if self.incompressible
                              else (prm.c0, tcfg["cfl"], tcfg["force_factor"]))
            dt = adaptive_dt(prm.h, c0, prm.nu, vmax, amax, cfl, force, tcfg["viscous_factor"])
            if tcfg["dt_max"] is not None:
                dt = min(dt, tcfg["dt_max"])
        bounds = [b for b in self.hooks.sph_max_dt(ctx=self.ctx) if b is not None]
        if bounds:
            dt = min(dt, min(bounds))
        if not math.isfinite(dt):
            raise CaseError(self.case.file, "time.dt", "required: no sound speed, velocity or force limits the step")
        remaining = self.t_end - self.t
        # land exactly on t_end instead of taking a sliver of a step at the end
        if remaining <= dt * (1.0 + 1e-6):
            return remaining
        if self.incompressible and remaining < 2.0 * dt:
            # the density solve removes the step's density error within the step (kappa ~ 1 / dt^2):
            # a sliver of a last step (4e-6 s after 6.5e-4 s in the 3D dam break) turned the error
            # into kicks of 29 m/s and 1.4e8 Pa. The last two steps share what remains instead.
            return 0.5 * remaining
        return dt

    def advance(self):
        """One complete step."""
        ctx = self.ctx
        for activity in self.before_step:
            activity(self)
        self.integrator.rates()  # dt needs the current accelerations (force limit)
        ctx.dt = self.choose_dt()
        if ctx.t + ctx.dt == ctx.t:  # a step below the round-off of t would hang the run
            raise Instability(ctx.step, ctx.t, -1, f"time step {ctx.dt:.3g} s is below the round-off of t: "
                              "time cannot advance")
        integ, st = self.integrator, self.state
        none = (np.zeros(3), np.zeros(3))
        if any(name not in ctx.wall_forces for name, _ in self.bodies):  # the first step's loads
            self._body_loads()
        for name, body in self.bodies:  # half a kick and the drift: the walls at t + dt
            body.begin_step(ctx.t, ctx.dt, *ctx.wall_forces.get(name, none))
            self._report_load(name, 0.5 * ctx.dt)
        ctx.contact_impulses.clear()
        integ.free_motion(ctx.dt)
        self.hooks.sph_after_integrate(ctx=ctx, pos0=integ.pos0, pos=st.pos, vel=st.vel, acc=integ.acc, dt=ctx.dt)
        for name, body in self.bodies:  # what the walls' contacts took from the fluid
            if name in ctx.contact_impulses:
                j = ctx.contact_impulses[name]
                body.impulse(j[:3], j[3:])
        # the particles are at t + dt now: so is the clock, so that the rates at the end of
        # the step (the leapfrog's) see moving walls where they are then
        ctx.t += ctx.dt
        self.update_pressure()
        if integ.finish(ctx.dt):  # the density changed again: its pressure too
            self.update_pressure()
        if self.bodies:  # the other half kick, with the loads at t + dt
            self._body_loads()
            for name, body in self.bodies:
                body.end_step(*ctx.wall_forces.get(name, none))
                self._report_load(name, 0.5 * ctx.dt)
            self.run.kept["bodies"] = {name: {**body.state(), "fluid_load": _six(ctx.wall_forces.get(name, none))}
                                       for name, body in self.bodies}
            figures = ctx.stats("bodies")  # in summary.json: each body's contacts with walls and bodies so far
            for name, body in self.bodies:
                figures[name] = {"contacts": body.contacts}
        ctx.step += 1
        if self.checks_due.due(self.run.clock):
            self.check()
        if not self.relaxing:  # gauges and probes sample the run, not its relaxation
            self.hooks.sph_after_step(ctx=ctx)

    def _report_load(self, name: str, dt: float) -> None:
        """The fluid's load on body ``name`` over ``dt`` (half a step: each half kick's), for
        the ``wall_loads`` writer (``ctx.add_wall_load``; the contacts add theirs)."""
        force, moment = self.ctx.wall_forces.get(name, (np.zeros(3), np.zeros(3)))
        self.ctx.add_wall_load(name, np.asarray(force) * dt, np.asarray(moment) * dt)

    def _body_loads(self) -> None:
        """Each floating body's load at the last evaluation of the rates, where its walls'
        particles are known (``ctx.wall_members``): minus the sum of m_i times the
        acceleration the completion gave them (``WallTerms.react``), weighted by the body's
        share of their wall terms, and its moment about the centre of mass. The fluid's
        momentum and the body's then change by opposite amounts."""
        ctx, react = self.ctx, self.forces.wall_react()
        if react is None:
            return
        st = self.state
        for name, body in self.bodies:
            if name not in ctx.wall_members:
                continue
            idx, w = ctx.wall_members[name]
            f = -(st.m[idx] * w)[:, None] * react[idx]
            force = f.sum(axis=0)
            arm = st.pos[idx] - body.body.x
            if arm.shape[1] == 2:
                moment = np.array([0.0, 0.0, float((arm[:, 0] * f[:, 1] - arm[:, 1] * f[:, 0]).sum())])
            else:
                moment = np.cross(arm, f).sum(axis=0)
            ctx.wall_forces[name] = (force, moment)

    # -- checks -----------------------------------------------------------------------

    def energy(self) -> float:
        """Kinetic + potential + Tait internal energy (J; J/m in 2D); see checks.total_energy,
        plus what plugins that store energy report (``sph_energy``)."""
        st, prm = self.state, self.params
        # the incompressible fluid stores no internal energy: its pressure is a constraint's
        e = checks.total_energy(st.pos, st.vel, st.rho, st.m, prm.gravity, prm.rho0, prm.c0 or 1.0,
                                prm.gamma, prm.sph and not self.incompressible)
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
        walls = self.ctx.planes
        # a summed density is low wherever the support is not full (a splash): only its upper bound applies
        rho_lo = 0.0 if self.incompressible else ck["rho_min"] * prm.rho0
        code, i, value = checks.scan(st.pos, st.vel, st.rho, rho_lo, ck["rho_max"] * prm.rho0,
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


def _six(load) -> list:
    """(F, M) as six floats (F padded to three components)."""
    f, m = np.zeros(3), np.zeros(3)
    f[:len(load[0])] = load[0]
    m[:len(load[1])] = load[1]
    return [float(v) for v in f] + [float(v) for v in m]
