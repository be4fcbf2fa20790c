"""sphcore's DFSPH against SPlisHSPlasH's DFSPH on the 3D dam break, whole process, side by side.

    python benchmarks/speed/bench_splishsplash.py [--pairs 3] [--threads 1 2] [--t-end 0.3] [--set KEY=VALUE ...]

The case is ``cases/dam_break_3d`` (0.42 m x 0.44 m x 0.228 m tank, 0.114 m x 0.228 m
column across the full depth, dx = 0.007125 m, y up). sphcore runs it as
``python -m sphcore.cli run cases/dam_break_3d --t-end T --set scheme.name="dfsph"
--set plugins.use=["reflective","wall_integral","front_gauge"]`` plus the ``--set`` given
here (``--set kernel.h_over_dx=1.0 --set scheme.cfl=0.4`` match SPlisHSPlasH's kernel
support and time step). SPlisHSPlasH 2.19.0 runs the same tank in a scene written by this
script: DFSPH (``simulationMethod`` 4), particleRadius = dx / 2 (its cubic kernel's support
is 4 particleRadius = 2 dx), dt = 0.4 dx / |v| at most 5 ms (``cflFactor`` 1 times its
formula's own 0.4 particle diameters), density and divergence tolerances 0.01 % and 0.1 %
(sphcore's defaults of ``scheme.density_tolerance`` and ``divergence_tolerance``; SPlisHSPlasH
counts compression only, which ``--set 'scheme.error="compression"'`` asks of sphcore), standard
viscosity 0.01, the tank a volume map (Bender et al. 2019, one cell per kernel support),
no particle output. Its fluid is unstable when its first layer starts closer than two dx to
a wall: the column keeps its 16 x 32 layers, moved 1.5 dx off the back wall and the floor, and
loses three layers across the depth (14848 particles against sphcore's 16384; both printed).

SPlisHSPlasH is a benchmark tool here, never a dependency of sphcore: the script installs
``pysplishsplash==--splish-version`` with pip into its own virtual environment
(``--splish-venv``, made with ``python -m venv``; skipped when that environment already
imports it). Its wheel needs the system's libGLdispatch.so.0 preloaded (found in the usual
library folders or by ``ldconfig -p``, or given by ``--gldispatch``); the preload is set for
SPlisHSPlasH's process only. Its simulator runs headless, as the ``splash`` entry point
does without its file dialog (which needs tkinter): ``python -c DRIVER --no-gui
--no-initial-pause --output-dir OUT --stopAt T scene.json``. The volume map is built by a
short warm-up run and cached beside the scene (``--no-cache`` rebuilds it in every run,
timing it too); sphcore's warm-up run fills numba's cache.

For each thread count (NUMBA_NUM_THREADS for sphcore, OMP_NUM_THREADS for SPlisHSPlasH),
``--pairs`` pairs run alternately (the order flips every pair); the table gives the median
wall time of each whole process, the median of the per-pair ratios sphcore / SPlisHSPlasH,
the steps each took, the time each spent in its time loop (sphcore's ``wall_time_s``,
SPlisHSPlasH's summed ``SimStep`` timer) and sphcore's front errors against Cruchaga at 0.1 s and 0.2 s and
Martin & Moyce (RMS, T up to 3). Figures are printed, never asserted: run on a quiet machine.
"""

from __future__ import annotations

import argparse
import json
import os
import re
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
import tomllib
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]
CASE = ROOT / "cases" / "dam_break_3d"
PLUGINS = '["reflective","wall_integral","front_gauge"]'
GAP = 2.0  # SPlisHSPlasH's first fluid layer from a wall, in dx
DRIVER = ("import sys, pysplishsplash as sph; b = sph.Exec.SimulatorBase(); "
          "b.init(sys.argv, 'SPlisHSPlasH'); b.run(); del b")  # del: prints its timers
GL_DIRS = ("/usr/lib/x86_64-linux-gnu", "/lib/x86_64-linux-gnu", "/usr/lib64", "/lib64", "/usr/lib")
# unit box, faces wound outwards; the scene scales it to the tank
BOX_OBJ = "".join(f"v {x} {y} {z}\n" for z in (0, 1) for y in (0, 1) for x in (0, 1)) + \
    "f 1 3 4\nf 1 4 2\nf 5 6 8\nf 5 8 7\nf 1 2 6\nf 1 6 5\nf 3 7 8\nf 3 8 4\nf 1 5 7\nf 1 7 3\nf 2 4 8\nf 2 8 6\n"


