"""Random trajectories fired at moving walls: every particle must end each step inside.

    python benchmarks/fuzz/fuzz_moving.py [--n 10000000] [--batch 20000] [--seed 1] [--quiet]

Each batch draws one scene and one step:

- ``tank``: a box tank (2D or 3D) rolling up to +-30 deg about a random centre and axis and
  swaying up to 0.3 m, at periods of 0.3-3 s, ramped or not; the particles start anywhere
  inside where the tank is at a random t;
- ``paddle``: a closed box of faces (a paddle through the floor) swinging up to 0.15 m
  and turning up to +-15 deg inside a fixed 2D tank of planes, never closer than 0.1 m to
  its sides; the particles start in the water
  (inside the tank, outside the paddle);
- ``piston``: one plane of a unit box (2D or 3D) moving on its own, swaying up to 0.15 m
  and turning up to +-15 deg about a hinge below the floor (piston and flap wave makers),
  the other planes fixed; the particles start between them.

Velocities are drawn so that the walls move up to ten times faster than the particles (and
as slow as a tenth), accelerations up to 30 m/s^2, the step up to the CFL limit of a
0.01 m particle spacing with c0 = 20 m/s (dt <= 1.5e-4 s) or, one batch in four, up to 100
times longer; CR anywhere in [0, 1]. After :func:`sphcore_plugins.reflective.moving.reflect_moving`
every particle is checked against the walls where they are at t + dt: clearance to every
plane and to the paddle's faces at least the radius (less 1e-9 of it), and on the fluid
side of the paddle; a particle pinched between two groups counts as an escape. An escape exits 1 and prints the scene.
"""

from __future__ import annotations

import argparse
import math
import sys
import time
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parents[2]
sys.path.insert(0, str(ROOT))

from sphcore.geometry.faces import box, closed_wall  # noqa: E402
from sphcore.geometry.motion import Motion, Ramp, SineRotation, SineTranslation  # noqa: E402
from sphcore.geometry.planes import Planes  # noqa: E402
from sphcore_plugins.reflective.collision import Response, Tally  # noqa: E402
from sphcore_plugins.reflective.corner import scratch  # noqa: E402
from sphcore_plugins.reflective.moving import Group, reflect_moving  # noqa: E402

R = 0.005  # particle radius (m)
TOL = 1e-9


def box_planes(dim, size=1.0):
    normals = np.concatenate([np.eye(dim), -np.eye(dim)])
    points = np.concatenate([np.zeros((dim, dim)), np.full((dim, dim), size)])
    p = Planes.from_lists(normals, points)
    return np.ascontiguousarray(p.normals), np.ascontiguousarray(p.offsets)


def unit(rng, dim):
    v = rng.normal(size=dim)
    return v / np.linalg.norm(v)


def motion(rng, dim, centre, roll_deg, sway):
    ramp = Ramp(rng.uniform(0, 0.5), rng.uniform(0, 1.0)) if rng.random() < 0.5 else Ramp()
    period_r, period_s = rng.uniform(0.3, 3.0), rng.uniform(0.3, 3.0)
    rot = SineRotation(math.radians(rng.uniform(0, roll_deg)), 2 * math.pi / period_r, rng.uniform(0, 2 * math.pi),
                       ramp)
    tr = SineTranslation(unit(rng, dim), rng.uniform(0, sway), 2 * math.pi / period_s, rng.uniform(0, 2 * math.pi),
                         ramp)
    return Motion(dim, (tr,), rot, centre, unit(rng, 3) if dim == 3 else None)


def draw_step(rng, motion_speed):
    """(particle speed scale, dt) of a batch."""
    return motion_speed / rng.uniform(0.1, 10.0), rng.uniform(1e-6, 1.5e-4) * (100.0 if rng.random() < 0.25 else 1.0)


def near_walls(rng, n, dim, reach):
    """n points inside the unit box, most of them within ``reach`` of a side (where the
    walls will meet them this step), the rest anywhere."""
    x = rng.uniform(R, 1 - R, (n, dim))
    near = rng.random(n) < 0.8
    axis = rng.integers(0, dim, n)
    side = rng.random(n) < 0.5
    depth = R + rng.uniform(0, 1, n) * min(reach, 0.5 - R)
    rows = np.flatnonzero(near)
    x[rows, axis[rows]] = np.where(side[rows], depth[rows], 1.0 - depth[rows])
    return x


