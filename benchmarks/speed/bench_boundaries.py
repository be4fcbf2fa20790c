"""Cost and still-water accuracy of the wall treatments: ``ghost``, ``reflective`` and both.

    python benchmarks/speed/bench_boundaries.py [--sizes 10000 40000 160000] [--steps 20] [--case still|dambreak]
    python benchmarks/speed/bench_boundaries.py --accuracy [--relax-s 0.2] [--free-s 1.0]

Speed: the same 2D case for every mode (still water filling the tank bottom, or a
dam-break column in the left quarter of a tank), one fresh process per mode and size so
that the peak memory (max RSS) is that run's own. After one warm-up step (compilation,
caches), ``--steps`` full steps are timed; the table gives particle-steps per second
(fluid particles x steps / wall time) and the time spent in the boundary hooks:
``sph_extra_sources`` (ghost generation) and ``sph_after_integrate`` (reflection).

Accuracy (``--accuracy``): the 20 x 20 tank of tests/test_ghost_hydrostatic.py (0.2 m of
water, dx = 0.01 m, Wendland h = 1.5 dx, alpha = 0.1), per mode: the largest relative
pressure error below the top two layers against rho0 g (H - y) and the surface drift, after
0.2 s of dynamic relaxation (``--relax-s``) and over the 1 s free run that follows
(``--free-s``), and over 1 s from the core's hydrostatic start without relaxation.

Figures are printed, never asserted: run by hand on a quiet machine.
"""

from __future__ import annotations

import argparse
import json
import math
import resource
import shutil
import subprocess
import sys
import tempfile
import time
from collections import defaultdict
from pathlib import Path

import numpy as np

MODES = (("ghost",), ("reflective",), ("ghost", "reflective"))

CASE = """
[case]
dim = 2
[domain]
min = [0.0, 0.0]
max = [{w}, {hbox}]
[[blocks]]
min = [0.0, 0.0]
count = [{nx}, {ny}]
[particles]
dx = {dx}
[kernel]
h_over_dx = {h_over_dx}
[time]
t_end = 100.0
[viscosity]
alpha = 0.1
[plugins]
use = {plugins}
"""


def reflective_importable() -> tuple[bool, str]:
    from sphcore.plugin import pluginhost

    info = pluginhost.available().get("reflective")
    if info is None:
        return False, "not installed"
    return info.cls is not None, info.error


