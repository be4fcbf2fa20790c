"""Fuzz the reflective boundary kernel: random trajectories through random convex domains.

Each batch is one domain (boxes turned at random, wedges down to 5 degrees, random
polygons and polyhedra, 2D and 3D), start points inside {d >= r}, displacements
log-uniform from 1e-4 to 100 domain lengths, random CR (0, 1 and in between), with and
without a random acceleration, Eq. 2 at the contact or at the end point. After the
kernel every particle is checked against every plane (d >= r - 1e-9 r).

    python benchmarks/fuzz/fuzz_reflective.py            # 10^7 trajectories
    python benchmarks/fuzz/fuzz_reflective.py --n 2e6 --batch 5e5
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

from sphcore_plugins.reflective.collision import reflect
from sphcore_plugins.reflective.corner import scratch
from sphcore_plugins.reflective.entry import face_arrays, outside_mask

sys.path.insert(0, str(Path(__file__).resolve().parents[2] / "tests"))  # the test domains
from domains import box, random_directions, random_polytope, random_rotation, sample_inside, wedge  # noqa: E402

KINDS = ("wedge5-2d", "wedge5-3d", "polytope-2d", "polytope-3d", "box-2d", "box-3d", "wedge-2d", "wedge-3d")


def make_domain(kind, rng):
    dim = 2 if kind.endswith("2d") else 3
    if kind.startswith("wedge5"):
        return wedge(5.0, 1.0, dim, height=rng.uniform(0.2, 1.0))
    if kind.startswith("wedge"):
        return wedge(rng.uniform(5.0, 170.0), 1.0, dim, height=rng.uniform(0.2, 1.0))
    if kind.startswith("polytope"):
        return random_polytope(rng, dim, int(rng.integers(dim + 1, 16)))
    return box(np.zeros(dim), rng.uniform(0.2, 2.0, dim), random_rotation(rng, dim))


def batch(rng, kind, n, cr, contact, max_reflections):
    """Run one batch; return (escaped, non-finite, guarded, reflections, kernel seconds)."""
    dom = make_domain(kind, rng)
    dim = dom.dim
    r = dom.inradius * rng.uniform(0.05, 0.9)
    radius = r * rng.uniform(0.3, 1.0, n)
    pos0 = sample_inside(rng, dom, r, n)
    length = dom.size * 10.0 ** rng.uniform(-4.0, 2.0, (n, 1))  # up to 100 domain lengths
    step = random_directions(rng, n, dim) * length
    dt = 1e-3
    vel = step / dt
    acc = np.zeros((n, dim))
    if rng.uniform() < 0.5:
        acc = random_directions(rng, n, dim) * 10.0 ** rng.uniform(-1, 4, (n, 1))
        step += 0.5 * dt * dt * acc
        vel += dt * acc
    pos = np.ascontiguousarray(pos0 + step)
    normals = np.ascontiguousarray(dom.planes.normals)
    offsets = np.ascontiguousarray(dom.planes.offsets)
    flags, counts = np.empty(n, np.int8), np.empty(n, np.int32)
    no_faces, work = face_arrays(None, dim, 1.0), scratch()
    t0 = time.perf_counter()
    guarded = reflect(pos0, pos, vel, acc, radius, normals, offsets, *no_faces, *work, float(cr),
                      int(max_reflections), bool(contact), flags, counts)[0]
    seconds = time.perf_counter() - t0
    bad = ~(np.isfinite(pos).all(axis=1) & np.isfinite(vel).all(axis=1))
    escaped = outside_mask(pos, radius, normals, offsets)
    return (int(np.count_nonzero(escaped)), int(np.count_nonzero(bad)), guarded,
            int(counts.sum(dtype=np.int64)), seconds)


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=float, default=1e7, help="trajectories in all (default 1e7)")
    ap.add_argument("--batch", type=float, default=5e5, help="trajectories per domain")
    ap.add_argument("--seed", type=int, default=20240601)
    ap.add_argument("--max-reflections", type=int, default=1000)
    ap.add_argument("--quiet", action="store_true", help="totals only")
    args = ap.parse_args(argv)
    n_total, n_batch = int(args.n), int(args.batch)
    rng = np.random.default_rng(args.seed)

    # compile (or load from the cache) outside the timing
    batch(np.random.default_rng(0), "box-2d", 10, 1.0, True, args.max_reflections)

    tried = escaped = nonfinite = guarded = reflections = 0
    kernel_s = 0.0
    wall0 = time.perf_counter()
    b = 0
    while tried < n_total:
        n = min(n_batch, n_total - tried)
        kind = KINDS[b % len(KINDS)]
        cr = (0.0, 1.0, float(rng.uniform()))[b % 3]
        contact = b % 2 == 0
        e, bad, g, refl, s = batch(rng, kind, n, cr, contact, args.max_reflections)
        tried += n
        escaped += e
        nonfinite += bad
        guarded += g
        reflections += refl
        kernel_s += s
        if not args.quiet:
            print(f"batch {b:3d} {kind:12s} cr={cr:.3f} {'contact' if contact else 'end    '} "
                  f"n={n} escaped={e} non-finite={bad} guarded={g} "
                  f"reflections/traj={refl / n:7.2f} {n / s:12.0f} traj/s", flush=True)
        b += 1
    wall = time.perf_counter() - wall0
    print(f"tried {tried} trajectories in {b} domains (2D and 3D, wedges down to 5 degrees, "
          f"displacements up to 100 domain lengths, CR in [0, 1])")
    print(f"escaped {escaped}   non-finite {nonfinite}   needed the guard {guarded} "
          f"({guarded / tried:.3%})   reflections {reflections} ({reflections / tried:.2f} per trajectory)")
    print(f"kernel time {kernel_s:.1f} s ({tried / kernel_s:,.0f} trajectories/s), wall time "
          f"{wall:.1f} s including set-up and checks")
    return 1 if escaped or nonfinite else 0


if __name__ == "__main__":
    raise SystemExit(main())