def fire(groups, step, rng, n, dim, t, pos0):
    """Velocities, accelerations and the step ``step`` (speed, dt) for particles at pos0;
    returns what reflect_moving returns, the end positions and dt."""
    speed, dt = step
    vel = rng.normal(0, speed / math.sqrt(dim), (n, dim))
    acc = rng.normal(0, 30.0 / math.sqrt(dim), (n, dim))
    pos = pos0 + dt * vel + 0.5 * dt * dt * acc
    vel = vel + dt * acc
    tally = Tally(np.zeros(n, np.int8), np.zeros(n, np.int32))
    out = reflect_moving(groups, t, dt, pos0, pos, vel, acc, np.full(n, R),
                         Response(rng.uniform(0, 1), 1000, True), tally, scratch())
    return out, pos, dt


def tank_batch(rng, n):
    dim = int(rng.choice([2, 3]))
    m = motion(rng, dim, rng.uniform(0, 1, dim), 30.0, 0.3)
    tank = Group("tank", *box_planes(dim), None, m)
    tank.build_grid(R)
    t = rng.uniform(0, 3)
    pose = m.pose(t)
    wall = np.linalg.norm(pose.velocity) + np.linalg.norm(pose.omega) * math.sqrt(dim) + 0.1
    step = draw_step(rng, wall)
    pos0 = pose.to_world(near_walls(rng, n, dim, 1.0 * (wall + step[0]) * step[1]))
    (guarded, hit, events, pinched), pos, dt = fire([tank], step, rng, n, dim, t, pos0)
    b = tank.to_body(pos, t + dt)
    clear = (b @ tank.normals.T - tank.offsets).min(axis=1)
    bad = clear < R * (1 - TOL) - 1e-15
    return int(bad.sum()), hit, guarded, f"tank {dim}D t={t:.4f} dt={dt:.3g} worst clearance {clear.min():.3g}"


def paddle_batch(rng, n):
    dim = 2
    m = motion(rng, dim, np.array([0.45, 0.0]), 15.0, 0.15)
    verts = closed_wall(box(np.array([0.4, -0.2]), np.array([0.5, 0.6])), False)
    paddle = Group("paddle", np.zeros((0, 2)), np.zeros(0), verts, m)
    tank = Group("tank", *box_planes(2, 1.0), None, None)
    groups = [tank, paddle]
    for g in groups:
        g.build_grid(R)
    t = rng.uniform(0, 3)
    pose = m.pose(t)
    wall = np.linalg.norm(pose.velocity) + np.linalg.norm(pose.omega) * 0.75 + 0.1
    step = draw_step(rng, wall)
    reach = 1.0 * (wall + step[0]) * step[1]
    # half near the tank's sides, half near the paddle's faces (where it is at t)
    pos0 = near_walls(rng, n, dim, reach)
    k = n // 2
    face = rng.integers(0, verts.count, k)
    a, b = verts.verts[face, 0], verts.verts[face, 1]
    normal = verts.normals()[face]
    on = a + rng.uniform(0, 1, (k, 1)) * (b - a)
    pos0[:k] = pose.to_world(on + normal * (R + rng.uniform(0, 1, (k, 1)) * reach))
    inside_tank = ((pos0 > R) & (pos0 < 1 - R)).all(axis=1)
    pos0 = pos0[inside_tank]
    b0 = paddle.to_body(pos0, t)
    keep = (verts.distances(b0) >= R * 1.001) & verts.in_fluid(b0)
    pos0 = np.ascontiguousarray(pos0[keep])
    (guarded, hit, events, pinched), pos, dt = fire(groups, step, rng, len(pos0), dim, t, pos0)
    b = paddle.to_body(pos, t + dt)
    inside = verts.in_fluid(b)
    gap = verts.distances(b)
    clear = (pos @ tank.normals.T - tank.offsets).min(axis=1)
    bad = ~inside | (gap < R * (1 - TOL) - 1e-15) | (clear < R * (1 - TOL) - 1e-15)
    # the paddle keeps 0.1 m from the tank's sides and its foot below the floor: nothing is pinched
    return int(bad.sum()) + pinched, hit, guarded, \
        f"paddle t={t:.4f} dt={dt:.3g} worst gap {gap.min():.3g} clearance {clear.min():.3g} pinched {pinched}"


