"""Particle-steps per second of a full SPH step (neighbours, rates, integration) on a 2D
block of water at rest in a box, at several sizes, with peak memory and the share of the
step spent in the boundary hook (sph_after_integrate: the reflective kernel).

    python benchmarks/speed/bench_step.py [--sizes 10000 100000 1000000] [--steps 20] [--plugins reflective]

Figures are printed, never asserted: run by hand on a quiet machine.
"""

from __future__ import annotations

import argparse
import math
import resource
import shutil
import tempfile
import time
from pathlib import Path

from sphcore.run import runner
from sphcore.run.build import build

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
[time]
t_end = 1.0
[viscosity]
alpha = 0.1
[plugins]
use = {plugins}
"""


def make_case(n: int, plugins) -> Path:
    nx = int(round(math.sqrt(n)))
    ny = max(1, n // nx)
    dx = 0.01
    d = Path(tempfile.mkdtemp(prefix="sphbench"))
    (d / "case.toml").write_text(CASE.format(w=nx * dx, hbox=2 * ny * dx, nx=nx, ny=ny, dx=dx,
                                             plugins=list(plugins)).replace("'", '"'))
    return d


def load_case(n: int, plugins, overrides=()):
    """(case, plugin manager) of ``make_case``'s block; the temporary case directory is removed."""
    d = make_case(n, plugins)
    try:
        return runner.load(d, list(overrides))
    finally:
        shutil.rmtree(d, ignore_errors=True)


def measure(n: int, steps: int, plugins) -> dict:
    case, pm = load_case(n, plugins)
    sim = build(case, pm)
    # time the after-integrate hook (where boundary plugins correct positions) separately
    boundary = [0.0]
    inner = sim.hooks.sph_after_integrate

    def timed(**kwargs):
        t = time.perf_counter()
        inner(**kwargs)
        boundary[0] += time.perf_counter() - t

    sim.hooks.sph_after_integrate = timed
    sim.advance()  # compile and warm caches
    boundary[0] = 0.0
    t0 = time.perf_counter()
    for _ in range(steps):
        sim.advance()
    wall = time.perf_counter() - t0
    return {"n": sim.state.n, "steps": steps, "wall_s": wall, "psps": steps * sim.state.n / wall,
            "boundary_share": boundary[0] / wall,
            "us_per_particle_step": 1e6 * wall / (steps * sim.state.n),
            "peak_mb": resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="+", default=[10_000, 100_000, 1_000_000])
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--plugins", nargs="*", default=[])
    a = ap.parse_args()
    import numba

    print(f"full SPH step, 2D water block at rest, plugins={a.plugins or 'none'}, numba threads={numba.get_num_threads()}")
    print(f"{'particles':>10} {'steps':>6} {'wall s':>8} {'particle-steps/s':>17} {'us/particle-step':>17} "
          f"{'boundary %':>10} {'peak MB':>8}")
    for n in a.sizes:
        r = measure(n, a.steps, a.plugins)
        print(f"{r['n']:>10} {r['steps']:>6} {r['wall_s']:>8.3f} {r['psps']:>17.3e} "
              f"{r['us_per_particle_step']:>17.4f} {100 * r['boundary_share']:>10.2f} {r['peak_mb']:>8.0f}")


if __name__ == "__main__":
    main()
