"""What a floating body costs a step beyond its moving wall: the same box moved by a motion
and moved by the water, side by side.

    python benchmarks/speed/bench_body.py [--n 100000] [--steps 10] [--pairs 5]

Still water fills a 2D tank 2 m long to 0.5 m (about ``--n`` particles); a box 0.2 m wide
and 0.1 m high floats at its draft in the middle, the wall model (``wall_integral``) and
the reflective boundary at every wall. Two runs are built in this process: the box heaving
by a prescribed sine (a moving wall: ``[[domain.walls.motion]]``), and the box a floating
body of density 500 (``[[bodies]]``, free to heave, roll and sway), which adds the sums of
its load over its particles, the rigid-body kicks and the contact checks. After a warm-up
step each (compilation), blocks of ``--steps`` steps alternate between the two,
``--pairs`` times; the table gives the median time per step of each, their ratio (body /
moving wall) and its spread over the pairs. Figures are printed, never asserted: run on a
quiet machine.
"""

from __future__ import annotations

import argparse
import math
import sys
import tempfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))  # run from a checkout without installing

from bench_moving import alternate, report  # this script's folder is on the path

from sphcore.run import runner
from sphcore.run.build import build
from sphcore.testing import case_with, tiny_case, write_case

WIDTH, DEPTH, BEAM, HEIGHT = 2.0, 0.5, 0.2, 0.1
HEAVE = [{"type": "sine_translation", "axis": [0.0, 1.0], "amplitude": 0.005, "period": 0.8}]


def simulation(root: Path, name: str, n: int, body: bool):
    dx = WIDTH / round(WIDTH / math.sqrt(WIDTH * DEPTH / n))  # whole rows across the tank
    bottom = DEPTH - 0.5 * HEIGHT  # density 500: the draft is half the height
    box = {"shape": "box", "min": [0.5 * (WIDTH - BEAM), bottom], "max": [0.5 * (WIDTH + BEAM), bottom + HEIGHT]}
    changes = {"domain.max": [WIDTH, 2.0 * DEPTH], "blocks[0].max": [WIDTH, DEPTH], "particles.dx": dx,
               "kernel.h_over_dx": 2.0, "time.t_end": 100.0, "plugins.use": ["reflective", "wall_integral"],
               "viscosity.alpha": 0.02}
    if body:
        changes["domain.walls"] = [box]
        changes["bodies"] = [{"wall": 0, "density": 500.0}]
    else:
        changes["domain.walls"] = [{**box, "motion": HEAVE}]
    case, pm = runner.load(write_case(root / name, case_with(tiny_case(), changes)))
    return build(case, pm)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=100_000, help="particles (about)")
    ap.add_argument("--steps", type=int, default=10, help="steps per block")
    ap.add_argument("--pairs", type=int, default=5, help="moving-wall/body blocks, alternating")
    args = ap.parse_args(argv)
    with tempfile.TemporaryDirectory() as tmp:
        sims = {m: simulation(Path(tmp), m, args.n, m == "body") for m in ("moving", "body")}
        per_step = alternate(sims, args.steps, args.pairs)
        n = sims["moving"].state.n
    print(f"2D tank, {n} particles, a box moving by a sine and floating, {args.pairs} pairs of {args.steps} steps")
    report(per_step, n, "body / moving wall")
    return 0


if __name__ == "__main__":
    sys.exit(main())