def piston_batch(rng, n):
    """A wave maker that is a plane of the tank on its own: the x = 0 side of a unit box
    (2D or 3D) sways along x up to 0.15 m and turns up to +-15 deg about a hinge line 0.1 m
    below the floor (a piston, a flap, or both), the other sides fixed."""
    dim = int(rng.choice([2, 3]))
    normals, offsets = box_planes(dim)
    hinge = np.zeros(dim)
    hinge[1 if dim == 2 else dim - 1] = -0.1
    m = motion(rng, dim, hinge, 15.0, 0.0)
    sway = SineTranslation(np.eye(dim)[0], rng.uniform(0, 0.15), 2 * math.pi / rng.uniform(0.3, 3.0),
                           rng.uniform(0, 2 * math.pi), m.translations[0].ramp)
    axis = None
    if dim == 3:  # the hinge runs along the floor, across the piston: y
        axis = np.array([0.0, 1.0, 0.0])
    m = Motion(dim, (sway,), m.rotation, hinge, axis)
    piston = Group("piston", np.ascontiguousarray(normals[:1]), np.ascontiguousarray(offsets[:1]), None, m)
    fixed = Group("fixed", np.ascontiguousarray(normals[1:]), np.ascontiguousarray(offsets[1:]), None, None)
    groups = [fixed, piston]
    for g in groups:
        g.build_grid(R)
    t = rng.uniform(0, 3)
    pose = m.pose(t)
    wall = np.linalg.norm(pose.velocity) + np.linalg.norm(pose.omega) * 1.5 + 0.1
    step = draw_step(rng, wall)
    reach = 1.0 * (wall + step[0]) * step[1]
    # half near the fixed sides, half near the piston's face where it is at t
    pos0 = near_walls(rng, n, dim, reach)
    k = n // 2
    body = rng.uniform(R, 1 - R, (k, dim))
    body[:, 0] = R + rng.uniform(0, 1, k) * min(reach, 0.5)
    pos0[:k] = pose.to_world(body)
    fixed_clear = (pos0 @ fixed.normals.T - fixed.offsets).min(axis=1)
    keep = (fixed_clear >= R * 1.001) & (piston.to_body(pos0, t)[:, 0] >= R * 1.001)
    pos0 = np.ascontiguousarray(pos0[keep])
    (guarded, hit, events, pinched), pos, dt = fire(groups, step, rng, len(pos0), dim, t, pos0)
    gap = piston.to_body(pos, t + dt)[:, 0]
    clear = (pos @ fixed.normals.T - fixed.offsets).min(axis=1)
    bad = (gap < R * (1 - TOL) - 1e-15) | (clear < R * (1 - TOL) - 1e-15)
    return int(bad.sum()) + pinched, hit, guarded, \
        f"piston {dim}D t={t:.4f} dt={dt:.3g} worst gap {gap.min():.3g} clearance {clear.min():.3g} pinched {pinched}"


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("--n", type=int, default=10_000_000, help="trajectories in all")
    ap.add_argument("--batch", type=int, default=20_000, help="trajectories per scene")
    ap.add_argument("--seed", type=int, default=1)
    ap.add_argument("--quiet", action="store_true")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(args.seed)
    done = escapes = reflected = guards = batches = 0
    start = time.perf_counter()
    while done < args.n:
        n = min(args.batch, args.n - done)
        bad, hit, guarded, scene = (tank_batch, paddle_batch, piston_batch)[batches % 3](rng, n)
        batches += 1
        done += n
        escapes += bad
        reflected += hit
        guards += guarded
        if bad:
            print(f"ESCAPE: {bad} particles, batch {batches}, seed {args.seed}: {scene}")
            return 1
        if not args.quiet and batches % 50 == 0:
            print(f"{done:,} trajectories, {escapes} escapes")
    wall = time.perf_counter() - start
    print(f"{done:,} trajectories in {batches} scenes: {escapes} escapes, {reflected:,} reflected, "
          f"{guards} guard returns, {done / wall:,.0f} trajectories/s")
    return 0


if __name__ == "__main__":
    sys.exit(main())