def gldispatch(given: str | None) -> str:
    """The system's libGLdispatch.so.0, which SPlisHSPlasH's wheel must have preloaded."""
    if given:
        return given
    for d in GL_DIRS:
        if (Path(d) / "libGLdispatch.so.0").exists():
            return str(Path(d) / "libGLdispatch.so.0")
    try:
        listing = subprocess.run(["ldconfig", "-p"], capture_output=True, text=True).stdout
    except OSError:
        listing = ""
    m = re.search(r"libGLdispatch\.so\.0 .*=> (\S+)", listing)
    if m:
        return m.group(1)
    sys.exit("libGLdispatch.so.0 not found (in " + ", ".join(GL_DIRS) + " or ldconfig -p): install the "
             "system's libglvnd (e.g. apt-get install libglvnd0) or pass --gldispatch PATH")


def install(venv: Path, version: str, env: dict) -> Path:
    """``venv``'s python, with pysplishsplash ``version`` installed there (pip, once)."""
    py = venv / "bin" / "python"
    check = [str(py), "-c", f"import importlib.metadata as m, pysplishsplash; "
                            f"assert m.version('pysplishsplash') == {version!r}"]
    if py.exists() and subprocess.run(check, env=env, capture_output=True).returncode == 0:
        return py
    print(f"installing pysplishsplash=={version} into {venv}", flush=True)
    subprocess.run([sys.executable, "-m", "venv", str(venv)], check=True)
    subprocess.run([str(py), "-m", "pip", "install", "--quiet", f"pysplishsplash=={version}"], check=True)
    r = subprocess.run(check, env=env, capture_output=True, text=True)
    if r.returncode != 0:
        sys.exit(f"pysplishsplash {version} installed in {venv} but does not import:\n{r.stderr[-2000:]}")
    return py


def scene(folder: Path, t_end: float) -> Path:
    """SPlisHSPlasH's scene of the case (see the module's docstring); its path."""
    case = tomllib.loads((CASE / "case.toml").read_text())
    dx, tank, block = case["particles"]["dx"], case["domain"], case["blocks"][0]
    size = [b - a for a, b in zip(tank["min"], tank["max"])]
    start, end = [], []
    for a, b, lo, hi in zip(block["min"], block["max"], tank["min"], tank["max"]):
        n = round((b - a) / dx)  # sphcore's layers
        if b >= hi - 0.5 * dx:  # the column spans the tank: two dx off both walls
            n = min(n, round((hi - lo) / dx - 2 * GAP) + 1)
        first = lo + GAP * dx
        # a block [s, e] holds round((e - s) / dx) - 1 layers, the first at s + dx
        start.append(first - dx)
        end.append(first + n * dx)
    cells = [max(1, round(s / (2 * dx))) for s in size]  # one volume-map cell per support
    (folder / "tank.obj").write_text(BOX_OBJ)
    config = {"particleRadius": dx / 2, "simulationMethod": 4, "gravitation": case["physics"]["gravity"],
              "cflMethod": 1, "cflFactor": 1.0, "cflMaxTimeStepSize": 0.005, "maxError": 0.01, "maxErrorV": 0.1,
              "enableDivergenceSolver": True, "boundaryHandlingMethod": 2, "stopAt": t_end,
              "enablePartioExport": False, "enableVTKExport": False, "enableRigidBodyExport": False}
    data = {"Configuration": config,
            "Materials": [{"id": "Fluid", "density0": 1000, "viscosityMethod": 1,
                           "Standard viscosity": {"viscosity": 0.01}}],
            "RigidBodies": [{"geometryFile": "tank.obj", "translation": tank["min"], "scale": size,
                             "isDynamic": False, "isWall": True, "mapInvert": True, "mapThickness": 0.0,
                             "mapResolution": cells}],
            "FluidBlocks": [{"denseMode": 0, "start": start, "end": end}]}
    path = folder / "scene.json"
    path.write_text(json.dumps(data, indent=1))
    return path


def timed(cmd, env, cwd) -> tuple[float, str]:
    """The wall time of ``cmd``'s whole process and what it printed; exits if it failed."""
    t = time.perf_counter()
    r = subprocess.run(cmd, env=env, cwd=cwd, stdout=subprocess.PIPE, stderr=subprocess.STDOUT, text=True)
    wall = time.perf_counter() - t
    if r.returncode != 0:
        sys.exit(f"failed ({r.returncode}): {' '.join(map(str, cmd))}\n{r.stdout[-3000:]}")
    return wall, r.stdout


def splash_figures(out: str) -> tuple[int | None, int | None, float | None]:
    """Particles, steps and the summed SimStep time (s) SPlisHSPlasH printed."""
    def num(pattern):
        m = re.search(pattern, out)
        return float(m.group(1)) if m else None
    n = num(r"Number of fluid particles: (\d+)")
    total, mean = num(r"Time sum: SimStep: ([\d.e+-]+) ms"), num(r"Average time: SimStep: ([\d.e+-]+) ms")
    steps = round(total / mean) if total and mean else None
    return (int(n) if n is not None else None), steps, (total / 1e3 if total is not None else None)


