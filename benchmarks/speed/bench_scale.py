"""How the cost of a full SPH step grows with the particle count, per boundary plugin:
particle-steps per second, microseconds per particle-step, peak RSS and memory per particle.

    python benchmarks/speed/bench_scale.py                       # particle-steps/s against particle count
    python benchmarks/speed/bench_scale.py --sizes2d 1000 10000 --sizes3d --plugins reflective

A still-water block (hydrostatic start, gravity, artificial viscosity alpha = 0.1) sits at
the bottom of a box twice its height (2D: about square; 3D: about a cube), dx = 0.01 m.
Each (dimension, size, plugin) row runs in a fresh Python process, so that one size's
arrays do not inflate the next one's peak memory: the process first steps a 64-particle
copy of the case (numba's compiled kernels are loaded, their memory counted as baseline),
then builds the real case, takes one step (first-touch allocations), then times ``steps``
more in five chunks and reports the fastest chunk (on a shared machine the other jobs
only ever slow a chunk down; the load average is printed with each row). MB per particle
= (peak RSS - baseline RSS) / particles: the marginal memory, ghost buffers and
neighbour-list arrays included. Figures are printed, never asserted.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CHUNKS = 5
PLUGINS = {"reflective": ["reflective"], "ghost": ["ghost"], "both": ["reflective", "ghost"]}

CASE = """
[case]
dim = {dim}
[domain]
min = {lo}
max = {hi}
[[blocks]]
min = {lo}
count = {count}
[particles]
dx = {dx}
[physics]
gravity = {gravity}
[viscosity]
alpha = 0.1
[time]
t_end = 100.0
[plugins]
use = {plugins}
"""


def block_counts(n: int, dim: int) -> list[int]:
    """Particles per axis of a block of about n particles: square in 2D, cubic in 3D."""
    side = max(2, int(round(n ** (1.0 / dim))))
    return [side] * dim


def write_case(directory: Path, n: int, dim: int, plugins: list[str], dx: float = 0.01, skin=None) -> Path:
    count = block_counts(n, dim)
    up = 1  # y is up
    hi = [c * dx for c in count]
    hi[up] *= 2.0
    gravity = [0.0, -9.81, 0.0][:dim]
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "case.toml").write_text(CASE.format(dim=dim, lo=[0.0] * dim, hi=hi, count=count, dx=dx,
                                                     gravity=gravity, plugins=json.dumps(plugins))
                                         + ("" if skin is None else f"[neighbours]\nskin = {skin}\n"))
    return directory


def _rss_mb() -> float:
    import resource

    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: kB


def measure_one(n: int, dim: int, plugin: str, steps: int, skin=None) -> dict:
    """In the child process: warm up on a tiny case, then time the real one."""
    from sphcore.run import runner
    from sphcore.run.build import build

    with tempfile.TemporaryDirectory(prefix="sphscale") as tmp:
        warm, _ = runner.load(write_case(Path(tmp) / "warm", 64, dim, PLUGINS[plugin], skin=skin))
        sim = build(warm, _)
        for _ in range(2):
            sim.advance()
        del sim
        base = _rss_mb()
        case, pm = runner.load(write_case(Path(tmp) / "real", n, dim, PLUGINS[plugin], skin=skin))
        t0 = time.perf_counter()
        sim = build(case, pm)
        sim.advance()
        setup = time.perf_counter() - t0
        chunks = [steps // CHUNKS + (k < steps % CHUNKS) for k in range(CHUNKS)]
        rates = []
        for c in (c for c in chunks if c):
            t0 = time.perf_counter()
            for _ in range(c):
                sim.advance()
            rates.append((time.perf_counter() - t0) / c)
        wall = min(rates) * steps  # the fastest chunk's pace
        peak = _rss_mb()
    import numba

    return {"dim": dim, "n": sim.state.n, "plugin": plugin, "steps": steps, "wall_s": wall, "setup_s": setup,
            "psps": steps * sim.state.n / wall, "us": 1e6 * wall / (steps * sim.state.n), "peak_mb": peak,
            "base_mb": base, "mb_per_particle": (peak - base) / sim.state.n, "threads": numba.get_num_threads(),
            "ghosts": int(getattr(sim, "n_sources", 0)), "list_builds": sim.counters.get("pair_list_builds", 0)}


def steps_for(n: int, budget: float) -> int:
    """Steps to time: about ``budget`` particle-steps, at least 5, at most 2000."""
    return int(min(2000, max(5, math.ceil(budget / n))))


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes2d", type=int, nargs="*", default=[1_000, 10_000, 100_000, 1_000_000])
    ap.add_argument("--sizes3d", type=int, nargs="*", default=[10_000, 100_000])
    ap.add_argument("--plugins", nargs="+", default=list(PLUGINS), choices=list(PLUGINS))
    ap.add_argument("--budget", type=float, default=2e6, help="particle-steps timed per row (steps = budget / n, "
                    "clamped to 5..2000)")
    ap.add_argument("--skin", type=float, default=None, help="neighbours.skin of the case (default: sphcore's); "
                    "in still water a kept pair list is built once, in a flow every few steps")
    ap.add_argument("--one", nargs=4, metavar=("N", "DIM", "PLUGIN", "STEPS"), help=argparse.SUPPRESS)
    a = ap.parse_args()
    if a.one:
        n, dim, plugin, steps = a.one
        print(json.dumps(measure_one(int(n), int(dim), plugin, int(steps), a.skin)))
        return
    rows = [(2, n) for n in a.sizes2d] + [(3, n) for n in a.sizes3d]
    threads = os.environ.get("NUMBA_NUM_THREADS", "default")
    print(f"full SPH step (neighbours, rates, leapfrog, plugins), still water in a box, dx = 0.01 m; "
          f"one process per row; {os.cpu_count()} cores, NUMBA_NUM_THREADS={threads}")
    head = (f"{'dim':>3} {'particles':>9} {'plugin':>10} {'steps':>5} {'particle-steps/s':>16} {'us/p-step':>9} "
            f"{'ghosts':>7} {'builds':>6} {'peak RSS MB':>11} {'base MB':>7} {'kB/particle':>11} {'setup s':>7} {'load':>5}")
    print(head)
    print("-" * len(head))
    for dim, n in rows:
        for plugin in a.plugins:
            steps = steps_for(n, a.budget)
            cmd = [sys.executable, __file__, "--one", str(n), str(dim), plugin, str(steps)]
            cmd += [] if a.skin is None else ["--skin", str(a.skin)]
            proc = subprocess.run(cmd, capture_output=True, text=True)
            if proc.returncode != 0:
                print(f"{dim:>3} {n:>9} {plugin:>10}  failed: {proc.stderr.strip().splitlines()[-1:]}", flush=True)
                continue
            r = json.loads(proc.stdout.strip().splitlines()[-1])
            print(f"{r['dim']:>3} {r['n']:>9} {r['plugin']:>10} {r['steps']:>5} {r['psps']:>16.3e} {r['us']:>9.3f} "
                  f"{r['ghosts']:>7} {r['list_builds']:>6} {r['peak_mb']:>11.0f} {r['base_mb']:>7.0f} {r['mb_per_particle'] * 1024:>11.3f}"
                  f"{r['setup_s']:>7.2f} {os.getloadavg()[0]:>5.1f}", flush=True)


if __name__ == "__main__":
    main()
