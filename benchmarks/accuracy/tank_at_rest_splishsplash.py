"""Water at rest with DFSPH, sphcore against SPlisHSPlasH: how far the particles move.

    python benchmarks/accuracy/tank_at_rest_splishsplash.py [--t-end 5] [--dx 0.02] [--threads 1]
        [--set SECTION.KEY=VALUE ...] [--sphcore-only]

A 3D cube of water 0.4 m deep in a box 0.4 m x 0.6 m x 0.4 m (y up), dx = 0.02 m, at rest
from the start, both codes with their DFSPH and default tolerances (0.01 % density, 0.1 %
divergence). sphcore runs a case written here (``[scheme] name = "dfsph"``, reflective
walls with the wall model, 8,000 particles); SPlisHSPlasH 2.19.0 a scene written by
:mod:`bench_splishsplash`'s rules (volume-map walls, its fluid 2 dx off the walls: 6,859
particles), with particle ids exported once a second. Each code's positions are read by
particle id every second; the script prints, per second, the largest and the mean
displacement in dx since the start and since t = 1 s (after the first settling: a lattice
block is not at its code's rest density), and the largest speed; then, at the last frame,
where the particles moved: the mean and largest displacement and the mean vertical one of
the particles that started in the first layer along the side walls, along the vertical
edges (two side walls), on the floor, in the top layer and in the interior.

``--set`` passes case overrides to sphcore's run (``reflective.cr=0``,
``particles.radius=0.005``, ``scheme.density_tolerance=1e-5``, ``'domain.max=[0.4,0.4,0.4]'``
for a closed box full of water, ...), and ``--sphcore-only`` leaves SPlisHSPlasH out (no
install needed).

SPlisHSPlasH is a benchmark tool here, installed by ``bench_splishsplash.py``'s rules into
its own environment (``--splish-venv``). Figures are printed, never asserted.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import tempfile
from pathlib import Path

import numpy as np

HERE = Path(__file__).resolve().parent
sys.path.insert(0, str(HERE.parent / "speed"))

from bench_splishsplash import BOX_OBJ, DRIVER, GAP, gldispatch, install, timed  # noqa: E402

DEPTH, WIDTH, HEIGHT = 0.4, 0.4, 0.6  # m: water depth, tank width (x and z), tank height

CASE = """[case]
name = "tank_at_rest_3d"
dim = 3

[domain]
min = [0.0, 0.0, 0.0]
max = [{w}, {h}, {w}]

[[blocks]]
min = [0.0, 0.0, 0.0]
max = [{w}, {d}, {w}]

[particles]
dx = {dx}

[fluid]
rho0 = 1000.0
nu = 1.0e-6

[scheme]
name = "dfsph"

[time]
t_end = {t_end}

[plugins]
use = ["reflective", "wall_integral", "netcdf"]

[netcdf]
every_dt = 1.0
"""


def splash_scene(folder: Path, dx: float, t_end: float) -> Path:
    """SPlisHSPlasH's scene of the same tank: its fluid block GAP dx off the walls."""
    (folder / "tank.obj").write_text(BOX_OBJ)
    size = [WIDTH, HEIGHT, WIDTH]
    first = GAP * dx
    n = [round(DEPTH / dx - 2 * GAP) + 1, round(DEPTH / dx - GAP), round(DEPTH / dx - 2 * GAP) + 1]
    config = {"particleRadius": dx / 2, "simulationMethod": 4, "gravitation": [0, -9.81, 0], "cflMethod": 1,
              "cflFactor": 1.0, "cflMaxTimeStepSize": 0.005, "maxError": 0.01, "maxErrorV": 0.1,
              "enableDivergenceSolver": True, "boundaryHandlingMethod": 2, "stopAt": t_end,
              "enablePartioExport": False, "enableVTKExport": True, "dataExportFPS": 1,
              "particleAttributes": "velocity;id", "enableZSort": False, "enableRigidBodyExport": False}
    data = {"Configuration": config,
            "Materials": [{"id": "Fluid", "density0": 1000, "viscosityMethod": 1,
                           "Standard viscosity": {"viscosity": 0.01}}],
            "RigidBodies": [{"geometryFile": "tank.obj", "translation": [0, 0, 0], "scale": size,
                             "isDynamic": False, "isWall": True, "mapInvert": True, "mapThickness": 0.0,
                             "mapResolution": [max(1, round(s / (2 * dx))) for s in size]}],
            "FluidBlocks": [{"denseMode": 0, "start": [first - dx] * 3,
                             "end": [first + k * dx for k in n]}]}
    path = folder / "scene.json"
    path.write_text(json.dumps(data, indent=1))
    return path


def splash_frames(out: Path) -> list[tuple[np.ndarray, np.ndarray]]:
    """(positions, velocities) sorted by particle id, one per exported second."""
    import meshio

    files = sorted((out / "vtk").glob("ParticleData_Fluid_*.vtk"), key=lambda f: int(f.stem.rsplit("_", 1)[1]))
    frames = []
    for f in files:
        m = meshio.read(f)
        order = np.argsort(m.point_data["id"].astype(np.int64).ravel())
        frames.append((np.asarray(m.points)[order], np.asarray(m.point_data["velocity"])[order]))
    return frames


