"""Reflective walls that move: the paper's collision detection and response in the frame of
each group of walls that move together.

The case's walls fall into groups (:attr:`sphcore.case.model.Case.moving`): the fixed walls,
the tank when it moves (its planes and the walls with ``tank = true``), and each plane or
wall with a motion of its own (a piston). A group's geometry is kept where case.toml draws it (its reference
frame), with its face grid built once. For a step from t to t + dt a moving group at poses
P0 = P(t) and P1 = P(t + dt) (:mod:`sphcore.geometry.motion`) sees each particle

- start at b0 = P0^-1(x0) and end at b1 = P1^-1(x1): the particle's path relative to the
  walls, taken as straight in the group's frame (exact for a translation at constant
  velocity; for a rotation its error is O((Omega dt)^2) of the step's travel);
- with the relative velocity v_b = R1^T (v - v_w(x1)) and acceleration
  a_b = R1^T (a - a_w(x1)), v_w and a_w the velocity and acceleration of the wall's
  point at x1 at t + dt.

The fixed-wall algorithm (:func:`.collision.reflect_step`) then runs unchanged on (b0, b1,
v_b, a_b) against the reference geometry: detection on the relative displacement (a wall
faster than the water still never passes a particle: the particle's relative path crosses
it), several walls of the group in order of contact, the response on the relative velocity,
v_b' = v_b,t - CR (v_b . n) n, and the guard. Only the particles it changed are taken back:
x1' = P1(b1'), v' = R1 v_b' + v_w(x1'), i.e.

    v' = v_w + v_rel,t - CR (v_rel . n) n,

the response the paper gives for a fixed wall, on the velocity relative to the moving one.
A particle left untouched keeps its bits. A particle ends inside the group at t + dt
because b1' is inside the reference geometry (the fixed algorithm's guarantee, the guard
included: b0 was inside the group at t) and P1 is a rigid motion.

Groups are treated one after the other (the fixed walls first), and the sweep repeats while
some group still reflects a particle, at most ``MAX_SWEEPS`` times: a particle that hits a
moving paddle and then the fixed floor in one step is put back by both. Two groups closer
than a particle's diameter pinch it (no admissible position); the sweeps then end with the
particle inside the last group treated, and ``pinched`` in the summary counts such
particle-steps.
"""

from __future__ import annotations

import numpy as np
from numba import prange

from sphcore.api import Faces, by_size

from .collision import Paths, WallGroup, reflect_step
from .entry import face_arrays

#: sweeps over the groups per step (a contact with a second group makes one more)
MAX_SWEEPS = 8


class Group:
    """One group of the reflective walls: its :class:`.collision.WallGroup` (reference frame),
    the :class:`sphcore.geometry.motion.Motion` that moves it (None: fixed), the finite faces
    (:class:`sphcore.geometry.faces.Faces` or None) and the group's name in case.toml."""

    def __init__(self, name, normals, offsets, faces, motion):
        self.name, self.motion, self.faces = name, motion, faces
        self.walls = WallGroup.of(normals, offsets, face_arrays(None, normals.shape[1], 1.0))
        self.normals, self.offsets = normals, offsets
        self._frame = None

    def frame(self, shape):
        """Scratch (b0, b1, vb, ab), each ``shape``, for the particles in the group's frame."""
        if self._frame is None or self._frame[0].shape != shape:
            self._frame = tuple(np.empty(shape) for _ in range(4))
        return self._frame

    def build_grid(self, radius):
        """The faces' grid, once the particle radius is known (its cells are sized by it)."""
        if self.faces is not None:
            self.walls = WallGroup.of(self.normals, self.offsets,
                                      face_arrays(self.faces, self.normals.shape[1], radius))

    def to_body(self, pos, t):
        """Positions in the group's reference frame at time t."""
        return pos if self.motion is None else self.motion.pose(t).to_body(pos)


