"""Where a step's time goes: the pair loop alone on a frozen state, then a step by stages.

    python benchmarks/speed/bench_pairs.py [CASE] [--at 0.15] [--calls 200] [--steps 1000]

Runs CASE (default ``cases/dam_break``) up to ``--at`` seconds of simulated time, then

1. calls ``sph_rates`` (the pair loop: continuity, momentum, viscosity, diffusion) on
   that frozen state, 9 times ``--calls`` calls, and prints the median time per call and
   per pair (pairs counted by the cell grid);
2. advances ``--steps`` more steps with a timer around each stage and prints the mean
   time per step of each: the pair loop, the neighbour grid, the walls (the
   ``sph_after_integrate`` hook), the checks, the time-step choice, the equation of state.

Threads: ``NUMBA_NUM_THREADS``. Figures are printed, never asserted: compare two versions
or two settings by running this script for each, alternately, on the same machine.
"""

from __future__ import annotations

import argparse
import collections
import statistics
import time
from pathlib import Path

import numba
import numpy as np

import sphcore.physics.forces
from sphcore.case.overrides import parse_set
from sphcore.neighbours.cellgrid import neighbour_pairs
from sphcore.physics.equations import sph_rates
from sphcore.run import runner
from sphcore.run.build import build

ROOT = Path(__file__).resolve().parents[2]


def frozen_pair_loop(sim, calls: int) -> tuple[float, int]:
    """Median seconds per ``sph_rates`` call on the current state, and the pair count."""
    f, st = sim.forces, sim.state
    acc, drho = np.zeros_like(st.vel), np.zeros(st.n)
    src = f.sources()
    view = f.pair_view(src)
    wall = f.wall_terms()
    f._buffers(st.n, src.pos.shape[0])
    n_src = src.pos.shape[0]
    args = (st.n, src, view, sim.params, f._L, wall, acc, drho, f._work[:n_src], f._spos[:n_src],
            numba.get_num_threads())
    sph_rates(*args)
    times = []
    for _ in range(9):
        t = time.perf_counter()
        for _ in range(calls):
            sph_rates(*args)
        times.append((time.perf_counter() - t) / calls)
    pi, _ = neighbour_pairs(src.pos, f.grid(src.pos, count=False).view, sim.params.support)
    return statistics.median(times), len(pi) // 2


def staged_steps(sim, steps: int) -> tuple[float, dict]:
    """Mean seconds per step, and per stage, over ``steps`` steps."""
    spent = collections.defaultdict(float)

    def timed(obj, name, label):
        inner = getattr(obj, name)

        def wrapper(*a, **kw):
            t = time.perf_counter()
            out = inner(*a, **kw)
            spent[label] += time.perf_counter() - t
            return out

        setattr(obj, name, wrapper)

    pair_loop = sphcore.physics.forces.sph_rates

    def rates(*a):
        t = time.perf_counter()
        pair_loop(*a)
        spent["pair loop (sph_rates)"] += time.perf_counter() - t

    sphcore.physics.forces.sph_rates = rates
    try:
        timed(sim.forces, "pair_view", "neighbour search (grid or pair list)")
        timed(sim.hooks, "sph_after_integrate", "walls (sph_after_integrate)")
        timed(sim, "check", "checks")
        timed(sim, "choose_dt", "time step")
        timed(sim, "update_pressure", "equation of state")
        t = time.perf_counter()
        for _ in range(steps):
            sim.advance()
        total = time.perf_counter() - t
    finally:
        sphcore.physics.forces.sph_rates = pair_loop
    return total / steps, {k: v / steps for k, v in spent.items()}


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", nargs="?", default=str(ROOT / "cases" / "dam_break"))
    ap.add_argument("--at", type=float, default=0.15, help="simulated time to run to first (s)")
    ap.add_argument("--calls", type=int, default=200, help="pair-loop calls per timing")
    ap.add_argument("--steps", type=int, default=1000, help="steps timed by stages")
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override a case option, as sph run --set does")
    args = ap.parse_args()
    case, pm = runner.load(Path(args.case), [parse_set(s) for s in args.set])
    sim = build(case, pm)
    while sim.t < args.at and not sim.done():
        sim.advance()
    per_call, pairs = frozen_pair_loop(sim, args.calls)
    print(f"{case.name}: {sim.state.n} particles at t = {sim.t:.4g} s, {numba.get_num_threads()} thread(s)")
    print(f"pair loop, frozen state: {1e3 * per_call:.3f} ms per call, {pairs} pairs, "
          f"{1e9 * per_call / max(pairs, 1):.1f} ns per pair")
    per_step, stages = staged_steps(sim, args.steps)
    print(f"{args.steps} steps: {1e6 * per_step:.1f} us per step")
    for label, sec in sorted(stages.items(), key=lambda kv: -kv[1]):
        print(f"  {label:30s} {1e6 * sec:9.1f} us  {100 * sec / per_step:5.1f}%")
    print(f"  {'the rest (integrator, hooks)':30s} {1e6 * (per_step - sum(stages.values())):9.1f} us")


if __name__ == "__main__":
    main()
