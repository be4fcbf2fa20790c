"""Hook specifications: every point where a plugin can act, grouped by lifecycle phase.

A plugin is a class registered under the entry-point group ``sphcore``; one instance is
created per run and only for the plugins a case names in ``[plugins] use``. Hooks fire
between kernel calls, once per run, step or stage: never once per particle. A hook
implementation whose name is not specified here is an error at start-up.

Arguments are passed by keyword; an implementation may accept any subset of them.
``ctx`` is the run context, :class:`sphcore.plugin.context.RunContext`; its docstring lists every
attribute: ``ctx.state`` (particles), ``ctx.params`` (constants), ``ctx.walls`` (wall
planes), ``ctx.case`` (validated configuration), the clock ``ctx.t``, ``ctx.step``,
``ctx.dt``, ``ctx.t_end``, ``ctx.output_dir``, ``ctx.restarting``,
``ctx.force_pressure``, ``ctx.acc``, ``ctx.counters``, and the plugin's own namespaces
``ctx.stats(self)`` (figures merged into summary.json under the plugin's name, kept across
restarts) and ``ctx.kept(self)`` (state kept across restarts). Everything a plugin needs
to import is in :mod:`sphcore.api`.
"""

from __future__ import annotations

import pluggy

PROJECT = "sphcore"
hookspec = pluggy.HookspecMarker(PROJECT)
hookimpl = pluggy.HookimplMarker(PROJECT)


# --------------------------------------------------------------------------------------
# Set-up: once per run, before the first step
# --------------------------------------------------------------------------------------


@hookspec
def sph_options():
    """Declare the case tables this plugin reads.

    Fires while the case is loaded, before validation. Return
    ``{table_name: {key: sphcore.case.options.Option}}``; the host validates the case's tables
    against it (unknown key, wrong type are errors naming file and key) and fills defaults.
    An option declared with ``restart=True`` may change on ``--restart`` (it changes how
    the run reports, not what it computes); any other change of the case is refused there.
    """


@hookspec
def sph_configure(case):
    """Read and check this plugin's validated options.

    Fires once after the whole case is validated, before any particle exists.
    ``case.config[table]`` holds the plugin's table with defaults filled in. Raise
    :class:`sphcore.errors.CaseError` for values that are valid alone but not together
    (e.g. planes that bound no region). May not change the case.
    """


@hookspec
def sph_setup(ctx):
    """Prepare for the run with the initial particles in place.

    Fires once after the particles are built and before the first force computation.
    May add particles (``ctx.state.append``; only when ``not ctx.restarting``: a checkpoint
    already holds them), allocate work arrays, and check the initial state against its own
    geometry (raise CaseError, e.g. a particle outside a wall).
    """


# --------------------------------------------------------------------------------------
# Forces: once per force evaluation
# --------------------------------------------------------------------------------------


@hookspec
def sph_before_forces(ctx):
    """Adjust the fields that feed a force evaluation.

    Fires at the start of every force evaluation, after the equation of state and before
    extra sources and the neighbour search. May change ``ctx.force_pressure`` and ``ctx.state.rho``
    (e.g. hold free-surface particles at zero pressure, filter the density); must not move
    particles. Under ``dfsph`` the pairs and the wall terms of the state may already have been
    taken when it fires (the scheme lists its pairs before its rates).
    """


@hookspec
def sph_extra_sources(ctx):
    """Return extra *source* particles for this force evaluation, or None.

    Fires before the neighbour search of every force evaluation. The result is a
    :class:`sphcore.physics.particles.Sources` (positions, velocities, densities, pressures,
    masses) that takes part in continuity and momentum as neighbours only: sources are
    never integrated or written as fluid. This is how ghost (mirror) particles enter.
    """


@hookspec
def sph_wall_terms(ctx, terms):
    """Add this plugin's walls to the per-particle boundary-integral terms, in place.

    Fires in every force evaluation after the neighbour search, before the pair sums, and
    only when some plugin implements it; under the incompressible scheme (``dfsph``) once
    per state: an evaluation at the positions, particle order and time of the last one
    reuses its terms, so a plugin's terms must depend on those alone there (its force
    pressure is zero). ``terms`` is a
    :class:`sphcore.physics.equations.WallTerms` of arrays zeroed by the core: ``terms.share`` (n,)
    the wall's share of each particle's kernel support, ``terms.grad`` (n, dim) its
    gradient (1/m, towards the wall), ``terms.hydro`` (n, dim) the hydrostatic moment of the
    wall pressure (m/s^2), ``terms.normals`` (n, dim, dim) the projector onto the normals of
    the walls within each particle's support, ``terms.fill`` (n,) the neighbour sum
    sum_j V_j W_ij a particle of the initial lattice has at that place (the core scales the
    completion by the particle's own sum over it; leave 0 for no scaling). Add (``+=``) what
    your walls contribute to share, grad, hydro and fill, and widen the projector to your
    walls' normals, so that several wall plugins combine. The core then completes the
    continuity and momentum sums with them through the function that a plugin returns from
    ``sph_wall_completion``. In a run with moving walls ``terms.flux`` (n,) and
    ``terms.accel`` (n, dim) are allocated too (empty otherwise): add v_w . G of your walls'
    velocity and their gradient, and the outside first moment of minus their acceleration.
    """


