"""What a case will cost, known before anything is allocated: the particle count and memory
(refused with the numbers when they exceed the machine), and the first time step (refused
when it cannot advance the clock or would need an absurd number of steps).

``sph check`` and ``sph run`` both call :func:`check_scales` and :func:`check_memory` (in
``runner.load``), build the simulation (:func:`sphcore.run.build.build`) and call
:func:`check_first_step` (before the output directory is touched), so whatever ``check``
accepts, ``run`` starts.
"""

from __future__ import annotations

import math
import os

import numpy as np

from sphcore.case import defaults
from sphcore.errors import CaseError

#: bytes per particle and dimension: the state (pos, vel, rho, p, m, radius, kind, id), the
#: integrator's work arrays (acc, pos0, acc_old, drho, drho_old, p_dyn, L, shepard), the
#: cell list, a writer's copy of a frame and plugin sources (ghosts). Measured: the 2D dam
#: break with reflective walls peaks at 190 MB with 125,000 particles and 273 MB with
#: 500,000, i.e. ~230 B per particle; 250 B per dimension (500 B in 2D) leaves room for
#: ghosts and writers, and still refuses only what is clearly too large.
BYTES_PER_PARTICLE_PER_DIM = 250
#: the interpreter with numpy, numba, vtk and netCDF loaded (bytes; ~280 MB measured)
BASELINE_BYTES = 300 << 20


#: largest gravity component accepted (m/s^2): 10^5 g, far beyond any case, far below overflow
MAX_GRAVITY = 1e6


def block_counts(case) -> list[float]:
    """Particles of each [[blocks]] entry (floats: a bad case may ask for 10^30)."""
    counts = []
    for b in case.blocks:
        if b["count"] is not None:
            n = math.prod(float(c) for c in b["count"])
        else:
            n = math.prod(max(0.0, float(round((hi - lo) / case.dx))) for lo, hi in zip(b["min"], b["max"]))
        counts.append(n)
    return counts


def available_bytes() -> float:
    """Memory this process may use: MemAvailable of /proc/meminfo, else physical memory."""
    try:
        with open("/proc/meminfo") as f:
            for line in f:
                if line.startswith("MemAvailable:"):
                    return float(line.split()[1]) * 1024
    except OSError:
        pass
    try:
        return float(os.sysconf("SC_PHYS_PAGES") * os.sysconf("SC_PAGE_SIZE"))
    except (ValueError, OSError, AttributeError):
        return math.inf


def estimate(case) -> tuple[float, float]:
    """(particles, bytes) the case needs."""
    n = sum(block_counts(case))
    return n, BASELINE_BYTES + n * BYTES_PER_PARTICLE_PER_DIM * case.dim


def check_scales(case) -> None:
    """Refuse values whose combination leaves the float range before a step is taken: the
    Tait equation and its energy use rho0^gamma."""
    g = case.config["physics"]["gravity"]
    if not all(abs(x) <= MAX_GRAVITY for x in g):
        raise CaseError(case.file, "physics.gravity", f"expected components of at most {MAX_GRAVITY:g} m/s^2 in size, "
                        f"got {g}")
    rho0, gamma = case.config["fluid"]["rho0"], case.config["eos"]["gamma"]
    try:
        r = rho0 ** gamma
    except OverflowError:
        r = math.inf
    if not 0.0 < r < math.inf or not 0.0 < rho0 ** (gamma - 1.0) < math.inf:
        raise CaseError(case.file, "fluid.rho0", f"rho0^gamma = {rho0:g}^{gamma:g} leaves the float range: expected "
                        "a reference density nearer 1 (or a smaller eos.gamma)")


def check_memory(case) -> None:
    """Refuse a case that needs more memory than the machine has (or particles.memory_limit_gib)."""
    n, need = estimate(case)
    limit_gib = case.config["particles"]["memory_limit_gib"]
    limit = available_bytes() if limit_gib is None else limit_gib * 2.0**30
    for k, c in enumerate(block_counts(case)):
        if c < 1:
            raise CaseError(case.file, f"blocks[{k}]", f"the block holds no particle at dx = {case.dx} m")
    if need > limit:
        counts = block_counts(case)
        big = max(range(len(counts)), key=counts.__getitem__)
        key = f"blocks[{big}].count" if case.blocks[big]["count"] is not None else "particles.dx"
        where = ("particles.memory_limit_gib" if limit_gib is not None
                 else "the memory available (set particles.memory_limit_gib to override)")
        raise CaseError(case.file, key, f"dx = {case.dx:g} m gives {n:.3g} particles needing about "
                        f"{need / 2.0**30:.3g} GiB, more than {limit / 2.0**30:.3g} GiB, {where}; "
                        "expected fewer particles (a larger dx or smaller blocks)")


