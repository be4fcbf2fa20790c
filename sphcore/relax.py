"""A start at rest in the scheme's own equilibrium: dynamic relaxation before t = 0 (``[relax]``).

A tank filled on a square lattice with the exact hydrostatic pressure
(``physics.hydrostatic_init``) is in equilibrium in the continuum, not in the SPH sums: the
layers under the free surface start out of balance (their supports are cut by the surface),
and under plain Tait pressure the square lattice itself is an unstable equilibrium for most
smoothing lengths (``postprocessing/rest_stability.py``: exp(2.7 t) at h = 1.5 dx with
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
A column held by a gate that the case removes at t = 0 would collapse while it relaxes: such
a case is refused (``blocks[k].velocity`` set is refused as well: the relaxation ends at rest).
"""

from __future__ import annotations

import math

import numpy as np

from .errors import CaseError, Instability

JITTER_SEED = 20121  # the start's random velocities: the same relaxation on every machine


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


def settle(case, pm, state) -> dict:
    """Relax ``state`` (the case's particles as built, hydrostatic start applied) in place
    (module docstring); returns the figures for the summary."""
    from .simulation import Simulation  # the relaxation runs a Simulation of its own

    cfg = case.config["relax"]
    sim = Simulation(case, pm, relaxing=True)
    st, dx = sim.state, case.dx
    sim.ctx.t_end = cfg["time"]
    start = st.pos[np.argsort(st.id)].copy()
    rng = np.random.default_rng(JITTER_SEED)
    st.vel[:] += cfg["jitter"] * dx / cfg["damping_time"] * rng.uniform(-1.0, 1.0, st.vel.shape)
    sim.integrator.invalidate()
    first = True
    try:
        while not sim.done():
            sim.advance()
            if first:
                first = False
                steps = cfg["time"] / sim.dt
                if steps > case.config["time"]["max_steps"]:
                    raise CaseError(case.file, "relax.time", f"{cfg['time']:g} s of relaxation at a step of "
                                    f"{sim.dt:.3g} s needs {steps:.3g} steps, more than time.max_steps = "
                                    f"{case.config['time']['max_steps']}: expected a shorter relaxation")
            # the accelerations of the next step keep the undamped velocities' viscous part:
            # a fictitious dynamics whose only purpose is its end state
            st.vel *= math.exp(-sim.dt / cfg["damping_time"])
    except Instability as e:
        raise CaseError(case.file, "relax.time", f"the relaxation became unstable ({e}): expected water "
                        "at rest in its container; try a longer relax.damping_time or none") from None
    order = np.argsort(st.id)
    speed = float(np.sqrt(np.max(np.einsum("ij,ij->i", st.vel, st.vel), initial=0.0)))
    pos, rho = st.pos[order], st.rho[order]
    mine = np.argsort(state.id)
    if not np.array_equal(state.id[mine], st.id[order]):  # the same case builds the same particles
        raise RuntimeError("the relaxation's particles are not the run's")
    state.pos[mine] = pos
    state.rho[mine] = rho
    state.vel[mine] = 0.0
    moved = np.linalg.norm(pos - start, axis=1)
    return {"time_s": sim.t, "steps": sim.step, "damping_time_s": cfg["damping_time"], "jitter_dx": cfg["jitter"],
            "max_move_dx": float(moved.max() / dx) if moved.size else 0.0,
            "last_speed_m_s": speed}