@hookspec
def sph_wall_completion(dim):
    """Return the compiled function that adds the wall terms to a particle's rates, or None.

    Fires once per run, when the core sets up its force evaluation (only if some plugin
    implements ``sph_wall_terms``). A plugin that implements ``sph_wall_terms`` says here how its terms enter the SPH
    equations. The core compiles the function into its pair loop (inlined: it runs once
    per particle near a wall, after the particle's pairs) for a ``dim``-dimensional run;
    every plugin that returns one must return the same function. The function is a numba
    ``@njit(inline="always")`` function

        complete(wall, i, dim, vel, rho_i, p_i, rho_ref, lam, gravity,
                 a0, a1, a2, dr, b0, b1, b2, gamma) -> (a0, a1, a2, dr)

    of the particle's :class:`sphcore.physics.equations.WallTerms` ``wall`` (row ``i``), the
    velocities ``vel``, the particle's density and pressure, the reference density
    (:attr:`Params.rho_ref`), the lattice normalisation ``lam`` (:attr:`Params.moment_norm`)
    and gravity; (a0, a1, a2, dr) are the particle's acceleration and density rate from its
    pairs, (b0, b1, b2) the sum sum_j V_j (x_ij . g) grad W_ij (the discrete first moment of
    its support applied to g, B g), and ``gamma`` its neighbour sum sum_j V_j W_ij (self
    excluded); the pair loop sums both for particles with ``wall.share > 0`` only. It returns
    the completed rates. The wall_integral plugin's
    :func:`sphcore_plugins.wall_integral.completion.complete_at_wall` is the example.
    Numba caches the pair loop under a name derived from the function's module, name and
    bytecode, so an edited completion is compiled afresh.
    """


@hookspec
def sph_moving_walls():
    """Return True when this plugin honours walls that move (``case.moving``).

    Fires once per run, after ``sph_configure``, and only for a case whose walls move. A
    case whose walls move (``[[domain.motion]]``, ``[[domain.walls.motion]]``) runs only
    with plugins that say so, unless a plugin acts on the output alone (it implements no
    hook but sph_options, sph_configure, sph_output, sph_summary and sph_finish): a plugin
    written for fixed walls would otherwise act on walls that are no longer where it thinks.
    A plugin that returns True reads each moving group's pose at any time from
    ``case.moving[k].motion.pose(t)`` (:mod:`sphcore.geometry.motion`).
    """


@hookspec
def sph_accelerations(ctx, acc):
    """Add accelerations to ``acc`` (shape (n, dim), m/s^2) in place.

    Fires after the core rates (pressure, viscosity, gravity) of every force evaluation.
    Accelerations may do work on the fluid: unless the plugin also implements
    ``sph_energy``, the core's energy-growth check is switched off and the summary says why.
    """


@hookspec
def sph_energy(ctx):
    """Return the energy (J, J/m in 2D) this plugin's forces store, or None.

    Fires whenever the core checks total energy. A plugin whose accelerations are
    conservative (a potential) returns its potential energy; the core's energy-growth
    check then stays on.
    """


# --------------------------------------------------------------------------------------
# Integration: once per step
# --------------------------------------------------------------------------------------


@hookspec
def sph_after_integrate(ctx, pos0, pos, vel, acc, dt):
    """Correct positions and velocities after the free-motion update of a step.

    Fires once per step, right after the integrator moved every particle from ``pos0``
    (start of the step) to ``pos`` with no walls present. ``vel`` is the velocity at the
    end of the step, ``acc`` the acceleration used for the step, ``dt`` the step (s).
    May change ``pos`` and ``vel`` in place (this is where the reflective boundary acts);
    must not change ``pos0`` or ``acc``. The integrator keeps its later stages consistent
    with the corrected values. Invariant: ``pos0`` is admissible (inside every wall), because
    nothing moves particles between the end of one step and the start of the next.
    """


@hookspec
def sph_after_step(ctx):
    """Inspect the state after a complete step: checks, counters, diagnostics.

    Fires once per step after the core checks. May raise
    :class:`sphcore.errors.Instability` to stop the run; may update ``ctx.stats(self)``.
    Must not change particle data.
    """


@hookspec
def sph_max_dt(ctx):
    """Return an upper bound on the next time step (s), or None for no limit.

    Fires once per step before the step size is chosen; the smallest bound wins.
    """


# --------------------------------------------------------------------------------------
# Output and end of run
# --------------------------------------------------------------------------------------


@hookspec
def sph_output(ctx, final):
    """Write output if this writer's schedule says so.

    Fires after the set-up (``ctx.step == 0``, unless the run restarts from a checkpoint),
    after every step, and once more with ``final=True`` when the run reaches its end or is
    stopped by a signal. After an instability it does not fire again, so the files keep the
    last good frame. Each writer owns its schedule, files and directory layout below
    ``ctx.output_dir``; ``ctx.restarting`` tells it to append to what is there. Must not
    change particle data. :class:`sphcore.api.ScheduledWriter` does the bookkeeping.
    """


@hookspec
def sph_summary(ctx):
    """Return a dict of figures for the run summary, or None.

    Fires once at the end of the run, before ``sph_finish``. The figures are merged with
    ``ctx.stats(self)`` and written to summary.json under the plugin's name.
    """


@hookspec
def sph_finish(ctx):
    """Release resources (close files). Fires once at the end of every run, also a failed one."""
