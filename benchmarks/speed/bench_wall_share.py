"""Cost of wall_terms (semi-analytical wall share, gradient and T g) per particle.

A fluid block filling a box at spacing dx (particles at cell centres, h = 1.3 dx), about
10^5 particles in 2D and in 3D. Prints microseconds per particle and million particles per
second for the whole box, and for the subsets near exactly one wall (single-plane path) and
near two or more walls (edges / corners: the polygon path), each timed on its own array.

    python benchmarks/speed/bench_wall_share.py [--threads N] [--repeat R] [--sides 316 46]

``--sides`` gives the particles along a side of the 2D and of the 3D box.
"""

from __future__ import annotations

import argparse
import time

import numba
import numpy as np

from sphcore.geometry.planes import Planes
from sphcore_plugins.wall_integral.share import wall_terms


def block(dim: int, n_side: int, dx: float) -> np.ndarray:
    c = (np.arange(n_side) + 0.5) * dx
    grids = np.meshgrid(*([c] * dim), indexing="ij")
    return np.ascontiguousarray(np.stack([g.ravel() for g in grids], 1))


def timed(pos, planes, h, g, repeat):
    n, dim = pos.shape
    share, grad, hydro = np.empty(n), np.empty((n, dim)), np.empty((n, dim))
    args = (planes.normals, planes.offsets, 1, h, g, share, grad, hydro)
    wall_terms(pos, *args)  # compile / warm
    best = np.inf
    for _ in range(repeat):
        t0 = time.perf_counter()
        wall_terms(pos, *args)
        best = min(best, time.perf_counter() - t0)
    return best


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--threads", type=int, default=numba.config.NUMBA_NUM_THREADS)
    ap.add_argument("--repeat", type=int, default=20)
    ap.add_argument("--sides", type=int, nargs=2, default=[316, 46], metavar=("N2D", "N3D"),
                    help="particles along a side of the 2D and of the 3D box")
    a = ap.parse_args()
    numba.set_num_threads(a.threads)
    print(f"numba threads: {a.threads}, best of {a.repeat}, Wendland C2 kernel, h = 1.3 dx")
    print(f"{'case':<9}{'subset':<14}{'particles':>10}{'share':>8}{'us/particle':>13}{'Mparticles/s':>14}")
    for dim, n_side in zip((2, 3), a.sides):
        dx = 1.0 / n_side
        h = 1.3 * dx
        planes = Planes.box(np.zeros(dim), np.ones(dim))
        pos = block(dim, n_side, dx)
        g = np.array([0.0, -9.81, 0.0]) if dim == 2 else np.array([0.0, 0.0, -9.81])
        near = ((pos @ planes.normals.T - planes.offsets) < 2 * h).sum(1)
        subsets = {"whole box": pos, "far (0)": pos[near == 0],
                   "one plane": pos[near == 1], "2+ planes": pos[near >= 2]}
        total = None
        for name, sub in subsets.items():
            if len(sub) == 0:  # a box a few h wide has no particle far from every wall
                print(f"{dim}D box  {name:<14}{0:>10}{0:>8.1%}{'-':>13}{'-':>14}")
                continue
            sub = np.ascontiguousarray(sub)
            t = timed(sub, planes, h, g, a.repeat)
            total = t if total is None else total
            print(f"{dim}D box  {name:<14}{len(sub):>10}{len(sub) / len(pos):>8.1%}"
                  f"{1e6 * t / len(sub):>13.4f}{len(sub) / t / 1e6:>14.1f}")
        print(f"{dim}D box  whole box per step: {1e3 * total:.3f} ms for {len(pos)} particles")


if __name__ == "__main__":
    main()
