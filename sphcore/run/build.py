"""The build: a case becomes a simulation ready to step.

    build(case, pm) : particles from the blocks -> constants (Params) -> hydrostatic start
                      -> relaxed start (``[relax]``) or the checkpoint (``--restart``)
                      -> run state -> Simulation (plugins set up, rates sized)

Everything that reads the case to make the run's first state is here; the
:class:`sphcore.run.simulation.Simulation` only wires the run state to the physics and the
plugins. The relaxation (:mod:`sphcore.run.relax`) runs before the run's Simulation
exists, on a Simulation of its own built by this module.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sphcore.errors import CaseError
from sphcore.jit import prepare
from sphcore.physics import eos
from sphcore.physics.params import derive
from sphcore.physics.particles import FLUID, SPHERE, ParticleState, lattice, make_block
from sphcore.plugin import pluginhost
from sphcore.run import checkpoint, relax
from sphcore.run.simulation import CORE, Simulation
from sphcore.run.state import RunState

KIND_CODES = {"fluid": FLUID, "sphere": SPHERE}  # case.toml block kind -> state.kind
INSIDE_TOL = 1e-9  # relative to the radius: a particle at d = r - ulp still counts as inside


def build(case, pm, output_dir: Path | None = None, restarting: bool = False, relaxing: bool = False,
          settle: bool = True) -> Simulation:
    """A Simulation of ``case`` with the plugins of ``pm``, set up and ready to step.

    ``output_dir``: where the writers write (None: no output); ``restarting``: continue from
    the checkpoint in ``output_dir``; ``relaxing``: the relaxation's own run (no relaxed start
    of its own, no ``sph_after_step``); ``settle=False`` leaves out the relaxed start, which
    only a run does (``sph check`` sizes the first step without it). Arithmetic that fails on
    the case's values (an overflow, a division by zero) is reported as a CaseError.
    """
    prepare()
    try:
        return _build(case, pm, output_dir, restarting, relaxing, settle)
    except ArithmeticError as e:
        raise CaseError(case.file, "-", f"setting up the particles failed on {type(e).__name__} ({e}): expected "
                        "values of a physical size") from None


def _build(case, pm, output_dir, restarting, relaxing, settle) -> Simulation:
    cfg = case.config
    particles = build_state(case)
    surface, tops = 0.0, None
    if cfg["physics"]["sph"] and np.linalg.norm(case.gravity) > 0:
        tops = block_tops(case, particles)
        surface = float(tops.max())  # hydrostatic reference of the modified pressure (m)
    prm = derive(case, particles, surface)
    if tops is not None and cfg["physics"]["hydrostatic_init"] and not prm.modified_pressure:
        if cfg["scheme"]["name"] == "dfsph":
            _incompressible_start(prm, particles, tops)
        else:
            _hydrostatic_start(case, prm, particles, tops)
    run = RunState(particles, cfg["time"]["t_end"])
    if restarting:  # constants above come from the case's initial particles, as in the first run
        try:
            run.load_payload(*checkpoint.read(output_dir))
        except (KeyError, ValueError) as e:
            raise CaseError(Path(output_dir) / checkpoint.NAME, "--restart", f"not a checkpoint of this run ({e})") \
                from None
    elif settle and not relaxing and cfg["relax"]["time"] > 0:
        # positions and densities at rest in the scheme's equilibrium, before t = 0
        run.stats.setdefault(CORE, {})["relax"] = relax.settle(case, particles, _relaxation)
    return Simulation(case, pm, prm, run, output_dir, restarting=restarting, relaxing=relaxing)


def _relaxation(case) -> Simulation:
    """The relaxation's own run of ``case``: plugins of its own (a second plugin manager,
    configured from the same case), so that no plugin state of the run is touched by it."""
    pm = pluginhost.make_manager(case.config["plugins"]["use"], case.file)
    pluginhost.configure(pm, case)
    return build(case, pm, relaxing=True)


def block_positions(case, k, b):
    """Centres of block k: its lattice, less the particles a finite wall removes (closer
    than a radius to a face, or in a solid) and, with ``clip``, those beyond a wall plane;
    (positions, removed count). Without ``clip`` a centre beyond a wall plane is an error
    naming the block."""
    dx, r = case.dx, case.radius
    pos = lattice(b["min"], b["max"], dx, b["count"])
    if pos.shape[0] == 0:
        raise CaseError(case.file, f"blocks[{k}]", f"the block holds no particle at dx = {dx} m")
    d = case.planes.distances(pos)
    clipped = 0
    if b["clip"] and d.size:
        inside = (d >= r * (1.0 - INSIDE_TOL)).all(axis=1)
        if not inside.any():
            raise CaseError(case.file, f"blocks[{k}].clip", "every particle of the block lies beyond a wall plane")
        clipped = int(pos.shape[0] - inside.sum())
        pos, d = pos[inside], d[inside]
    bad = np.argwhere(d < r * (1.0 - INSIDE_TOL))
    if bad.size:
        i, p = bad[0]
        if case.config["particles"]["radius"] is not None and d[i, p] >= 0.5 * dx * (1.0 - INSIDE_TOL):
            # inside the walls with the default radius dx/2: the radius set is what pushes it out
            raise CaseError(case.file, "particles.radius", f"{r:g} m puts the particle at {pos[i].round(9).tolist()} "
                            f"of blocks[{k}] within a radius of wall plane {p} (distance {d[i, p]:.6g} m): expected "
                            "a radius of about dx/2, smaller than the particles' distance to the walls")
        raise CaseError(case.file, f"blocks[{k}]", f"particle at {pos[i].round(9).tolist()} is outside wall plane {p} "
                        f"(distance {d[i, p]:.6g} m < radius {r:.6g} m){_rounding_hint(k, b, dx, pos[i])}")
    if case.faces.count == 0:
        return np.ascontiguousarray(pos), clipped
    keep = (case.faces.distances(pos) >= r * (1.0 - INSIDE_TOL)) & case.faces.in_fluid(pos)
    if not keep.any():
        raise CaseError(case.file, f"blocks[{k}]", "every particle of the block lies in a solid wall or "
                        "closer than a radius to a wall face")
    return np.ascontiguousarray(pos[keep]), clipped + int(pos.shape[0] - keep.sum())


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
    """Particles of every [[blocks]] entry; each must lie inside every wall plane (or, with
    ``clip``, is left out), and those a finite wall covers are not created
    (``state.removed_by_walls`` counts both)."""
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




def _hydrostatic_start(case, prm, st, tops):
    """Each fluid block at rest in the discrete equilibrium of the SPH sums: the exact
    hydrostatic pressure of the Tait fluid below the block's top
    (:func:`sphcore.physics.eos.hydrostatic_pressure`), the density from the inverse Tait equation,
    and the mass of each particle scaled by rho / rho0, since the particles stand on a
    uniform lattice: the fluid's extra mass at depth is in the masses, not in a closer
    spacing.

    Why the masses carry the stratification: with the pressure rho0 g d and equal masses
    rho0 dx^dim, the pressure sums of a uniform lattice see the density stratification only
    through the p_j / rho_j^2 of the momentum equation. In a 1 m tank of plain Tait water at
    h = 1.5 dx the interior's vertical acceleration then drifts from -0.004 g under the free
    surface to -0.018 g at the bottom, and a particle along a side wall differs from its
    interior neighbours by up to 0.004 g (a shear the wall's terms do not carry). With this
    start both are -0.0026 g everywhere below the free surface's reach ((lambda - 1) g, the
    lattice normalisation), walls included (``tests/test_hydrostatic_start.py``).
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


def _incompressible_start(prm, st, tops):
    """Each fluid block at rest under the divergence-free scheme: density rho0 and masses
    rho0 dx^dim (the fluid does not compress), the pressure rho0 g d below the block's top,
    which the first step's density solve starts from."""
    fluid = st.kind == FLUID
    st.p[fluid] = prm.rho0 * prm.g_abs * (tops[fluid] - st.pos[fluid] @ prm.up)
    st.rho[fluid] = prm.rho0

