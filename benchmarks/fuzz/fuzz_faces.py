"""Fuzz the reflective boundary with finite wall faces (segments, triangles), 2D and 3D.

Random trajectories through random tanks with obstacles, non-convex tanks given by faces
only, and tanks split by thin plates.

Every batch (``--batch`` trajectories) is spread evenly over the domain kinds below, each
in 2D and 3D, with a fresh random domain every ``--per-domain`` trajectories:

- ``obstacles``: a box tank (planes) with 1 to 6 random box obstacles given as closed
  faces (fluid outside), half of them turned at random; they may overlap each other and
  the tank walls.
- ``nonconvex``: a tank given by faces only (no planes): in 2D a random simple star-shaped
  polygon with sharp spikes and sharp concave corners, in 3D a closed triangle mesh of a
  step- or L-shaped tank (a random height map of boxes, turned at random in half of them).
- ``plate``: a box tank split in two by a closed plate whose thickness is exactly one
  particle diameter 2r (all particles of radius r), turned at random in half of them and
  reaching just beyond the tank; a particle that ends on the other side of the plate than
  it started is *crossed* (an escape too).
- ``sheet``: the same with an open wall of zero thickness (a segment, two triangles).

Every domain is shifted by up to 10 domain lengths from the origin. Start points are drawn
uniformly in the tank and kept where admissible; 10% (``--on-wall``) are put at distance r
from a random wall (touching it; where all particles of the domain have one radius). Displacements are log-uniform from 1e-4 to 100 domain lengths in
random directions (2% at rest); CR is 0 for 20% of the domains, 1 for 20%, uniform in
[0, 1] otherwise; half the domains with a random acceleration (as in fuzz_reflective.py),
half with Eq. 2 at the contact and half at the end point.

A trajectory *escaped* when its end point is not admissible: beyond a plane
(d < r - 1e-9 r), closer than r - 1e-9 r to a face, or not on the fluid side of a closed
wall (winding number). *Non-finite*: NaN or inf in the position or velocity. The guard
share is guarded / trajectories. Kernel time counts only the call of ``reflect_particles``
(the face grid is built before, and the kernel runs parallel whatever the domain's size);
domain set-up, sampling and checks are outside it. The first line of each domain with a
failure is printed (FAILURE ...). Exit status 1 on any escape, crossing or non-finite.

The starts on the walls matter: a sub-segment starting within an ulp of r from a slanted
face once passed through it (about 1 in 1,000 such starts; tests/test_reflective_faces.py,
test_touching_*); ``--on-wall 0`` leaves such starts only to contact points in corners.

    python benchmarks/fuzz/fuzz_faces.py                 # 10^7 trajectories
    python benchmarks/fuzz/fuzz_faces.py --n 2e5
"""

from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path

import numpy as np

sys.path.insert(0, str(Path(__file__).resolve().parent))
from fuzz_domains import KINDS, admissible, make_scene  # noqa: E402  (the random domains)

from sphcore.jit import parallel  # noqa: E402
from sphcore_plugins.reflective import entry  # noqa: E402


def side(dom, pos):
    """(n,) sign of each point's side of the plate's mid-plane (0 without a plate)."""
    if dom.plate_normal is None:
        return np.zeros(pos.shape[0])
    return np.sign((pos - dom.plate_point) @ dom.plate_normal)


def check(scene, pos, vel):
    """(escaped, crossed, non-finite) masks of the kernel's result."""
    bad = ~(np.isfinite(pos).all(axis=1) & np.isfinite(vel).all(axis=1))
    escaped = ~admissible(scene.dom, np.where(bad[:, None], scene.pos0, pos), scene.radius) | bad
    crossed = side(scene.dom, pos) != side(scene.dom, scene.pos0)
    if scene.dom.plate_normal is None:
        crossed[:] = False
    return escaped & ~bad, crossed & ~bad, bad


def run_scene(scene, max_reflections=1000):
    """Run the kernel on a scene (through ``reflect_particles``); returns pos, vel, guard
    flags, reflection counts and the seconds of that call. The face grid is built before
    the clock starts and handed in, so the time is the kernel's (and the argument checks')."""
    dom, n = scene.dom, scene.radius.size
    fa = entry.face_arrays(dom.faces, dom.dim, float(scene.radius.max()))
    pos, vel = scene.pos1.copy(), scene.vel.copy()
    flags, counts = np.empty(n, np.int8), np.empty(n, np.int32)
    build = entry.face_arrays
    entry.face_arrays = lambda faces, dim, radius: fa
    try:
        t0 = time.perf_counter()
        entry.reflect_particles(scene.pos0, pos, vel, scene.acc, scene.radius, dom.planes,
                                    float(scene.cr), int(max_reflections), bool(scene.contact),
                                    flags, counts, faces=dom.faces)
        seconds = time.perf_counter() - t0
    finally:
        entry.face_arrays = build
    return pos, vel, flags, counts, seconds


