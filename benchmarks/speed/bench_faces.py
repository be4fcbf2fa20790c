"""Cost of the reflective kernel against wall faces, by the number of faces.

A 3D block of water at rest (about 10^5 particles, dx = 0.01 m) in a box tank, with a
submerged obstacle: a sphere of radius 0.1 m triangulated with about F faces (F = 0: no
obstacle, the planes alone). Per F: the median wall time of a full step, and of the
reflective kernel alone on that step's motion (start = end - dt v, the drift of the
step), and the kernel's share of the step. The cost should not grow with F: each
particle tests only the faces listed in the grid cells around it.

    python benchmarks/speed/bench_faces.py [--faces 0 80 1000 10000] [--steps 5] [--repeat 5] [--dx 0.01]
    python benchmarks/speed/bench_faces.py --wall-model     # the wall model's share instead

With ``--wall-model`` each F runs the case with reflective walls alone and with the wall
model (``wall_integral``: planes and faces; the faces' terms exact and from the table, see
``--face-terms``) in alternation and prints the wall model's share of a step,
(t_model - t_alone) / t_model, medians, and the first step's wall time (numba compile from
the cache, and for the table its construction).

Figures are printed, never asserted: run by hand on a quiet machine.
"""

from __future__ import annotations

import argparse
import statistics
import sys
import tempfile
import time
from pathlib import Path

import meshio
import numpy as np

from sphcore.run import runner
from sphcore.run.build import build
from sphcore_plugins.reflective.collision import reflect
from sphcore_plugins.reflective.corner import scratch
from sphcore_plugins.reflective.entry import face_arrays

CASE = """
[case]
dim = 3
[domain]
min = [0.0, 0.0, 0.0]
max = [0.6, 0.6, 0.6]
{walls}
[[blocks]]
min = [0.0, 0.0, 0.0]
max = [0.5, 0.5, 0.42]
[particles]
dx = {dx}
[physics]
gravity = [0.0, 0.0, -9.81]
modified_pressure = false
[time]
t_end = 10.0
[output]
progress = "off"
[plugins]
use = {plugins}
"""


def sphere_mesh(path: Path, faces: int, centre=(0.25, 0.25, 0.2), radius=0.1) -> int:
    """A UV sphere of about ``faces`` triangles written to ``path`` (STL); its face count."""
    m = max(int(round(0.5 + np.sqrt(0.25 + faces / 4.0))), 3)  # rings; 4 m (m - 1) triangles
    k = 2 * m
    th = np.linspace(0.0, np.pi, m + 1)[1:-1]
    ph = np.linspace(0.0, 2 * np.pi, k, endpoint=False)
    pts = [[0.0, 0.0, 1.0]]
    pts += [[np.sin(t) * np.cos(p), np.sin(t) * np.sin(p), np.cos(t)] for t in th for p in ph]
    pts.append([0.0, 0.0, -1.0])
    pts = np.asarray(pts) * radius + np.asarray(centre)
    ring = lambda i, j: 1 + i * k + (j % k)  # noqa: E731
    tris = [(0, ring(0, j), ring(0, j + 1)) for j in range(k)]
    for i in range(m - 2):
        for j in range(k):
            tris += [(ring(i, j), ring(i + 1, j), ring(i + 1, j + 1)), (ring(i, j), ring(i + 1, j + 1), ring(i, j + 1))]
    last = len(pts) - 1
    tris += [(last, ring(m - 2, j + 1), ring(m - 2, j)) for j in range(k)]
    meshio.write(path, meshio.Mesh(pts, [("triangle", np.asarray(tris))]))
    return len(tris)


