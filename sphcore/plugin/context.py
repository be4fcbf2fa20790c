"""The run context: everything a plugin's hooks may read or change, in one documented object.

Every hook that acts during a run receives ``ctx``, a :class:`RunContext`:

====================  ===================================================================
``ctx.state``         :class:`sphcore.physics.particles.ParticleState`, the integrated particles
                      (pos, vel, rho, p, m, radius, kind, id). The core reorders them by
                      cell every few steps: read arrays inside a hook, never keep them.
``ctx.params``        :class:`sphcore.physics.params.Params`, every physical and numerical
                      constant of the run (h, support, kernel_id, rho0, c0, gamma, tait_b,
                      gravity, up, ...), frozen; also an argument to numba kernels.
``ctx.planes``        :class:`sphcore.geometry.planes.Planes`, the wall planes of the case
                      where they are at ``ctx.t`` (a moving tank's move; ``planes_at(t)``
                      at any other time; also ``ctx.walls``, the name earlier versions used).
``ctx.case``          :class:`sphcore.case.model.Case`, the validated case: ``ctx.case.config[table]``
                      holds a plugin's options with defaults filled in.
``ctx.t``             simulated time (s) of the particles: the start of the step in
                      ``sph_after_integrate`` (whose ``dt`` says where it ends), the end of
                      the step from the rates that follow it on (the leapfrog's end-of-step
                      forces see moving walls where the particles are).
``ctx.step``          steps completed.
``ctx.dt``            the last step (s); 0 before the first.
``ctx.t_end``         simulated time the run goes to (s).
``ctx.output_dir``    pathlib.Path of the run's output, or None (no output).
``ctx.restarting``    True when the run continues from a checkpoint: at ``sph_setup`` the
                      particles, clock, stats and kept state are those of the checkpoint.
``ctx.force_pressure`` the pressure the momentum equation uses (Pa, (n,)): ``state.p``,
                      or with modified pressure its dynamic part. Plugins may change it in
                      ``sph_before_forces`` (e.g. a free surface held at zero).
``ctx.acc``           (n, dim) the integrator's last accelerations (m/s^2), read only: those
                      of the current state between steps with the leapfrog, of the start of
                      the step in ``sph_after_integrate`` and with Euler.
``ctx.counters``      collections.Counter of the core's kernel calls (for tests, summary).
``ctx.stats(plugin)`` the plugin's own dict of figures: merged into summary.json under
                      the plugin's name and kept across restarts (JSON numbers/strings).
``ctx.kept(plugin)``  the plugin's own dict of state to keep across a restart (numbers,
                      strings, lists or numpy arrays); restored before ``sph_setup``.
``ctx.host()``        the particles as host numpy arrays, read-only: what a writer puts in
                      its files (today the particles themselves).
``ctx.planes_at(t)``  the case's wall planes at time t (s): a moving tank's where it is then.
``ctx.add_wall_load`` (group, impulse, angular_impulse): what the fluid gave the walls
                      of a moving group this step (N s, N m s), for ``wall_loads``.
``ctx.set_wall_force`` (group, force, moment): the fluid's force and moment on a moving
                      group at the rates just evaluated, set by the plugins whose walls
                      carry a pressure; a floating body takes it for its kicks.
``ctx.wall_forces``   {group: (force, moment)} as set above, for the last evaluation.
``ctx.add_contact_impulse`` (group, impulse, angular_impulse): a wall contact's impulse
                      on a group this step (N s, N m s): in its load, and given to a
                      floating body at once.
``ctx.contact_impulses`` {group: six numbers}: the contact impulses of the current step.
``ctx.wall_members``  {group: (particle indices, weights)}: the particles a floating
                      body's faces completed at the last evaluation and the body's share
                      of each one's wall terms.
``ctx.solved_impulse`` (n, dim) or None: the momentum (N s) the walls gave each particle
                      through the pressure of the scheme's last solve, which the rates do
                      not hold (dfsph: the density solve's in ``sph_after_integrate``, the
                      divergence solve's in ``sph_after_step``); None with wcsph, whose
                      wall pressure is in the rates.
====================  ===================================================================

The context is a view of the run state (:class:`sphcore.run.state.RunState`, ``ctx.run``),
built by :class:`sphcore.run.simulation.Simulation`; plugins import its type from
:mod:`sphcore.api`.
"""

from __future__ import annotations

from collections import Counter
from pathlib import Path

import numpy as np

from sphcore.geometry.motion import plane_groups, planes_at


