"""What output costs: the dam break with its writers (VTU + netCDF frames on the case's
schedules, every 0.01 s) against the same run without them, at the case's resolution and
at about 10x more particles.

    python benchmarks/speed/bench_output.py [--case cases/dam_break] [--t-end 0.3] [--scales 1 10] [--repeat 1]

Each run is ``sph run`` in a fresh process on a temporary copy of the case, with and
without writers alternating on the same machine (``--without`` sets ``plugins.use`` of the
run without them; ``["reflective"]`` by default: the case's walls and nothing else). A
scale k divides particles.dx by sqrt(k); a block given by ``count`` is rewritten with
``max`` = min + count dx in the copy so that its extent stays and only the lattice gets
finer. Wall time is the run summary's ``wall_time_s`` (the stepping loop with its output,
not the interpreter's start-up); with ``--repeat`` > 1 the fastest of each is kept. The
output share is (with - without) / with.

Two runs compare well only on a quiet machine: another job on a 2-core box can double one
of them. So each run also times its own output calls (``Simulation.output``, i.e. every
``sph_output`` hook, wrapped with a clock in the child process) and the table gives that
share of the same run's wall time, ``hooks``, which holds up under load; and the CPU
seconds of each whole process (user + system, start-up included).

Figures are printed, never asserted: run by hand on a quiet machine.
"""

from __future__ import annotations

import argparse
import json
import math
import os
import re
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python 3.10
    import tomli as tomllib

ROOT = Path(__file__).resolve().parents[2]


# ``sph ARGV`` (sphcore.cli.main) with every Simulation.output call timed; the seconds go
# to the file named by $SPH_BENCH_OUTPUT_TIMES.
CHILD = """
import json, os, sys, time
from sphcore import cli
from sphcore.run import simulation
spent = {"output_s": 0.0, "calls": 0}
inner = simulation.Simulation.output
def timed(self, final=False):
    t = time.perf_counter()
    try:
        return inner(self, final)
    finally:
        spent["output_s"] += time.perf_counter() - t
        spent["calls"] += 1
simulation.Simulation.output = timed
status = cli.main(sys.argv[1:])
with open(os.environ["SPH_BENCH_OUTPUT_TIMES"], "w") as f:
    json.dump(spent, f)
sys.exit(status)
"""


def scaled_case(case_dir: Path, scale: float, work: Path) -> tuple[Path, list[str]]:
    """A copy of the case whose blocks are given by min/max; the --set that refines it."""
    text = (case_dir / "case.toml").read_text()
    cfg = tomllib.loads(text)
    dx = float(cfg["particles"]["dx"])
    blocks = cfg.get("blocks", [])
    counted = iter([b for b in blocks if "count" in b])

    def to_max(match):
        b = next(counted)
        top = [lo + n * dx for lo, n in zip(b["min"], b["count"])]
        return f"max = [{', '.join(repr(x) for x in top)}]"

    text = re.sub(r"(?m)^count\s*=\s*\[[^\]]*\][^\n]*", to_max, text)
    assert next(counted, None) is None, "a block's count was not found on a line of its own"
    out = work / f"case_x{scale:g}"
    out.mkdir()
    (out / "case.toml").write_text(text)
    return out, [f"particles.dx={dx / math.sqrt(scale)!r}"]