def setup(tmp: Path, faces: int, dx: float, plugins='["reflective"]', sets=()):
    d = tmp / f"f{faces}{len(plugins)}{len(sets) and sets[0][-5:]}"
    d.mkdir()
    walls = ""
    count = 0
    if faces:
        count = sphere_mesh(d / "sphere.stl", faces)
        walls = '[[domain.walls]]\nshape = "mesh"\nfile = "sphere.stl"'
    (d / "case.toml").write_text(CASE.format(walls=walls, plugins=plugins, dx=dx))
    case, pm = runner.load(d, list(sets))
    sim = build(case, pm)
    t0 = time.perf_counter()
    sim.advance()  # compile, warm caches (and build the wall model's face table)
    sim.first_step_s = time.perf_counter() - t0
    return sim, count, case


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--faces", type=int, nargs="+", default=[0, 80, 1000, 10000])
    ap.add_argument("--steps", type=int, default=5)
    ap.add_argument("--repeat", type=int, default=5)
    ap.add_argument("--dx", type=float, default=0.01, help="particle spacing (m): 0.01 is about 10^5 particles")
    ap.add_argument("--wall-model", action="store_true", help="the wall model's share of a step")
    ap.add_argument("--face-terms", nargs="+", default=["exact", "table"], choices=["exact", "table"],
                    help="with --wall-model: wall_integral.faces values to measure")
    a = ap.parse_args()
    import numba

    if a.wall_model:
        return wall_model_share(a)

    with tempfile.TemporaryDirectory() as tmp:
        print(f"3D water at rest, a submerged sphere of F faces, numba threads={numba.get_num_threads()}, "
              f"median of {a.repeat}")
        print(f"{'faces':>7} {'particles':>9} {'step ms':>9} {'kernel ms':>10} {'share':>7}")
        for f in a.faces:
            sim, count, case = setup(Path(tmp), f, a.dx)
            st = sim.state
            fa = face_arrays(case.faces if count else None, 3, float(st.radius.max()))
            ws = scratch()
            planes = case.planes
            steps, kern = [], []
            for _ in range(a.repeat):
                t0 = time.perf_counter()
                for _ in range(a.steps):
                    sim.advance()
                steps.append((time.perf_counter() - t0) / a.steps)
                pos = np.ascontiguousarray(st.pos)
                pos0 = np.ascontiguousarray(pos - sim.dt * st.vel)
                acc = np.zeros_like(pos)
                flags, counts = np.empty(st.n, np.int8), np.empty(st.n, np.int32)
                total = 0.0
                for _ in range(a.steps):
                    p, v = pos.copy(), np.ascontiguousarray(st.vel).copy()
                    t0 = time.perf_counter()
                    reflect(pos0, p, v, acc, st.radius, planes.normals, planes.offsets, *fa, *ws, 1.0, 1000, True,
                            flags, counts)
                    total += time.perf_counter() - t0
                kern.append(total / a.steps)
            ts, tk = statistics.median(steps), statistics.median(kern)
            print(f"{count:>7} {st.n:>9} {1e3 * ts:>9.2f} {1e3 * tk:>10.3f} {100 * tk / ts:>6.1f}%")
            sys.stdout.flush()


def per_step(sim, steps):
    t0 = time.perf_counter()
    for _ in range(steps):
        sim.advance()
    return (time.perf_counter() - t0) / steps


def wall_model_share(a):
    import numba

    with tempfile.TemporaryDirectory() as tmp:
        print(f"3D water at rest, a submerged sphere of F faces, numba threads={numba.get_num_threads()}, "
              f"median of {a.repeat} alternating runs of {a.steps} steps, plain Tait; the wall model's faces "
              f"{' / '.join(a.face_terms)} (wall_integral.faces)")
        print(f"{'faces':>7} {'particles':>9} {'alone ms':>9}" + "".join(
            f" {m + ' ms':>10} {'share':>7} {'first s':>8}" for m in a.face_terms))
        for f in a.faces:
            alone, count, _ = setup(Path(tmp), f, a.dx)
            models = [setup(Path(tmp), f, a.dx, '["reflective", "wall_integral"]', [f"wall_integral.faces={m!r}"])[0]
                      for m in a.face_terms]
            ta, tm = [], [[] for _ in models]
            for _ in range(a.repeat):
                ta.append(per_step(alone, a.steps))
                for k, model in enumerate(models):
                    tm[k].append(per_step(model, a.steps))
            t0 = statistics.median(ta)
            row = f"{count:>7} {alone.state.n:>9} {1e3 * t0:>9.2f}"
            for model, times in zip(models, tm):
                t1 = statistics.median(times)
                row += f" {1e3 * t1:>10.2f} {100 * (t1 - t0) / t1:>6.1f}% {model.first_step_s:>8.2f}"
            print(row)
            sys.stdout.flush()


if __name__ == "__main__":
    main()
