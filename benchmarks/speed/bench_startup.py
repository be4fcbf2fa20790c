"""Where a whole ``sph run`` process spends its time before and while it steps: imports,
the case, the set-up, numba's first calls, the steps.

    python benchmarks/speed/bench_startup.py [CASE] [--steps N]

Run in a fresh process (this script is one): numpy's and numba's imports, sphcore's,
``runner.load`` (the case and its plugins), the ``Simulation`` (particles, parameters, the
first numba call: numba loads its typing registries there), the first-step check of
``sph run`` (the pair loop's cached code is loaded there), five steps (the kernels first
called in a step), then ``--steps`` more (default: to the case's end) and their mean.
Every numba dispatcher's first call is timed too (loading its cached machine code, or
compiling it when there is no cache) and listed, slowest first. No output is written.
CASE defaults to ``benchmarks/speed/pysph_dam_break``, the case of ``bench_pysph.py``, whose
whole process this splits. Figures are printed, never asserted.
"""

from __future__ import annotations

import time

T0 = time.perf_counter()
MARKS: list[tuple[str, float]] = []


def mark(label: str) -> None:
    MARKS.append((label, time.perf_counter()))


import importlib  # noqa: E402

importlib.import_module("numpy")

mark("import numpy")
import numba  # noqa: E402

mark("import numba")
from numba.core import dispatcher  # noqa: E402

from sphcore.run import budget, runner  # noqa: E402
from sphcore.run.build import build  # noqa: E402

mark("import sphcore")

import argparse  # noqa: E402
from pathlib import Path  # noqa: E402

HERE = Path(__file__).resolve().parent
FIRST_CALLS: list[tuple[str, float]] = []
_compile_for_args = dispatcher.Dispatcher._compile_for_args


def _timed_first_call(self, *args, **kwargs):
    t = time.perf_counter()
    try:
        return _compile_for_args(self, *args, **kwargs)
    finally:
        FIRST_CALLS.append((self.py_func.__qualname__, time.perf_counter() - t))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", nargs="?", default=str(HERE / "pysph_dam_break"))
    ap.add_argument("--steps", type=int, default=None, help="steps after the first five (default: to the end)")
    a = ap.parse_args()
    dispatcher.Dispatcher._compile_for_args = _timed_first_call
    case, pm = runner.load(Path(a.case), [])
    mark("load the case and its plugins")
    sim = build(case, pm)
    mark("set up the simulation")
    budget.check_first_step(sim)
    mark("first-step check (sph run's)")
    n = 0
    while not sim.done() and n < 5:
        sim.advance()
        n += 1
    mark("the first 5 steps")
    limit = None if a.steps is None else n + a.steps
    while not sim.done() and (limit is None or n < limit):
        sim.advance()
        n += 1
    mark(f"{n - 5} more steps")
    prev = T0
    print(f"{case.name}: {sim.state.n} particles, {numba.get_num_threads()} thread(s), t = {sim.t:.4g} s")
    for label, t in MARKS:
        print(f"  {label:32s} {1e3 * (t - prev):8.1f} ms   (from the start {1e3 * (t - T0):8.1f} ms)")
        prev = t
    if n > 5:
        print(f"  mean step after the first five    {1e6 * (MARKS[-1][1] - MARKS[-2][1]) / (n - 5):8.1f} us")
    print(f"numba first calls: {len(FIRST_CALLS)}, {1e3 * sum(s for _, s in FIRST_CALLS):.1f} ms in all "
          "(the first includes numba's registries)")
    for name, s in sorted(FIRST_CALLS, key=lambda x: -x[1])[:8]:
        print(f"  {1e3 * s:8.1f} ms  {name}")


if __name__ == "__main__":
    main()