def _rates_at_start(sim) -> tuple[float, float]:
    """(first step's size (s) as the run chooses it, largest |a| (m/s^2)): the rates at the
    initial state, then ``choose_dt``. The run state is put back afterwards
    (:meth:`sphcore.run.simulation.Simulation.snapshot`), so the run that follows takes exactly
    the steps it would have taken without this look-ahead."""
    snap = sim.snapshot()
    integ = sim.integrator
    try:
        integ.invalidate()
        integ.rates()
        if not np.all(np.isfinite(integ.acc)) or not np.all(np.isfinite(integ.drho)):
            raise CaseError(sim.case.file, "-", "the forces at t = 0 are not finite: expected physics.gravity, eos, "
                            "viscosity and density_diffusion values of a physical size")
        return sim.choose_dt(), float(np.sqrt(np.max(np.einsum("ij,ij->i", integ.acc, integ.acc), initial=0.0)))
    finally:
        sim.restore(snap)


def _binding_limit(sim, amax: float) -> str:
    """The case key behind the smallest adaptive limit (see :mod:`sphcore.physics.timestep`)."""
    tcfg = sim.case.config["time"]
    vmax = float(max((math.sqrt(sum(v * v for v in row)) for row in sim.state.vel.tolist()), default=0.0))
    prm = sim.params
    limits = {"time.cfl": tcfg["cfl"] * prm.h / (prm.c0 + vmax) if prm.c0 + vmax > 0 else math.inf,
              "time.force_factor": tcfg["force_factor"] * math.sqrt(prm.h / amax) if amax > 0 else math.inf,
              "fluid.nu": tcfg["viscous_factor"] * prm.h ** 2 / prm.nu if prm.nu > 0 else math.inf}
    return min(limits, key=limits.get)


def check_first_step(sim) -> float:
    """The first step's size (s); a CaseError when nothing limits it, when the forces at the
    start are not finite, when it is below the round-off of t_end, or when reaching t_end
    would take more than time.max_steps steps.

    A fresh run evaluates the rates at its initial state (as its first step will); a
    restart has its rates from the checkpoint and is sized from them.
    """
    case = sim.case
    tcfg = case.config["time"]
    if sim.done():  # a restart of a finished run: nothing to step
        return 0.0
    key = "time.dt" if tcfg["dt"] is not None else "time.dt_max" if tcfg["dt_max"] is not None else "time.cfl"
    if sim.step == 0:
        dt, amax = _rates_at_start(sim)
    else:
        dt, amax = sim.choose_dt(), None
    if tcfg["dt"] is None and tcfg["dt_max"] is None and amax is not None:
        key = _binding_limit(sim, amax)
    if not math.isfinite(dt) or not dt > 0:
        raise CaseError(case.file, "time.dt", "required: no sound speed, velocity or force limits the step")
    t_end = sim.t_end
    if t_end + dt <= t_end or sim.t + dt <= sim.t:
        # a step of a physical size lost in the round-off of t: the end time is what is too far
        blame = "time.t_end" if dt >= MIN_PLAIN_STEP else key
        raise CaseError(case.file, blame, f"the time step {dt:.3g} s is below the round-off of t = {t_end:g} s: "
                        "time would not advance (expected a shorter time.t_end or a longer step)")
    steps = (t_end - sim.t) / dt
    if steps > tcfg["max_steps"]:
        blame, what = _step_count_key(case, key)
        raise CaseError(case.file, blame, f"{what}a time step of {dt:.3g} s needs {steps:.3g} steps to reach "
                        f"time.t_end = {t_end:g} s, more than time.max_steps = {tcfg['max_steps']}")
    return dt


#: a time step (s) below which a step that cannot advance t is blamed on the step, not on t_end
MIN_PLAIN_STEP = 1e-12


def _step_count_key(case, key: str) -> tuple[str, str]:
    """(key, opening words) for a run needing too many steps: the sound speed when the
    acoustic limit binds and the case raised it, else the limit's own key, else time.t_end."""
    ecfg = case.config["eos"]
    if key == "time.cfl":
        if ecfg["c0"] is not None:
            return "eos.c0", f"c0 = {ecfg['c0']:g} m/s: "
        if ecfg["c0_factor"] != defaults.CORE["eos"]["c0_factor"].default:
            return "eos.c0_factor", f"c0_factor = {ecfg['c0_factor']:g}: "
        return "time.t_end", ""
    return key, ""