class Tally:
    def __init__(self):
        self.n = self.escaped = self.crossed = self.nonfinite = self.guarded = 0
        self.reflections = 0
        self.max_reflections = 0
        self.kernel_s = 0.0
        self.domains = 0

    def add(self, other):
        for k in ("n", "escaped", "crossed", "nonfinite", "guarded", "reflections", "kernel_s", "domains"):
            setattr(self, k, getattr(self, k) + getattr(other, k))
        self.max_reflections = max(self.max_reflections, other.max_reflections)

    def row(self, name):
        n = max(self.n, 1)
        rate = self.n / self.kernel_s if self.kernel_s > 0 else float("nan")
        return (f"{name:14s} {self.n:>11,d} {self.domains:>7d} {self.escaped:>7d} {self.crossed:>7d} "
                f"{self.nonfinite:>7d} {self.guarded / n:>9.4%} {self.reflections / n:>8.3f} "
                f"{self.max_reflections:>6d} {self.kernel_s:>9.2f} {rate:>12,.0f}")


HEADER = (f"{'kind':14s} {'trajectories':>11s} {'domains':>7s} {'escaped':>7s} {'crossed':>7s} "
          f"{'non-fin':>7s} {'guard':>9s} {'refl/tr':>8s} {'maxref':>6s} {'kernel s':>9s} {'traj/s':>12s}")


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--n", type=float, default=1e7, help="trajectories in all (default 1e7)")
    ap.add_argument("--batch", type=float, default=2e5,
                    help="trajectories per batch, spread over every kind (default 2e5)")
    ap.add_argument("--per-domain", type=float, default=5e3, help="trajectories per random domain")
    ap.add_argument("--seed", type=int, default=20240602)
    ap.add_argument("--max-reflections", type=int, default=1000)
    ap.add_argument("--on-wall", type=float, default=0.1,
                    help="share of start points touching a wall (default 0.1)")
    ap.add_argument("--quiet", action="store_true", help="no line per batch")
    args = ap.parse_args(argv)
    n_total, n_batch, per_domain = int(args.n), int(args.batch), max(int(args.per_domain), 1)
    rng = np.random.default_rng(args.seed)
    # a domain's few thousand trajectories are below the kernel's parallel threshold:
    # run them on every core all the same (the results are identical, only faster)
    parallel.PARALLEL_MIN = 0

    # compile (or load from numba's cache) outside the timing
    for kind in KINDS:
        run_scene(make_scene(kind, np.random.default_rng(1), 50), args.max_reflections)

    tallies = {k: Tally() for k in KINDS}
    wall0 = time.perf_counter()
    tried = 0
    b = 0
    while tried < n_total:
        n_b = min(n_batch, n_total - tried)
        batch = Tally()
        for i, kind in enumerate(KINDS):
            share = n_b // len(KINDS) + (1 if i < n_b % len(KINDS) else 0)
            while share > 0:
                n = min(per_domain, share)
                share -= n
                scene = make_scene(kind, rng, n, on_wall=args.on_wall)
                pos, vel, flags, counts, s = run_scene(scene, args.max_reflections)
                esc, cro, bad = check(scene, pos, vel)
                t = Tally()
                t.n, t.domains, t.kernel_s = n, 1, s
                t.escaped, t.crossed, t.nonfinite = int(esc.sum()), int(cro.sum()), int(bad.sum())
                t.guarded = int(flags.sum())
                t.reflections = int(counts.sum(dtype=np.int64))
                t.max_reflections = int(counts.max()) if n else 0
                if t.escaped or t.crossed or t.nonfinite:
                    j = int(np.nonzero(esc | cro | bad)[0][0])
                    print(f"FAILURE {kind} cr={scene.cr} contact={scene.contact}: particle {j} "
                          f"r={scene.radius[j]!r} pos0={scene.pos0[j].tolist()} "
                          f"pos1={scene.pos1[j].tolist()} vel={scene.vel[j].tolist()} "
                          f"acc={scene.acc[j].tolist()} -> pos={pos[j].tolist()} vel={vel[j].tolist()} "
                          f"(escaped={bool(esc[j])} crossed={bool(cro[j])})", flush=True)
                tallies[kind].add(t)
                batch.add(t)
        tried += n_b
        if not args.quiet:
            print(f"batch {b:4d}: {tried:>11,d} tried  escaped {batch.escaped}  crossed {batch.crossed}  "
                  f"non-finite {batch.nonfinite}  guard {batch.guarded / max(batch.n, 1):.4%}  "
                  f"kernel {batch.kernel_s:.2f} s  wall {time.perf_counter() - wall0:.0f} s", flush=True)
        b += 1
    wall = time.perf_counter() - wall0
    total = Tally()
    print()
    print(HEADER)
    for kind in KINDS:
        print(tallies[kind].row(kind))
        total.add(tallies[kind])
    print(total.row("total"))
    print(f"\n{total.n:,d} trajectories in {total.domains} random domains; displacements 1e-4 to 100 "
          f"domain lengths, CR in [0, 1] (20% 0, 20% 1); kernel {total.kernel_s:.1f} s "
          f"({total.n / total.kernel_s:,.0f} trajectories/s), wall {wall:.1f} s including set-up "
          f"and checks")
    fail = total.escaped or total.crossed or total.nonfinite
    print("FAILED: escapes, crossings or non-finite values" if fail else "OK: no escape, crossing or non-finite value")
    return 1 if fail else 0


if __name__ == "__main__":
    raise SystemExit(main())
