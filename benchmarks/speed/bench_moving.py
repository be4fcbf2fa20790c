"""What moving walls cost a step: the same tank fixed and rolling, side by side.

    python benchmarks/speed/bench_moving.py [--n 100000] [--steps 10] [--pairs 5] [--plugins reflective]

Still water fills the bottom quarter of a 2D tank (about ``--n`` particles). Two runs are
built in this process: the tank fixed, and the same tank rolling +-4 deg at 1.63 s about
its floor's centre (the SPHERIC sloshing motion) and swaying. After a warm-up step each
(compilation), blocks of ``--steps`` steps alternate between the two, ``--pairs`` times;
the table gives the median time per step of each, their ratio (moving / fixed) and its
spread over the pairs. Figures are printed, never asserted: run on a quiet machine.
"""

from __future__ import annotations

import argparse
import math
import statistics
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))  # run from a checkout without installing

from sphcore.run import runner  # noqa: E402
from sphcore.run.build import build  # noqa: E402
from sphcore.testing import case_with, tiny_case, write_case  # noqa: E402

ROLL = [{"type": "sine_rotation", "centre": [1.0, 0.0], "amplitude": 4.0, "period": 1.63},
        {"type": "sine_translation", "axis": [1.0, 0.0], "amplitude": 0.01, "period": 1.63}]


def simulation(root: Path, name: str, n: int, plugins: list[str], moving: bool):
    width, depth = 2.0, 0.5
    dx = width / round(width / math.sqrt(width * depth / n))  # whole rows across the tank
    changes = {"domain.max": [width, 2.0 * depth], "blocks[0].max": [width, depth], "particles.dx": dx,
               "time.t_end": 100.0, "plugins.use": plugins, "viscosity.alpha": 0.1}
    if moving:
        changes["domain.motion"] = ROLL
    case, pm = runner.load(write_case(root / name, case_with(tiny_case(), changes)))
    return build(case, pm)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=100_000, help="particles (about)")
    ap.add_argument("--steps", type=int, default=10, help="steps per block")
    ap.add_argument("--pairs", type=int, default=5, help="fixed/moving blocks, alternating")
    ap.add_argument("--plugins", nargs="+", default=["reflective"])
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        sims = {m: simulation(Path(tmp), m, args.n, args.plugins, m == "moving") for m in ("fixed", "moving")}
        per_step = alternate(sims, args.steps, args.pairs)
        n = sims["fixed"].state.n
    print(f"2D tank, {n} particles, plugins {' '.join(args.plugins)}, {args.pairs} pairs of {args.steps} steps")
    report(per_step, n, "moving / fixed")
    return 0


def alternate(sims: dict, steps: int, pairs: int) -> dict:
    """After a warm-up step each (compilation), ``pairs`` rounds of ``steps`` steps of each
    simulation in turn; the seconds per step of each block, by name."""
    for sim in sims.values():
        sim.advance()  # compile, fill caches
    per_step = {m: [] for m in sims}
    for _ in range(pairs):
        for m, sim in sims.items():
            t0 = time.perf_counter()
            for _ in range(steps):
                sim.advance()
            per_step[m].append((time.perf_counter() - t0) / steps)
    return per_step


def report(per_step: dict, n: int, ratio: str) -> None:
    """The median time per step of each and the ratio of the second to the first (its
    median over the pairs and their spread), as ``ratio`` names it."""
    print(f"{'':8s} {'ms/step':>10s} {'particle-steps/s':>17s}")
    for m, times in per_step.items():
        t = statistics.median(times)
        print(f"{m:8s} {1e3 * t:10.3f} {n / t:17.3g}")
    first, second = per_step.values()
    ratios = [b / a for a, b in zip(first, second)]
    print(f"{ratio}: {statistics.median(ratios):.3f} (pairs {min(ratios):.3f} .. {max(ratios):.3f})")


if __name__ == "__main__":
    sys.exit(main())
