"""What a parallel loop costs after serial work: the second thread's wake-up.

    NUMBA_NUM_THREADS=2 python benchmarks/speed/bench_wakeup.py [--n 18224] [--gaps 0 50 200] [--calls 500] [--load 0]

A step of sphcore is several parallel loops (numba's prange: fork and join, no barrier
inside) with serial work between them. numba's OpenMP workers spin for
``GOMP_SPINCOUNT`` iterations after a loop (sphcore sets 1,000, ~25 us) and then sleep;
a loop that starts after a longer serial stretch first wakes them. This script times one
element-wise loop of ``--n`` elements (a square root and a multiply-add each; 18,224 =
8 x the 2,278 particles of PySPH's dam break) called back to back, and called after
``--gaps`` microseconds (about) of serial work, with one thread and with all of them;
it prints the median time of the loop alone (the serial work's own time subtracted) and
the gap as measured. ``--load N`` starts N busy processes beside it (each an endless loop:
another user's job on a core), as ``bench_loaded.py`` does. The OpenMP settings are
sphcore's (``import sphcore`` first; ``GOMP_SPINCOUNT`` in the environment wins). Figures
are printed, never asserted.
"""

from __future__ import annotations

import argparse
import multiprocessing as mp
import statistics
import time

import numba
import numpy as np
from numba import njit, prange

import sphcore  # noqa: F401  (its OpenMP wait policy and spin count)


@njit(parallel=True)
def loop(x, y):
    for i in prange(x.shape[0]):
        y[i] = np.sqrt(x[i]) * 1.0001 + y[i]


@njit
def serial(x, reps):
    s = 0.0
    for _ in range(reps):
        for i in range(x.shape[0]):
            s += x[i] * 1.0000001
    return s


def busy():
    while True:
        pass


def per_call(fn, calls, repeats=5):
    out = []
    for _ in range(repeats):
        t = time.perf_counter()
        for _ in range(calls):
            fn()
        out.append((time.perf_counter() - t) / calls)
    return statistics.median(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=int, default=18224)
    ap.add_argument("--gaps", type=float, nargs="+", default=[0.0, 50.0, 200.0], help="serial work between calls (us)")
    ap.add_argument("--calls", type=int, default=500)
    ap.add_argument("--load", type=int, default=0, help="busy processes beside the measurement")
    args = ap.parse_args()
    loads = [mp.Process(target=busy, daemon=True) for _ in range(args.load)]
    for p in loads:
        p.start()
    try:
        measure(args)
    finally:
        for p in loads:
            p.terminate()


def measure(args):
    most = numba.get_num_threads()
    x = np.random.default_rng(0).random(args.n)
    y = np.zeros_like(x)
    small = np.random.default_rng(1).random(256)
    loop(x, y)
    serial(small, 1)
    # one pass over `small`, from a long call (a call of one pass is mostly numba's call overhead)
    one = per_call(lambda: serial(small, 1000), args.calls // 10 + 1) / 1000
    print(f"threading layer {numba.threading_layer()}, {most} threads at most, loop of {args.n} elements, "
          f"{args.load} busy processes beside")
    print(f"{'gap us':>8} {'1 thread us':>12} {f'{most} threads us':>14}")
    for gap in args.gaps:
        reps = max(int(round(gap * 1e-6 / one)), 0)
        t_gap = per_call(lambda: serial(small, reps), args.calls) if reps else 0.0
        row = []
        for nt in (1, most):
            numba.set_num_threads(nt)
            row.append(per_call(lambda: (loop(x, y), serial(small, reps)), args.calls) - t_gap)
        numba.set_num_threads(most)
        print(f"{1e6 * t_gap:8.0f} {1e6 * row[0]:12.1f} {1e6 * row[1]:14.1f}")


if __name__ == "__main__":
    main()
