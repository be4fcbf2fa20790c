"""Cost of the wall model and of density diffusion as shares of a full SPH step.

A 2D block of water at rest in a box (``bench_step.py``'s case, about 10^5 particles,
plain Tait pressure), stepped with: the reflective walls alone (base); + the wall model
(``wall_integral``); + density diffusion (delta = 0.1, hydrostatic); both. The variants
run in alternation, ``--pairs`` times each, and the median wall time per step is compared:
share = (t_variant - t_base) / t_variant, the part of the variant's step the addition takes.

    python benchmarks/speed/bench_wall_model.py [--n 100000] [--steps 20] [--pairs 5]

Figures are printed, never asserted: run by hand on a quiet machine.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from bench_step import load_case  # noqa: E402

from sphcore.run.build import build  # noqa: E402

VARIANTS = {
    "reflective": (["reflective"], []),
    "+ wall model": (["reflective", "wall_integral"], []),
    "+ density diffusion": (["reflective"], ["density_diffusion.delta=0.1", "density_diffusion.hydrostatic=true"]),
    "+ both": (["reflective", "wall_integral"], ["density_diffusion.delta=0.1", "density_diffusion.hydrostatic=true"]),
}


def simulation(n, plugins, sets):
    case, pm = load_case(n, plugins, ["physics.modified_pressure=false", *sets])
    sim = build(case, pm)
    sim.advance()  # compile and warm caches
    return sim


def per_step(sim, steps) -> float:
    t0 = time.perf_counter()
    for _ in range(steps):
        sim.advance()
    return (time.perf_counter() - t0) / steps


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=100_000)
    ap.add_argument("--steps", type=int, default=20)
    ap.add_argument("--pairs", type=int, default=5)
    a = ap.parse_args()
    import numba

    sims = {k: simulation(a.n, *v) for k, v in VARIANTS.items()}
    times = {k: [] for k in sims}
    for _ in range(a.pairs):
        for k, sim in sims.items():
            times[k].append(per_step(sim, a.steps))
    n = next(iter(sims.values())).state.n
    base = statistics.median(times["reflective"])
    print(f"{n} particles, 2D water at rest, plain Tait, numba threads={numba.get_num_threads()}, "
          f"median of {a.pairs} alternating runs of {a.steps} steps")
    print(f"{'variant':>22} {'ms/step':>9} {'particle-steps/s':>17} {'share of step':>14}")
    for k, ts in times.items():
        t = statistics.median(ts)
        share = "-" if k == "reflective" else f"{100 * (t - base) / t:.1f}%"
        print(f"{k:>22} {1e3 * t:>9.2f} {n / t:>17.3e} {share:>14}")


if __name__ == "__main__":
    main()