def sph_frames(out: Path) -> list[tuple[np.ndarray, np.ndarray]]:
    import xarray as xr

    with xr.open_dataset(out / "particles.nc") as ds:  # particles sorted by id
        return [(ds["position"].values[k], ds["velocity"].values[k]) for k in range(ds.sizes["time"])]


def report(name: str, frames, dx: float) -> None:
    p0, p1 = frames[0][0], frames[min(1, len(frames) - 1)][0]
    print(f"{name}: {p0.shape[0]} particles")
    print(f"{'t s':>4} {'max from 0':>11} {'mean from 0':>12} {'max from 1 s':>13} {'mean from 1 s':>14} {'|v| max m/s':>12}")
    for k, (p, v) in enumerate(frames):
        d0, d1 = np.linalg.norm(p - p0, axis=1) / dx, np.linalg.norm(p - p1, axis=1) / dx
        late = k >= 1
        print(f"{k:>4} {d0.max():11.3f} {d0.mean():12.4f} {d1.max() if late else float('nan'):13.3f} "
              f"{d1.mean() if late else float('nan'):14.4f} {np.linalg.norm(v, axis=1).max():12.3e}")


def regions(p0: np.ndarray, dx: float) -> dict[str, np.ndarray]:
    """Masks of the particles by where they started, against the block's first frame: in the
    first row along one side wall (x or z; "side"), along two ("edge"), on the floor, in the
    top layer, or none (a row: within dx / 2 of the block's outermost particles)."""
    lo, hi = p0.min(axis=0), p0.max(axis=0)
    row = 0.5 * dx
    near = [(p0[:, k] - lo[k] < row) | (hi[k] - p0[:, k] < row) for k in range(3)]
    sides = near[0].astype(int) + near[2]
    floor, top = p0[:, 1] - lo[1] < row, hi[1] - p0[:, 1] < row
    return {"side": (sides == 1) & ~top & ~floor, "edge": (sides == 2) & ~top & ~floor, "floor": floor & ~top,
            "top": top, "interior": (sides == 0) & ~top & ~floor}


def report_regions(frames, dx: float) -> None:
    p0, p = frames[0][0], frames[-1][0]
    d = np.linalg.norm(p - p0, axis=1) / dx
    dy = (p[:, 1] - p0[:, 1]) / dx
    print(f"{'region':>9} {'particles':>10} {'mean':>8} {'max':>8} {'mean dy':>8}  (at the last frame, in dx)")
    for name, m in regions(p0, dx).items():
        if m.any():
            print(f"{name:>9} {int(m.sum()):10d} {d[m].mean():8.3f} {d[m].max():8.3f} {dy[m].mean():+8.3f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--t-end", type=float, default=5.0)
    ap.add_argument("--dx", type=float, default=0.02)
    ap.add_argument("--threads", type=int, default=1)
    ap.add_argument("--splish-venv", type=Path, default=Path("/tmp/splishsplash-venv"))
    ap.add_argument("--splish-version", default="2.19.0")
    ap.add_argument("--gldispatch", help="path of libGLdispatch.so.0 (default: searched)")
    ap.add_argument("--set", dest="overrides", action="append", default=[], metavar="SECTION.KEY=VALUE",
                    help="a case override for sphcore's run (repeatable)")
    ap.add_argument("--sphcore-only", action="store_true", help="run sphcore alone (SPlisHSPlasH not installed)")
    a = ap.parse_args(argv)
    py = splash_env = None
    if not a.sphcore_only:
        splash_env = dict(os.environ, LD_PRELOAD=gldispatch(a.gldispatch), OMP_NUM_THREADS=str(a.threads))
        py = install(a.splish_venv, a.splish_version, splash_env)
    with tempfile.TemporaryDirectory(prefix="tank_at_rest") as tmp:
        tmp = Path(tmp)
        case = tmp / "case"
        case.mkdir()
        (case / "case.toml").write_text(CASE.format(w=WIDTH, h=HEIGHT, d=DEPTH, dx=a.dx, t_end=a.t_end))
        env = dict(os.environ, NUMBA_NUM_THREADS=str(a.threads))
        sets = [x for o in a.overrides for x in ("--set", o)]
        timed([sys.executable, "-m", "sphcore.cli", "run", str(case), "--output", str(tmp / "sph"), "--progress",
               "off", *sets], env, tmp)
        print(f"water at rest, {DEPTH} m deep, dx = {a.dx} m, {a.t_end:g} s; displacements in dx")
        if a.overrides:
            print("sphcore's overrides: " + " ".join(a.overrides))
        frames = sph_frames(tmp / "sph")
        report("sphcore dfsph", frames, a.dx)
        report_regions(frames, a.dx)
        if py is None:
            return 0
        splash = tmp / "splash"
        splash.mkdir()
        scene = splash_scene(splash, a.dx, a.t_end)
        timed([str(py), "-c", DRIVER, "--no-gui", "--no-initial-pause", "--output-dir", str(splash / "out"),
               "--stopAt", repr(a.t_end), str(scene)], splash_env, tmp)
        frames = splash_frames(splash / "out")
        report(f"SPlisHSPlasH {a.splish_version} DFSPH", frames, a.dx)
        report_regions(frames, a.dx)
    return 0


if __name__ == "__main__":
    sys.exit(main())