class RunContext:
    """See the module docstring for every attribute. ``run`` is the run state
    (:class:`sphcore.run.state.RunState`): the context is a view of it, so that what a
    plugin reads or changes is always the run's own. ``pressure`` owns the force pressure
    (:class:`sphcore.physics.forces.PressureField`; None: the physical pressure)."""

    def __init__(self, case, params, run, *, pressure=None, output_dir: Path | None = None, restarting: bool = False,
                 plugin_name=None):
        if not hasattr(run, "particles"):
            raise TypeError("RunContext takes the run state (sphcore.run.state.RunState), not the particles; "
                            "sphcore.testing.context() builds a context of a case for a test")
        self.case = case
        self.params = params
        self.run = run
        # the groups that move planes (the tank, pistons); the planes at one time, cached
        self._plane_groups = plane_groups(getattr(case, "moving", ()))
        self._planes_at = (None, case.planes)
        self.output_dir = output_dir
        self.restarting = restarting
        self._pressure = pressure
        self._plugin_name = plugin_name or (lambda plugin: type(plugin).__name__)
        self._names: dict[int, tuple] = {}  # id(plugin) -> (plugin, name): see _name_of
        #: the fluid's force and moment on each moving group at the last evaluation of the
        #: rates ({group: (F, M)}), from the plugins that give walls a pressure
        self.wall_forces: dict[str, tuple] = {}
        #: the contact impulses each moving group took during the current step
        self.contact_impulses: dict[str, list] = {}
        #: {group: (particle indices, weights)}: the particles a floating body's walls completed
        #: at the last evaluation of the rates and the body's share of each one's wall terms
        self.wall_members: dict[str, tuple] = {}
        #: the walls' impulse on each particle through the last solve's pressure (a scheme that
        #: solves for it sets it), None when the rates hold the walls' whole pressure
        self.solved_impulse: np.ndarray | None = None

    # -- the run state, by name ---------------------------------------------------------

    @property
    def state(self):
        return self.run.particles

    def host(self):
        """The particles as host numpy arrays, read-only: what a writer puts in its files
        (:meth:`sphcore.run.state.RunState.host`)."""
        return self.run.host()

    @property
    def planes(self):
        return self.planes_at(self.t)

    def planes_at(self, t: float):
        """The case's wall planes at time t (s): those of case.toml unless some move (the tank,
        a piston: :func:`sphcore.geometry.motion.planes_at`)."""
        if not self._plane_groups:
            return self.case.planes
        if self._planes_at[0] != t:
            self._planes_at = (t, planes_at(self.case.planes, self._plane_groups, t))
        return self._planes_at[1]

    @property
    def walls(self):
        """The wall planes (the same object as :attr:`planes`; kept for plugins written
        against earlier versions)."""
        return self.planes

    @property
    def t(self) -> float:
        return self.run.clock.t

    @t.setter
    def t(self, value: float):
        self.run.clock.t = value

    @property
    def step(self) -> int:
        return self.run.clock.step

    @step.setter
    def step(self, value: int):
        self.run.clock.step = value

    @property
    def dt(self) -> float:
        return self.run.clock.dt

    @dt.setter
    def dt(self, value: float):
        self.run.clock.dt = value

    @property
    def t_end(self) -> float:
        return self.run.clock.t_end

    @t_end.setter
    def t_end(self, value: float):
        self.run.clock.t_end = value

    @property
    def counters(self) -> Counter:
        return self.run.counters

    @property
    def force_pressure(self) -> np.ndarray:
        return self.state.p if self._pressure is None else self._pressure.force_pressure(self.state)

    @property
    def acc(self) -> np.ndarray:
        return self.run.rates.acc

    # -- per-plugin namespaces --------------------------------------------------------

    def stats(self, plugin) -> dict:
        """The figures of ``plugin`` (an instance, or its registered name): in the summary
        under that name, and in every checkpoint."""
        return self.run.stats.setdefault(plugin if isinstance(plugin, str) else self._name_of(plugin), {})

    def kept(self, plugin) -> dict:
        """State of ``plugin`` that a checkpoint keeps and a restart restores."""
        return self.run.kept.setdefault(plugin if isinstance(plugin, str) else self._name_of(plugin), {})

    def add_wall_load(self, group: str, impulse, angular_impulse) -> None:
        """Add what the fluid gave the walls of the moving group ``group`` (its name in
        ``case.moving``) during the current step: the momentum (N s; N s/m in 2D) and the
        angular momentum about the group's centre of rotation where it is (N m s; about z in
        2D: the third component), each as up to three components. Plugins whose walls take momentum from the fluid
        (reflective impulses, ghost or wall-model pressure forces times dt) add here; the
        ``wall_loads`` writer turns the sums into forces and moments. Kept across a restart."""
        acc = self.run.kept.setdefault("wall_impulses", {}).setdefault(group, [0.0] * 6)
        for k, v in enumerate(impulse):
            acc[k] += float(v)
        for k, v in enumerate(angular_impulse):
            acc[3 + k] += float(v)

    def set_wall_force(self, group: str, force, moment) -> None:
        """The fluid's force (N; N/m in 2D) and moment about the group's centre of rotation
        where it is (N m; about z in 2D: the third component) on the moving group ``group``
        at the rates just evaluated. A floating body takes it for its kicks; plugins whose
        walls carry a pressure set it at each evaluation."""
        self.wall_forces[group] = (np.asarray(force, float), np.asarray(moment, float))

    def add_contact_impulse(self, group: str, impulse, angular_impulse) -> None:
        """An impulse of the wall contacts of this step on ``group`` (N s, N m s): counted in
        the group's load (:meth:`add_wall_load`) and given to a floating body at once."""
        self.add_wall_load(group, impulse, angular_impulse)
        acc = self.contact_impulses.setdefault(group, [0.0] * 6)
        for k, v in enumerate(impulse):
            acc[k] += float(v)
        for k, v in enumerate(angular_impulse):
            acc[3 + k] += float(v)

    def _name_of(self, plugin) -> str:
        """The registered name of ``plugin``, looked up once per plugin (pluggy's lookup walks
        every registered plugin; the reflective walls ask on every step). The plugin is kept
        beside its name, so that its id is not reused while the entry exists."""
        entry = self._names.get(id(plugin))
        if entry is None:
            entry = self._names[id(plugin)] = (plugin, self._plugin_name(plugin))
        return entry[1]

    def all_stats(self) -> dict[str, dict]:
        """Every plugin's figures, by plugin name (only those that have any)."""
        return {name: dict(s) for name, s in self.run.stats.items() if s}