def run(case: Path, out: Path, sets: list[str], t_end: float | None) -> dict:
    """One ``sph run`` in a fresh process; its summary plus the process's wall and CPU time."""
    cmd = [sys.executable, "-c", CHILD, "run", str(case), "--output", str(out), "--progress", "off"]
    if t_end is not None:
        cmd += ["--t-end", repr(t_end)]
    for s in sets:
        cmd += ["--set", s]
    log, times = out.with_suffix(".log"), out.with_suffix(".times.json")
    env = dict(os.environ, SPH_BENCH_OUTPUT_TIMES=str(times))
    with open(log, "w") as f:  # a file, not a pipe: nothing to drain while waiting
        start = time.perf_counter()
        proc = subprocess.Popen(cmd, stdout=f, stderr=subprocess.STDOUT, env=env)
        _, status, usage = os.wait4(proc.pid, 0)  # wait4: the child's own CPU time
        wall = time.perf_counter() - start
    proc.returncode = os.waitstatus_to_exitcode(status)
    if proc.returncode != 0:
        raise SystemExit(f"{' '.join(cmd)} failed ({proc.returncode}):\n{log.read_text()}")
    summary = json.loads((out / "summary.json").read_text())
    summary["process_wall_s"] = wall
    summary["process_cpu_s"] = usage.ru_utime + usage.ru_stime
    summary.update(json.loads(times.read_text()))
    summary["output_mb"] = sum(p.stat().st_size for p in out.rglob("*") if p.is_file()
                               and p.name not in ("checkpoint.npz", "summary.json")) / 2**20
    return summary


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--case", type=Path, default=ROOT / "cases" / "dam_break")
    ap.add_argument("--t-end", type=float, default=0.3, help="simulated time (s); the case's when 0")
    ap.add_argument("--scales", type=float, nargs="+", default=[1.0, 10.0], help="particle-count factors")
    ap.add_argument("--repeat", type=int, default=1, help="runs of each kind; the fastest is kept")
    ap.add_argument("--without", default='["reflective"]', help="plugins.use of the run without writers")
    args = ap.parse_args()
    t_end = args.t_end or None

    work = Path(tempfile.mkdtemp(prefix="sph_bench_output_"))
    print(f"case {args.case}, t_end {t_end} s, {os.cpu_count()} cores, "
          f"OMP_WAIT_POLICY={os.environ.get('OMP_WAIT_POLICY', 'passive (sphcore default)')}", flush=True)
    rows = []
    try:
        for scale in args.scales:
            case, sets = scaled_case(args.case, scale, work)
            best = {}
            for r in range(args.repeat):
                for kind, extra in (("with", []), ("without", [f"plugins.use={args.without}"])):
                    out = work / f"out_x{scale:g}_{kind}_{r}"
                    s = run(case, out, sets + extra, t_end)
                    shutil.rmtree(out)
                    print(f"  x{scale:g} {kind:<7} run {r + 1}: {s['n_particles']} particles, {s['steps']} steps, "
                          f"{s['wall_time_s']:.2f} s wall ({s['process_wall_s']:.2f} s process, "
                          f"{s['process_cpu_s']:.2f} s CPU), output calls {s['output_s']:.2f} s, "
                          f"frames vtu {s.get('vtu', {}).get('frames', 0)} "
                          f"netcdf {s.get('netcdf_frames', 0)}, {s['output_mb']:.1f} MB", flush=True)
                    if kind not in best or s["wall_time_s"] < best[kind]["wall_time_s"]:
                        best[kind] = s
            rows.append((scale, best["with"], best["without"]))
    finally:
        shutil.rmtree(work, ignore_errors=True)

    print()
    print(f"{'scale':>5} {'particles':>9} {'steps':>6} {'frames':>6} {'MB':>6} {'with s':>8} {'without s':>9} "
          f"{'share':>6} {'hooks s':>7} {'hooks':>6} {'ms/frame':>8} {'CPU with':>8} {'CPU w/o':>8} {'CPU share':>9}")
    for scale, w, wo in rows:
        frames = w.get("vtu", {}).get("frames", 0) + w.get("netcdf", {}).get("frames", 0)
        share = (w["wall_time_s"] - wo["wall_time_s"]) / w["wall_time_s"]
        cpu_share = (w["process_cpu_s"] - wo["process_cpu_s"]) / w["process_cpu_s"]
        print(f"{scale:>5g} {w['n_particles']:>9} {w['steps']:>6} {frames:>6} {w['output_mb']:>6.1f} "
              f"{w['wall_time_s']:>8.2f} {wo['wall_time_s']:>9.2f} {100 * share:>5.1f}% "
              f"{w['output_s']:>7.2f} {100 * w['output_s'] / w['wall_time_s']:>5.1f}% "
              f"{1e3 * w['output_s'] / max(frames, 1):>8.1f} {w['process_cpu_s']:>8.1f} {wo['process_cpu_s']:>8.1f} "
              f"{100 * cpu_share:>8.1f}%")
    print("share = (with - without) / with, wall time of the stepping loop (summary wall_time_s); hooks = time in "
          "the output calls of the run with writers / its wall time; frames = VTU + netCDF frames written; MB = "
          "their size; CPU = user + system seconds of the whole process")


if __name__ == "__main__":
    main()
