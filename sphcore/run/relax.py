"""A start at rest in the scheme's own equilibrium: dynamic relaxation before t = 0 (``[relax]``).

A tank filled on a square lattice with the exact hydrostatic pressure
(``physics.hydrostatic_init``) is in equilibrium in the continuum, not in the SPH sums: the
layers under the free surface start out of balance (their supports are cut by the surface),
and under plain Tait pressure the square lattice itself is an unstable equilibrium for most
smoothing lengths (``validation/hydrostatic_tank/rest_stability.py``: exp(2.7 t) at h = 1.5 dx with
ghosts), so that a run from it moves by a few particle spacings in seconds whatever the
walls. Dynamic relaxation (Day 1965, The Engineer 219, 218-221; Underwood 1983 in Belytschko
& Hughes (eds.), Computational Methods for Transient Analysis) finds the static equilibrium
of a discrete system by running its own dynamics with a damping force; as the start of an SPH
run it is the relaxation of Colagrossi et al. (2012, Comput. Phys. Commun. 183, 1641-1653,
"particle packing"), here with the run's own forces rather than a fictitious pressure, so
that the state it ends in is an equilibrium of the very equations the run integrates.

:func:`settle` runs a copy of the case (same particles, walls, plugins and physics) for
``relax.time`` seconds with every velocity multiplied by exp(-dt / ``relax.damping_time``)
after each step, starting from small random velocities (``relax.jitter``: about that many
dx of motion, seeded) that take the particles off a symmetric but unstable arrangement;
then it copies the positions and densities into the run's particles, at rest. The run's
t = 0 is that state: its gauges, probes and first frame see it. Masses are not changed.
What it did (how far the particles moved from the lattice, the last speed it removed) is
in the summary (``relax`` in the core's figures).

For water at rest in its container (a tank, the still start of a sloshing or wave case).
A column held by a gate that the case removes at t = 0 would collapse while it relaxes: a
relaxation in which a particle moves more than ``MOVE_LIMIT`` dx from where it started is
stopped and the case refused, as is a block given a velocity (the relaxation ends at rest).
The relaxation runs with plugins of its own (a second plugin manager, configured from the
same case), so that no plugin's state of the run is touched by it; it uses at most
``parallel.threads`` threads, as the run does. While it runs, the relaxation's particles and
work arrays exist beside the run's (built from the same case): the case's memory estimate
(``particles.memory_limit_gib``) counts one set, so a relaxed case near that limit may need
up to twice it.
"""

from __future__ import annotations

import math
import time

import numba
import numpy as np

from sphcore.errors import CaseError, Instability

JITTER_SEED = 20121  # the start's random velocities: the same relaxation on every machine
MOVE_LIMIT = 3.0  # dx: water at rest settles within a spacing or two; a collapsing column does not
MOVE_EVERY = 200  # steps between the checks of how far the particles moved


def check(case) -> None:
    """Refuse ``[relax]`` values that cannot settle the case (CaseError, exit 2)."""
    cfg = case.config["relax"]
    if cfg["time"] <= 0:
        return
    if not case.config["physics"]["sph"]:
        raise CaseError(case.file, "relax.time", "0 without SPH forces (physics.sph = false): there is no "
                        "equilibrium of the particles to relax to")
    for k, block in enumerate(case.config["blocks"]):
        v = block.get("velocity")
        if v is not None and any(x != 0.0 for x in v):
            raise CaseError(case.file, f"blocks[{k}].velocity", "unset (zero) with relax.time > 0: the relaxation "
                            "ends at rest and would discard the block's velocity")


def settle(case, state, simulation) -> dict:
    """Relax ``state`` (the case's particles as built, hydrostatic start applied) in place
    (module docstring); returns the figures for the summary. ``simulation(case)`` makes the
    relaxation's own run of the case (:func:`sphcore.run.build.build` with plugins of its
    own and ``relaxing=True``)."""
    cfg = case.config["relax"]
    clock = time.perf_counter()
    threads_before = numba.get_num_threads()
    if case.config["parallel"]["threads"]:
        numba.set_num_threads(min(threads_before, case.config["parallel"]["threads"]))
    try:
        sim = simulation(case)
        st, dx = sim.state, case.dx
        sim.ctx.t_end = cfg["time"]
        ids0 = np.sort(st.id)
        start = st.pos[np.argsort(st.id)].copy()
        rng = np.random.default_rng(JITTER_SEED)
        st.vel[:] += cfg["jitter"] * dx / cfg["damping_time"] * rng.uniform(-1.0, 1.0, st.vel.shape)
        sim.integrator.invalidate()
        while not sim.done():
            sim.advance()
            if sim.step == 1:
                steps = cfg["time"] / sim.dt
                if steps > case.config["time"]["max_steps"]:
                    raise CaseError(case.file, "relax.time", f"{cfg['time']:g} s of relaxation at a step of "
                                    f"{sim.dt:.3g} s needs {steps:.3g} steps, more than time.max_steps = "
                                    f"{case.config['time']['max_steps']}: expected a shorter relaxation")
            if sim.step % MOVE_EVERY == 0:
                moved = _largest_move(st, start) / dx
                if moved > MOVE_LIMIT:
                    raise CaseError(case.file, "relax.time", f"0 (off) for this case: a particle moved {moved:.3g} dx "
                                    f"within {sim.t:.3g} s of relaxation (more than {MOVE_LIMIT:g} dx): the "
                                    "water is not at rest in its container (a column held by a gate falls)")
            # the accelerations of the next step keep the undamped velocities' viscous part:
            # a fictitious dynamics whose only purpose is its end state
            st.vel *= math.exp(-sim.dt / cfg["damping_time"])
    except Instability as e:
        raise CaseError(case.file, "relax.time", f"the relaxation became unstable ({e}): expected water "
                        "at rest in its container; try a longer relax.damping_time or none") from None
    finally:
        numba.set_num_threads(threads_before)
    order = np.argsort(st.id)
    speed = float(np.sqrt(np.max(np.einsum("ij,ij->i", st.vel, st.vel), initial=0.0)))
    pos, rho = st.pos[order], st.rho[order]
    mine = np.argsort(state.id)
    if not (np.array_equal(state.id[mine], ids0) and np.array_equal(ids0, st.id[order])):
        raise RuntimeError("the relaxation's particles are not the run's (a plugin added particles?)")
    state.pos[mine] = pos
    state.rho[mine] = rho
    state.vel[mine] = 0.0
    return {"time_s": sim.t, "steps": sim.step, "damping_time_s": cfg["damping_time"], "jitter_dx": cfg["jitter"],
            "max_move_dx": _largest_move(st, start) / dx, "last_speed_m_s": speed,
            "wall_time_s": time.perf_counter() - clock}


def _largest_move(st, start) -> float:
    """Largest distance (m) of the particles from ``start`` (rows in id order)."""
    pos = st.pos[np.argsort(st.id)]
    return float(np.sqrt(np.max(np.einsum("ij,ij->i", pos - start, pos - start), initial=0.0)))