def groups_of(case, normals, offsets):
    """The reflective walls of ``case`` in groups (module docstring): the fixed walls first
    (only if there are any), then each moving group. ``normals``, ``offsets``: the case's
    planes as the kernel takes them."""
    dim = normals.shape[1]
    faces = getattr(case, "faces", None)
    nf = faces.count if faces is not None else 0
    moving = getattr(case, "moving", ())
    fixed_faces = np.ones(nf, bool)
    fixed_planes = np.ones(normals.shape[0], bool)
    out = []
    for g in moving:
        fixed_faces[g.faces] = False
        fixed_planes[g.planes] = False

    def planes(index):
        if len(index) == normals.shape[0]:  # all of them (the arrays as they are)
            return normals, offsets
        return np.ascontiguousarray(normals[index]), np.ascontiguousarray(offsets[index])

    if fixed_planes.any() or fixed_faces.any():
        out.append(Group("fixed", *planes(np.flatnonzero(fixed_planes)), select(faces, np.flatnonzero(fixed_faces)),
                         None))
    for g in moving:
        out.append(Group(g.name, *planes(np.asarray(g.planes, np.int64)), select(faces, g.faces), g.motion))
    return out


def select(faces, index):
    """The faces ``index`` (whole wall entries, in order) of ``faces``, their closed walls
    kept; None when none."""
    if faces is None or len(index) == 0:
        return None
    index = np.asarray(index, np.int64)
    keep = set(index.tolist())
    groups = []
    for a, b, sign in faces.groups:
        if a in keep:
            start = int(np.searchsorted(index, a))
            groups.append((start, start + (b - a), sign))
    return Faces(np.ascontiguousarray(faces.verts[index]), tuple(groups))


def reflect_moving(groups, t, dt, pos0, pos, vel, acc, radius, response, tally, work, mass=None, loads=None):
    """Reflect every particle that crossed a wall of any group during the step from t to
    t + dt (s); ``pos`` and ``vel`` in place. Returns (guard returns, particle-steps
    reflected, reflections, pinched particle-steps). With ``mass`` (n,) (kg) and a dict
    ``loads``, each moving group's name gets what its walls took from the fluid this step:
    (impulse (3,) N s, angular impulse about its centre of rotation at t + dt (3,) N m s),
    the negative of the momentum its reflections gave the particles."""
    guarded = events = 0
    touched = np.zeros(pos.shape[0], bool)
    for sweep in range(MAX_SWEEPS):
        any_hit = False
        for g in groups:
            if g.motion is None:
                gd, hit, ev = reflect_step(Paths(pos0, pos, vel, acc, radius), g.walls, response, tally, work)
                changed = (tally.reflections > 0) | (tally.guarded > 0) if hit or gd else None
            else:
                p0, p1 = g.motion.pose(t), g.motion.pose(t + dt)
                R = p1.rotation
                frame = g.frame(pos.shape)
                into_frame(pos0, pos, vel, acc, frame_of(p0, p1), *frame)
                b0, b1, vb, ab = frame
                gd, hit, ev = reflect_step(Paths(b0, b1, vb, ab, radius), g.walls, response, tally, work)
                changed = None
                if hit or gd:
                    changed = (tally.reflections > 0) | (tally.guarded > 0)
                    x = p1.to_world(b1[changed])
                    v_new = vb[changed] @ R.T + p1.point_velocity(x)
                    if loads is not None and mass is not None:
                        dp = mass[changed, None] * (v_new - vel[changed])  # what the walls gave
                        arm = x - p1.centre - p1.shift
                        imp, ang = loads.setdefault(g.name, (np.zeros(3), np.zeros(3)))
                        imp[:dp.shape[1]] -= dp.sum(axis=0)
                        if dp.shape[1] == 2:
                            ang[2] -= float((arm[:, 0] * dp[:, 1] - arm[:, 1] * dp[:, 0]).sum())
                        else:
                            ang -= np.cross(arm, dp).sum(axis=0)
                    pos[changed] = x
                    vel[changed] = v_new
            guarded, events = guarded + gd, events + ev
            if changed is not None:
                any_hit = True
                touched |= changed
        if not any_hit or len(groups) == 1:
            break
    pinched = 0
    if len(groups) > 1 and any_hit:
        # the sweeps ended with a group still reflecting: count what is outside another group
        pinched = int(sum(outside_any(g, t + dt, pos, radius).sum() for g in groups))
    return guarded, int(touched.sum()), events, pinched


def outside_any(group, t, pos, radius):
    """(n,) bool: particles closer than their radius to a plane of ``group`` at time t
    (planes only: the faces' check is the grid kernel's)."""
    b = group.to_body(pos, t)
    if group.normals.shape[0] == 0:
        return np.zeros(pos.shape[0], bool)
    d = b @ group.normals.T - group.offsets
    return (d < (radius * (1.0 - 1e-9))[:, None]).any(axis=1)


