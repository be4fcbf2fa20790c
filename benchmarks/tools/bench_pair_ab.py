"""Two pair loops side by side in one process: another checkout's ``sphcore/physics/equations.py``
(A) against this one's (B), on the same frozen state, interleaved.

    python benchmarks/tools/bench_pair_ab.py OTHER_EQUATIONS_PY [CASE] [--at 0.15] [--rounds 21]
        [--set KEY=VALUE ...]

    git worktree add /tmp/before HEAD~1       # for example: the commit before a change
    NUMBA_NUM_THREADS=1 python benchmarks/tools/bench_pair_ab.py /tmp/before/sphcore/physics/equations.py \\
        benchmarks/speed/pysph_dam_break

CASE (default ``benchmarks/speed/pysph_dam_break``) runs up to ``--at`` seconds of simulated time
with this checkout; then A's ``sph_rates`` and B's are called on copies of the same
arguments, alternately, ``--rounds`` times each (about 2 million particle evaluations a
round, A first in even rounds and B first in odd ones), and the script prints whether they give the same bits, the fastest and the median
milliseconds per call of each, and B / A as the ratio of the fastest calls and as the
median of the rounds' ratios. On a machine whose speed drifts within minutes, rounds that
alternate in one process see the same drift; separate runs of
``benchmarks/speed/bench_pairs.py`` do not.

Run it first with a copy of this checkout's own file as A (``git worktree add /tmp/same
HEAD``): that A/A run shows what the script reads when nothing differs. On a machine
whose speed drifted it read 0.85-0.92 with A always first, hence the alternating order;
alternating, 0.96-1.06 (fastest calls) and 0.94-1.05 (median of the rounds) with another
job on the other core, 0.91-1.05 and 0.92-0.99 without: differences within about 10 % are
noise there (docs/explanation/performance.md).

A is loaded as the module ``sphcore.equations_a``: its imports resolve to this checkout's
modules, so the file must fit them (the same ``Fields``, grid view and parameters). Its
numba cache lies beside that file, keyed by the file: this checkout's own file is refused
as A (its cache would be shared with ``sphcore.physics.equations``'s under another module name).
Figures are printed, never asserted.
"""

from __future__ import annotations

import argparse
import importlib.util
import statistics
import sys
import time
from pathlib import Path

import numba
import numpy as np

import sphcore.physics.equations as B
from sphcore.case.overrides import parse_set
from sphcore.run import runner
from sphcore.run.build import build

ROOT = Path(__file__).resolve().parents[2]


def load_other(path: Path):
    spec = importlib.util.spec_from_file_location("sphcore.equations_a", path)
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module
    spec.loader.exec_module(module)
    return module


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("other", type=Path, help="the other checkout's sphcore/physics/equations.py (A)")
    ap.add_argument("case", nargs="?", default=str(ROOT / "benchmarks" / "speed" / "pysph_dam_break"))
    ap.add_argument("--at", type=float, default=0.15, help="simulated time to run to first (s)")
    ap.add_argument("--rounds", type=int, default=21)
    ap.add_argument("--set", action="append", default=[], metavar="KEY=VALUE",
                    help="override a case option, as sph run --set does")
    a = ap.parse_args()
    if not a.other.is_file():
        sys.exit(f"{a.other}: no such file (expected another checkout's sphcore/physics/equations.py)")
    if a.other.resolve() == Path(B.__file__).resolve():
        sys.exit(f"{a.other} is this checkout's own file: give a copy in another checkout (git worktree add)")
    A = load_other(a.other)
    case, pm = runner.load(Path(a.case), [parse_set(s) for s in a.set])
    sim = build(case, pm)
    while sim.t < a.at and not sim.done():
        sim.advance()
    f, st = sim.forces, sim.state
    src = f.sources()
    view = f.pair_view(src)
    wall = f.wall_terms()
    f._buffers(st.n, src.pos.shape[0])
    n_src = src.pos.shape[0]

    def arguments():
        return (st.n, src, view, sim.params, f._L, wall, np.zeros_like(st.vel), np.zeros(st.n),
                f._work[:n_src].copy(), f._spos[:n_src].copy(), numba.get_num_threads())

    args = {"A": arguments(), "B": arguments()}
    loops = {"A": A.sph_rates, "B": B.sph_rates}
    for k in loops:
        loops[k](*args[k])
    same = all(np.array_equal(args["A"][i], args["B"][i]) for i in (6, 7))
    print(f"{case.name}: {st.n} particles at t = {sim.t:.4g} s, {numba.get_num_threads()} thread(s); "
          f"A = {a.other}, B = this checkout; same bits: {same}")
    calls = max(1, int(2e6 / max(n_src, 1)))
    times = {"A": [], "B": []}
    for r in range(a.rounds):
        for k in (("A", "B") if r % 2 == 0 else ("B", "A")):  # ABBA...: neither always runs first
            t = time.perf_counter()
            for _ in range(calls):
                loops[k](*args[k])
            times[k].append((time.perf_counter() - t) / calls * 1e3)
    for k in ("A", "B"):
        print(f"{k}: fastest {min(times[k]):.3f} ms, median {statistics.median(times[k]):.3f} ms per call")
    ratios = [b / x for x, b in zip(times["A"], times["B"])]
    print(f"B / A: {min(times['B']) / min(times['A']):.3f} (fastest calls), {statistics.median(ratios):.3f} "
          f"(median of {a.rounds} rounds)")


if __name__ == "__main__":
    main()
