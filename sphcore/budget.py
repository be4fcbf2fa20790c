"""What a case will cost, known before anything is allocated: the particle count and memory
(refused with the numbers when they exceed the machine), and the first time step (refused
when it cannot advance the clock or would need an absurd number of steps).

``sph check`` and ``sph run`` both call :func:`check_memory` (in ``runner.load``) and
:func:`check_first_step` (after the particles are built, before the output directory is
touched), so whatever ``check`` accepts, ``run`` starts.
"""

from __future__ import annotations

import math
import os

from .errors import CaseError

#: bytes per particle and dimension: the state (pos, vel, rho, p, m, radius, kind, id), the
#: integrator's work arrays (acc, pos0, acc_old, drho, drho_old, p_dyn, L, shepard), the
#: cell list, a writer's copy of a frame and plugin sources (ghosts). Measured: the 2D dam
#: break with reflective walls peaks at 190 MB with 125,000 particles and 273 MB with
#: 500,000, i.e. ~230 B per particle; 250 B per dimension (500 B in 2D) leaves room for
#: ghosts and writers, and still refuses only what is clearly too large.
BYTES_PER_PARTICLE_PER_DIM = 250
#: the interpreter with numpy, numba, vtk and netCDF loaded (bytes; ~280 MB measured)
BASELINE_BYTES = 300 << 20


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


def check_first_step(sim) -> float:
    """The first step's size (s), estimated as the run will choose it; a CaseError when none
    limits it, when it is below the round-off of t_end, or when reaching t_end would take
    more than time.max_steps steps."""
    case = sim.case
    tcfg = case.config["time"]
    key = "time.dt"
    if tcfg["dt"] is not None:
        dt = tcfg["dt"]
    else:
        from .timestep import adaptive_dt, max_norms

        # before any rates, gravity is the only acceleration known
        vmax, _ = max_norms(sim.state.vel, sim.state.vel)
        dt = adaptive_dt(sim.h, sim.c0, sim.nu, vmax, sim.g_abs, tcfg["cfl"], tcfg["force_factor"],
                         tcfg["viscous_factor"])
        if tcfg["dt_max"] is not None:
            dt = min(dt, tcfg["dt_max"])
            key = "time.dt_max"
        else:
            key = "time.cfl"
    bounds = [b for b in sim.pm.hook.sph_max_dt(sim=sim) if b is not None]
    if bounds:
        dt = min(dt, min(bounds))
    if not math.isfinite(dt) or not dt > 0:
        raise CaseError(case.file, "time.dt", "required: no sound speed, velocity or force limits the step")
    t_end = sim.t_end
    if t_end + dt <= t_end or sim.t + dt <= sim.t:
        raise CaseError(case.file, key, f"the time step {dt:.3g} s is below the round-off of t = {t_end:g} s: "
                        "time would not advance")
    steps = (t_end - sim.t) / dt
    if steps > tcfg["max_steps"]:
        raise CaseError(case.file, key, f"a time step of {dt:.3g} s needs {steps:.3g} steps to reach "
                        f"time.t_end = {t_end:g} s, more than time.max_steps = {tcfg['max_steps']}")
    return dt
