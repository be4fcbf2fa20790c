"""One thread against two on a quiet and on a loaded machine, whole process, side by side.

    python benchmarks/speed/bench_loaded.py [CASE] [--pairs 5] [--load 0 1] [--set KEY=VALUE ...]

Runs ``sph run CASE`` (default: the seed's dam break without output writers) with
``NUMBA_NUM_THREADS=1``, with ``=2`` and the adaptive thread count (the default,
``parallel.adapt = true``), and with ``=2`` fixed (``parallel.adapt = false``), in
alternating order, ``--pairs`` times, once with no other load and once with ``--load``
busy processes (each an endless loop in its own process, one core's worth of work from
another user). Prints the median wall time of each variant, the median of the per-round
ratios to one thread, and the adaptive runs' share of steps with each count. Figures are
printed, never asserted: run by hand.
"""

from __future__ import annotations

import argparse
import json
import multiprocessing as mp
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
VARIANTS = {  # label: (NUMBA_NUM_THREADS, extra --set)
    "1 thread": (1, []),
    "2 adaptive": (2, []),
    "2 fixed": (2, ["parallel.adapt=false"]),
}


def spin():
    while True:
        pass


def run(case, out, threads, sets) -> tuple[float, dict]:
    cmd = [sys.executable, "-m", "sphcore.cli", "run", str(case), "--output", str(out), "--overwrite",
           "--progress", "off"]
    for s in sets:
        cmd += ["--set", s]
    env = dict(os.environ, NUMBA_NUM_THREADS=str(threads))
    t = time.perf_counter()
    r = subprocess.run(cmd, env=env, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    wall = time.perf_counter() - t
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(cmd)}\n{r.stdout[-2000:]}")
    return wall, json.loads((out / "summary.json").read_text())["threads"]


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", nargs="?", default=str(ROOT / "cases" / "dam_break"))
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--load", type=int, nargs="+", default=[0, 1], help="busy processes beside the runs")
    ap.add_argument("--set", action="append", default=None,
                    help="case overrides for every run (default: plugins.use=[\"reflective\"], no writers)")
    a = ap.parse_args()
    a.set = a.set or ['plugins.use=["reflective"]']
    tmp = Path(tempfile.mkdtemp(prefix="bench_loaded"))
    print(f"case: {a.case} ({' '.join(a.set)}), whole process, {a.pairs} rounds, cores: {os.cpu_count()}")
    for label, (threads, sets) in VARIANTS.items():
        run(a.case, tmp / "warm", threads, a.set + sets)  # numba's cache
    print(f"{'load':>4} {'variant':>11} {'median s':>9} {'ratio to 1':>11}  adaptive: steps per count")
    for load in a.load:
        spinners = [mp.Process(target=spin, daemon=True) for _ in range(load)]
        for p in spinners:
            p.start()
        try:
            walls = {k: [] for k in VARIANTS}
            steps = {}
            labels = list(VARIANTS)
            for k in range(a.pairs):
                for label in (labels if k % 2 == 0 else labels[::-1]):
                    threads, sets = VARIANTS[label]
                    wall, info = run(a.case, tmp / "run", threads, a.set + sets)
                    walls[label].append(wall)
                    if label == "2 adaptive":
                        for c, n in info["steps_per_count"].items():
                            steps[c] = steps.get(c, 0) + n
        finally:
            for p in spinners:
                p.terminate()
        one = walls["1 thread"]
        total = sum(steps.values()) or 1
        share = ", ".join(f"{c}: {n / total:.0%}" for c, n in sorted(steps.items()))
        for label, w in walls.items():
            ratio = statistics.median(x / y for x, y in zip(w, one))
            print(f"{load:>4} {label:>11} {statistics.median(w):9.2f} {ratio:11.2f}  "
                  f"{share if label == '2 adaptive' else ''}")
    shutil.rmtree(tmp, ignore_errors=True)


if __name__ == "__main__":
    main()