def pct(x, width: int, sign: str = "+") -> str:
    """A front error in percent, right-aligned in ``width``; '-' when the run did not reach it."""
    return f"{x:{sign}{width}.1%}" if x is not None and x == x else f"{'-':>{width}}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--pairs", type=int, default=3, help="sphcore/SPlisHSPlasH runs, alternating")
    ap.add_argument("--threads", type=int, nargs="+", default=[1, 2])
    ap.add_argument("--t-end", type=float, default=0.3, help="simulated time of both runs (s)")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="KEY=VALUE",
                    help="passed to sph run (repeatable), e.g. kernel.h_over_dx=1.0")
    ap.add_argument("--splish-venv", type=Path, default=Path("/tmp/splishsplash-venv"),
                    help="SPlisHSPlasH's own virtual environment (made when absent)")
    ap.add_argument("--splish-version", default="2.19.0")
    ap.add_argument("--gldispatch", help="path of libGLdispatch.so.0 (default: searched)")
    ap.add_argument("--no-cache", action="store_true", help="SPlisHSPlasH rebuilds its volume map every run")
    a = ap.parse_args(argv)
    splash_env = dict(os.environ, LD_PRELOAD=gldispatch(a.gldispatch))
    py = install(a.splish_venv, a.splish_version, splash_env)
    tmp = Path(tempfile.mkdtemp(prefix="bench_splishsplash"))
    sph_out, splash_dir = tmp / "sph", tmp / "splash"
    splash_dir.mkdir()
    scene_file = scene(splash_dir, a.t_end)
    sets = ['scheme.name="dfsph"', f"plugins.use={PLUGINS}", *a.overrides]

    def sph_cmd(t_end):
        return [sys.executable, "-m", "sphcore.cli", "run", str(CASE), "--output", str(sph_out), "--overwrite",
                "--progress", "off", "--t-end", repr(t_end)] + [x for s in sets for x in ("--set", s)]

    def splash_cmd(t_end):
        return [str(py), "-c", DRIVER, "--no-gui", "--no-initial-pause", "--output-dir", str(splash_dir / "out"),
                "--stopAt", repr(t_end), str(scene_file)] + (["--no-cache"] if a.no_cache else [])

    warm = min(a.t_end, 0.01)  # numba's cache; SPlisHSPlasH's volume map
    env = dict(os.environ, NUMBA_NUM_THREADS=str(a.threads[0]))
    timed(sph_cmd(warm), env, tmp)
    n_splash = splash_figures(timed(splash_cmd(warm), dict(splash_env, OMP_NUM_THREADS=str(a.threads[0])), tmp)[1])[0]
    n_sph = json.loads((sph_out / "summary.json").read_text())["n_particles"]
    print(f"case: {CASE}, {a.t_end:g} s, sphcore dfsph {' '.join('--set ' + s for s in a.overrides) or '(case)'}; "
          f"SPlisHSPlasH {a.splish_version} DFSPH; {a.pairs} pairs per thread count, whole process")
    print(f"particles: sphcore {n_sph}, SPlisHSPlasH {n_splash}")
    print(f"{'threads':>7} {'sphcore s':>10} {'SPlisH s':>9} {'ratio':>6} {'sph steps':>9} {'SPlisH steps':>12} "
          f"{'sph loop s':>10} {'SPlisH loop s':>13} {'Cruchaga 0.1s':>13} {'0.2s':>7} {'M&M rms':>7}")
    for threads in a.threads:
        ours_env = dict(os.environ, NUMBA_NUM_THREADS=str(threads), OMP_NUM_THREADS=str(threads))
        theirs_env = dict(splash_env, OMP_NUM_THREADS=str(threads))
        ours, theirs, ratios, runs = [], [], [], {}
        for k in range(a.pairs):
            for which in (("sph", "splash") if k % 2 == 0 else ("splash", "sph")):
                if which == "sph":
                    wall, runs["sph"] = timed(sph_cmd(a.t_end), ours_env, tmp)
                    ours.append(wall)
                else:
                    wall, runs["splash"] = timed(splash_cmd(a.t_end), theirs_env, tmp)
                    theirs.append(wall)
            ratios.append(ours[-1] / theirs[-1])
        s = json.loads((sph_out / "summary.json").read_text())
        front = s.get("front_gauge", {})
        _, steps, loop = splash_figures(runs["splash"])
        errs = [pct(front.get("err_cruchaga_0.10s"), 13), pct(front.get("err_cruchaga_0.20s"), 7),
                pct(front.get("rms_rel_err_martin_moyce_T3"), 7, "")]
        print(f"{threads:>7} {statistics.median(ours):10.2f} {statistics.median(theirs):9.2f} "
              f"{statistics.median(ratios):6.2f} {s['steps']:>9} {steps or '-':>12} {s['wall_time_s']:10.2f} "
              f"{loop or float('nan'):13.2f} {' '.join(errs)}")
    shutil.rmtree(tmp, ignore_errors=True)
    return 0


if __name__ == "__main__":
    sys.exit(main())