def write_case(n: int, plugins, case: str, h_over_dx: float = 1.3, dx: float = 0.01) -> Path:
    """Still water: a square block filling a tank as wide as it, twice as high.
    Dam break: a column twice as high as wide in the left quarter of a tank."""
    if case == "still":
        nx = int(round(math.sqrt(n)))
        ny = max(1, n // nx)
        w = nx * dx
    else:
        nx = int(round(math.sqrt(n / 2)))
        ny = max(1, n // nx)
        w = 4 * nx * dx
    d = Path(tempfile.mkdtemp(prefix="sphbench"))
    (d / "case.toml").write_text(CASE.format(w=w, hbox=2 * ny * dx, nx=nx, ny=ny, dx=dx, h_over_dx=h_over_dx,
                                             plugins=json.dumps(list(plugins))))
    return d


def load(case_dir: Path):
    """A Simulation of the case (no output directory); the temporary case is removed."""
    from sphcore.run import runner
    from sphcore.run.build import build

    try:
        return build(*runner.load(case_dir))
    finally:
        shutil.rmtree(case_dir, ignore_errors=True)


def measure_one(n: int, steps: int, plugins, case: str) -> dict:
    """Runs in its own process (see main): timings and that process's peak memory."""
    sim = load(write_case(n, plugins, case))
    hook_s = defaultdict(float)

    def timed(name, call):
        def wrapper(**kwargs):
            t = time.perf_counter()
            try:
                return call(**kwargs)
            finally:
                hook_s[name] += time.perf_counter() - t
        return wrapper

    sim.advance()  # compile and warm caches
    # timed on the run's hook relay, which the simulation and the forces share: a hook with
    # one implementation is called there directly, not through pluggy, so pluggy's
    # add_hookcall_monitoring would not see it (sphcore.plugin.pluginhost.HookRelay)
    for name in ("sph_extra_sources", "sph_after_integrate"):
        setattr(sim.hooks, name, timed(name, getattr(sim.hooks, name)))
    ghosts = []
    t0 = time.perf_counter()
    for _ in range(steps):
        sim.advance()
        ghosts.append(sim.forces.n_sources)
    wall = time.perf_counter() - t0
    return {"n": sim.state.n, "steps": steps, "wall_s": wall, "psps": steps * sim.state.n / wall,
            "ghosts": float(np.mean(ghosts)), "ghost_ms": 1e3 * hook_s["sph_extra_sources"] / steps,
            "reflect_ms": 1e3 * hook_s["sph_after_integrate"] / steps,
            "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def speed_table(sizes, steps, case):
    import numba

    ok, why = reflective_importable()
    print(f"full SPH step, 2D {case} water, {steps} timed steps, numba threads={numba.get_num_threads()}, "
          f"one process per row")
    if not ok:
        print(f"NOTE: rows with 'reflective' are skipped: the plugin is not importable ({why})")
    head = (f"{'mode':<18} {'fluid':>8} {'ghosts':>7} {'wall s':>8} {'particle-steps/s':>17} "
            f"{'us/p-step':>10} {'ghost ms/step':>14} {'reflect ms/step':>16} {'peak MB':>8}")
    print(head)
    print("-" * len(head))
    for n in sizes:
        for mode in MODES:
            name = "+".join(mode)
            if "reflective" in mode and not ok:
                print(f"{name:<18} {'skipped: reflective plugin not importable':>60}")
                continue
            out = subprocess.run([sys.executable, __file__, "--one", name, "--n", str(n), "--steps", str(steps),
                                  "--case", case], capture_output=True, text=True)
            if out.returncode != 0:
                print(f"{name:<18} FAILED: {out.stderr.strip().splitlines()[-1] if out.stderr else out.returncode}")
                continue
            r = json.loads(out.stdout.strip().splitlines()[-1])
            print(f"{name:<18} {r['n']:>8} {r['ghosts']:>7.0f} {r['wall_s']:>8.3f} {r['psps']:>17.3e} "
                  f"{1e6 / r['psps']:>10.3f} {r['ghost_ms']:>14.3f} {r['reflect_ms']:>16.3f} {r['peak_mb']:>8.0f}")


# ----------------------------------------------------------------------------------------
# still-water accuracy
# ----------------------------------------------------------------------------------------

TANK_NX = TANK_NY = 20
TANK_DX = 0.01
TANK_H = TANK_NY * TANK_DX  # free-surface height of the initial block (m)


def _still_water_figures(plugins, relax_s: float, free_s: float) -> dict:
    sim = load(write_case(TANK_NX * TANK_NY, plugins, "still", h_over_dx=1.5, dx=TANK_DX))

    def by_id():
        return sim.state.pos[np.argsort(sim.state.id)]

    def p_err():
        st = sim.state
        y = st.pos[:, 1]
        below = y < TANK_H - 2 * TANK_DX
        exact = sim.params.rho0 * np.linalg.norm(sim.params.gravity) * (TANK_H - y[below])
        return float(np.max(np.abs(st.p[below] - exact) / exact))

    while sim.t < relax_s:
        sim.advance()
        sim.state.vel *= 0.98  # dynamic relaxation
    ref = by_id()
    top = ref[:, 1] > TANK_H - TANK_DX
    t0, err, drift, clearance = sim.t, p_err(), 0.0, np.inf
    while sim.t < t0 + free_s:
        sim.advance()
        if sim.step % 10 == 0:
            err = max(err, p_err())
            drift = max(drift, abs(by_id()[top, 1].mean() - ref[top, 1].mean()))
        clearance = min(clearance, float(sim.case.planes.distances(sim.state.pos).min()))
    return {"p_err": err, "drift_dx": drift / TANK_DX, "clearance_dx": clearance / TANK_DX}


def accuracy_table(relax_s: float = 0.2, free_s: float = 1.0):
    ok, why = reflective_importable()
    print(f"still water, {TANK_NX} x {TANK_NY} particles, H = {TANK_H} m, dx = {TANK_DX} m, Wendland h = 1.5 dx, "
          f"alpha = 0.1, leapfrog; pressure error below the top two layers vs rho0 g (H - y)")
    head = f"{'mode':<18} {'start':<26} {'max |dp|/p':>11} {'surface drift':>14} {'min wall dist':>14}"
    print(head)
    print("-" * len(head))
    for mode in MODES:
        name = "+".join(mode)
        if "reflective" in mode and not ok:
            print(f"{name:<18} skipped: reflective plugin not importable ({why})")
            continue
        for label, relax in ((f"relaxed {relax_s:g} s, then {free_s:g} s", relax_s),
                             (f"hydrostatic start, {free_s:g} s", 0.0)):
            r = _still_water_figures(mode, relax, free_s)
            print(f"{name:<18} {label:<26} {100 * r['p_err']:>10.2f}% {r['drift_dx']:>12.4f}dx "
                  f"{r['clearance_dx']:>12.4f}dx")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10_000, 40_000, 160_000])
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--case", choices=("still", "dambreak"), default="still")
    ap.add_argument("--accuracy", action="store_true", help="print the still-water accuracy table instead")
    ap.add_argument("--relax-s", type=float, default=0.2, help="with --accuracy: dynamic relaxation (s)")
    ap.add_argument("--free-s", type=float, default=1.0, help="with --accuracy: the free run measured (s)")
    ap.add_argument("--one", help=argparse.SUPPRESS)  # internal: one measurement in this process
    ap.add_argument("--n", type=int, help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one:
        print(json.dumps(measure_one(a.n, a.steps, a.one.split("+"), a.case)))
    elif a.accuracy:
        accuracy_table(a.relax_s, a.free_s)
    else:
        speed_table(a.sizes, a.steps, a.case)


if __name__ == "__main__":
    main()
