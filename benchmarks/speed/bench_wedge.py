"""Particles pushed by gravity into an acute wedge: reflections per particle per step.

512 rigid spheres (r = 0.005 m) start in a 7-degree wedge whose walls are planes rotated
off the axes (2D and 3D; in 3D the wedge is closed by two end planes), fall under gravity
along the wedge's bisector into its apex and are stepped with the reflective kernel alone
(free motion, then ``reflect``), dt = 1e-3 s, 2,000 steps, CR = 0, 0.5 and 1. Printed per
CR: mean and maximum reflections per particle per step, guard returns, the smallest
clearance (distance - radius) at the end, and the kernel time against CR = 1.

With the paper's one-wall-at-a-time rule a particle at the apex bounces between the two
walls (with CR = 0 the projections never finish: about 825 reflections per particle per
step and the guard); a contact with both walls is now resolved as one.

    python benchmarks/speed/bench_wedge.py [--angle 7] [--steps 2000]

Figures are printed, never asserted.
"""

from __future__ import annotations

import argparse
import time

import numpy as np

from sphcore.geometry.planes import Planes
from sphcore_plugins.reflective import clearance, reflect_particles


def wedge(angle_deg, dim, turn=0.3):
    """Wedge planes with the apex at the origin, opening along +x, turned by ``turn`` rad."""
    a = np.radians(angle_deg) / 2
    n = [[np.sin(a), np.cos(a)], [np.sin(a), -np.cos(a)]]  # inward normals of y = +-tan(a) x
    if dim == 3:
        n = [v + [0.0] for v in n] + [[0.0, 0.0, 1.0], [0.0, 0.0, -1.0]]
    n = np.array(n)
    pts = np.zeros_like(n)
    if dim == 3:
        pts[2, 2], pts[3, 2] = -0.05, 0.05
    c, s = np.cos(turn), np.sin(turn)
    rot = np.eye(dim)
    rot[:2, :2] = [[c, -s], [s, c]]
    return Planes.from_lists(n @ rot.T, pts @ rot.T), rot


def run(angle, dim, cr, steps, n=512, r=0.005, dt=1e-3, seed=1):
    planes, rot = wedge(angle, dim)
    rng = np.random.default_rng(seed)
    a = np.radians(angle) / 2
    x = rng.uniform(0.3, 1.0, n)
    y = rng.uniform(-1, 1, n) * (x * np.tan(a) - r / np.cos(a)) * 0.9
    pos = np.column_stack([x, y] + ([rng.uniform(-0.04, 0.04, n)] if dim == 3 else [])) @ rot.T
    pos = np.ascontiguousarray(pos)
    g = (np.array([-9.81, 0.0] + ([0.0] if dim == 3 else [])) @ rot.T)
    acc = np.ascontiguousarray(np.tile(g, (n, 1)))
    vel = np.zeros_like(pos)
    flags, counts = np.empty(n, np.int8), np.empty(n, np.int32)
    refl, worst, guards, kernel = 0, 0, 0, 0.0
    for _ in range(steps):
        pos0 = pos.copy()
        pos += dt * vel + 0.5 * dt * dt * acc
        vel += dt * acc
        t0 = time.perf_counter()
        guards += reflect_particles(pos0, pos, vel, acc, r, planes, cr=cr, guarded_flags=flags,
                                    reflection_counts=counts)
        kernel += time.perf_counter() - t0
        refl += int(counts.sum())
        worst = max(worst, int(counts.max()))
    return refl / (n * steps), worst, guards, float(clearance(pos, r, planes).min()), kernel


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--angle", type=float, default=7.0)
    ap.add_argument("--steps", type=int, default=2000)
    a = ap.parse_args()
    run(a.angle, 2, 1.0, 2)  # compile
    run(a.angle, 3, 1.0, 2)
    print(f"512 particles into a {a.angle:g}-degree wedge under gravity, {a.steps} steps of 1 ms")
    print(f"{'dim':>3} {'CR':>4} {'refl/particle/step':>19} {'max/step':>9} {'guard':>6} "
          f"{'min clearance m':>16} {'kernel s':>9} {'vs CR=1':>8}")
    for dim in (2, 3):
        base = None
        for cr in (1.0, 0.5, 0.0):
            mean, worst, guards, clear, kt = run(a.angle, dim, cr, a.steps)
            base = base or kt
            print(f"{dim:>3} {cr:>4} {mean:>19.3f} {worst:>9d} {guards:>6d} {clear:>16.3e} {kt:>9.3f} "
                  f"{kt / base:>7.2f}x")


if __name__ == "__main__":
    main()