def frame_of(p0, p1):
    """The two poses as the arrays :func:`into_frame` takes: R0, D0, R1, D1, the centre c,
    and at t + dt the velocity V, acceleration A and the angular velocity and acceleration
    (3-vectors)."""
    return (np.ascontiguousarray(p0.rotation), np.ascontiguousarray(p0.shift, dtype=np.float64),
            np.ascontiguousarray(p1.rotation), np.ascontiguousarray(p1.shift, dtype=np.float64),
            np.ascontiguousarray(p1.centre, dtype=np.float64), np.ascontiguousarray(p1.velocity, dtype=np.float64),
            np.ascontiguousarray(p1.acceleration, dtype=np.float64), np.ascontiguousarray(p1.omega, dtype=np.float64),
            np.ascontiguousarray(p1.alpha, dtype=np.float64))


@by_size
def into_frame(pos0, pos, vel, acc, poses, b0, b1, vb, ab):
    """The step's paths in a moving group's frame (module docstring), in one pass:
    b0 = c + R0^T (x0 - c - D0), b1 = c + R1^T r with r = x1 - c - D1,
    vb = R1^T (v - V - Omega x r), ab = R1^T (a - A - alpha x r - Omega x (Omega x r))."""
    R0, D0, R1, D1, c, V, A, w, al = poses
    n, dim = pos.shape
    for i in prange(n):
        if dim == 2:
            x0 = pos0[i, 0] - c[0] - D0[0]
            y0 = pos0[i, 1] - c[1] - D0[1]
            b0[i, 0] = c[0] + R0[0, 0] * x0 + R0[1, 0] * y0
            b0[i, 1] = c[1] + R0[0, 1] * x0 + R0[1, 1] * y0
            rx = pos[i, 0] - c[0] - D1[0]
            ry = pos[i, 1] - c[1] - D1[1]
            b1[i, 0] = c[0] + R1[0, 0] * rx + R1[1, 0] * ry
            b1[i, 1] = c[1] + R1[0, 1] * rx + R1[1, 1] * ry
            wz = w[2]
            az = al[2]
            ux = vel[i, 0] - (V[0] - wz * ry)
            uy = vel[i, 1] - (V[1] + wz * rx)
            vb[i, 0] = R1[0, 0] * ux + R1[1, 0] * uy
            vb[i, 1] = R1[0, 1] * ux + R1[1, 1] * uy
            gx = acc[i, 0] - (A[0] - az * ry - wz * wz * rx)
            gy = acc[i, 1] - (A[1] + az * rx - wz * wz * ry)
            ab[i, 0] = R1[0, 0] * gx + R1[1, 0] * gy
            ab[i, 1] = R1[0, 1] * gx + R1[1, 1] * gy
        else:
            p0 = pos0[i, 0] - c[0] - D0[0]
            p1 = pos0[i, 1] - c[1] - D0[1]
            p2 = pos0[i, 2] - c[2] - D0[2]
            r0 = pos[i, 0] - c[0] - D1[0]
            r1 = pos[i, 1] - c[1] - D1[1]
            r2 = pos[i, 2] - c[2] - D1[2]
            wr0 = w[1] * r2 - w[2] * r1
            wr1 = w[2] * r0 - w[0] * r2
            wr2 = w[0] * r1 - w[1] * r0
            u0 = vel[i, 0] - (V[0] + wr0)
            u1 = vel[i, 1] - (V[1] + wr1)
            u2 = vel[i, 2] - (V[2] + wr2)
            g0 = acc[i, 0] - (A[0] + al[1] * r2 - al[2] * r1 + w[1] * wr2 - w[2] * wr1)
            g1 = acc[i, 1] - (A[1] + al[2] * r0 - al[0] * r2 + w[2] * wr0 - w[0] * wr2)
            g2 = acc[i, 2] - (A[2] + al[0] * r1 - al[1] * r0 + w[0] * wr1 - w[1] * wr0)
            for d in range(3):
                b0[i, d] = c[d] + R0[0, d] * p0 + R0[1, d] * p1 + R0[2, d] * p2
                b1[i, d] = c[d] + R1[0, d] * r0 + R1[1, d] * r1 + R1[2, d] * r2
                vb[i, d] = R1[0, d] * u0 + R1[1, d] * u1 + R1[2, d] * u2
                ab[i, d] = R1[0, d] * g0 + R1[1, d] * g1 + R1[2, d] * g2
