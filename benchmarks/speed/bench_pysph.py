"""sphcore against PySPH on PySPH's own 2D dam break, whole process, side by side.

    python benchmarks/speed/bench_pysph.py [--pairs 5] [--threads 1 2] [--pysph PATH] [--t-end 0.3] [--alone]

Runs ``sph run benchmarks/speed/pysph_dam_break`` (the geometry and constants of PySPH
1.0b2's example ``dam_break_2d``: 1 m x 2 m column, 4 m tank, dx = 0.03 m, 0.3 s) and
``pysph run dam_break_2d --disable-output --tf 0.3`` alternately (``--t-end`` shortens
both), ``--pairs`` times per thread count (the order flips every pair), after one warm-up
run of each (numba's and PySPH's compiled caches). Prints the median wall time of each
code, the median of the per-pair ratios sphcore / PySPH, and the steps each took.
Threads: NUMBA_NUM_THREADS and OMP_NUM_THREADS; PySPH runs with ``--openmp`` above one
thread (serial code otherwise).

PySPH is a benchmark tool here, never a dependency of sphcore: install it in its own
virtual environment (PySPH 1.0b2 builds with Cython 3 and needs cyarray)::

    python -m venv /path/venvpysph
    /path/venvpysph/bin/pip install "cython>=3" numpy mako compyle setuptools wheel cyarray beaker pytools
    /path/venvpysph/bin/pip install --no-build-isolation pysph==1.0b2

and pass ``--pysph /path/venvpysph/bin/pysph`` (default: ``$PYSPH``, else ``pysph`` on
PATH). Without it the script says so in one line and exits with status 77 (UNAVAILABLE);
``--alone`` times sphcore alone instead. Figures are printed, never asserted: run by hand,
on a quiet machine for absolute figures.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

CASE = Path(__file__).resolve().parent / "pysph_dam_break"
#: exit status when PySPH is not found (and --alone is not given): the peer is absent
UNAVAILABLE = 77


def timed(cmd, env, cwd) -> float:
    t = time.perf_counter()
    r = subprocess.run(cmd, env=env, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    wall = time.perf_counter() - t
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(map(str, cmd))}\n{r.stdout[-2000:]}")
    return wall


def sphcore_cmd(out: Path, t_end: float):
    return [sys.executable, "-m", "sphcore.cli", "run", str(CASE), "--output", str(out), "--overwrite",
            "--progress", "off", "--t-end", repr(t_end)]


def pysph_cmd(pysph: str, out: Path, threads: int, t_end: float):
    cmd = [pysph, "run", "dam_break_2d", "--disable-output", "--tf", repr(t_end), "-d", str(out)]
    return cmd + (["--openmp"] if threads > 1 else [])


def pysph_steps(out: Path):
    """PySPH's step count: the calls of Integrator.stage1 in the profile_info.csv it writes
    even with --disable-output (one stage1 per step of its predictor-corrector)."""
    for f in out.rglob("profile_info.csv"):
        for row in f.read_text().splitlines()[1:]:
            cols = row.split(",")
            if len(cols) >= 4 and cols[2] == "Integrator.stage1":
                return int(cols[3])
    return None


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--pairs", type=int, default=5)
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--pysph", default=os.environ.get("PYSPH") or shutil.which("pysph"),
                    help="the pysph executable of a separate environment")
    ap.add_argument("--t-end", type=float, default=0.3, help="simulated time of both runs (s)")
    ap.add_argument("--alone", action="store_true", help="time sphcore alone, without PySPH")
    a = ap.parse_args()
    have_pysph = not a.alone and bool(a.pysph) and Path(a.pysph).exists()
    if not have_pysph and not a.alone:
        print(f"PySPH not found: {a.pysph or 'no pysph on PATH'} (pass --pysph PATH, see this script's docstring; "
              "--alone times sphcore alone)", file=sys.stderr)
        return UNAVAILABLE
    tmp = Path(tempfile.mkdtemp(prefix="bench_pysph"))
    peer = "alone" if a.alone else "vs PySPH dam_break_2d"
    print(f"case: {CASE} {peer}, {a.t_end:g} s, whole process, {a.pairs} pairs per thread count")
    print(f"{'threads':>7} {'sphcore s':>10} {'PySPH s':>9} {'ratio':>7} {'sphcore steps':>14} {'PySPH steps':>12}")
    for threads in a.threads:
        env = dict(os.environ, NUMBA_NUM_THREADS=str(threads), OMP_NUM_THREADS=str(threads))
        ours, theirs, ratios = [], [], []
        timed(sphcore_cmd(tmp / "sph", a.t_end), env, tmp)  # warm-up: numba's cache
        if have_pysph:
            timed(pysph_cmd(a.pysph, tmp / "pysph", threads, a.t_end), env, tmp)  # PySPH compiles its code
        for k in range(a.pairs):
            first_ours = k % 2 == 0
            for which in ((0, 1) if first_ours else (1, 0)):
                if which == 0:
                    ours.append(timed(sphcore_cmd(tmp / "sph", a.t_end), env, tmp))
                elif have_pysph:
                    theirs.append(timed(pysph_cmd(a.pysph, tmp / "pysph", threads, a.t_end), env, tmp))
            if have_pysph:
                ratios.append(ours[-1] / theirs[-1])
        steps = json.loads((tmp / "sph" / "summary.json").read_text())["steps"]
        med_t = f"{statistics.median(theirs):9.2f}" if theirs else f"{'-':>9}"
        med_r = f"{statistics.median(ratios):7.2f}" if ratios else f"{'-':>7}"
        psteps = pysph_steps(tmp / "pysph") if have_pysph else None
        print(f"{threads:>7} {statistics.median(ours):10.2f} {med_t} {med_r} {steps:>14} {psteps or '-':>12}")
    shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
