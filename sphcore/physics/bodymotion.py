"""A floating body as a wall group's motion: the pose of its walls at any time of the
current step, advanced by the loads the fluid gives it.

A wall group's motion answers ``pose(t)`` (:class:`sphcore.geometry.motion.Pose`); for a
prescribed motion t can be anything, for a body it is a time of the step being taken: the
step starts at t0 with the body's pose and momenta, :meth:`BodyMotion.begin_step` kicks
the momenta by half a step with the loads at t0 and drifts the body to t0 + dt (the poses
between are the drift's, at the same momenta), the fluid then moves and is reflected by
the walls between those two poses (the contact impulses go to :meth:`impulse`), and
:meth:`end_step` kicks by the other half with the loads at t0 + dt, which the fluid's rates
at the end of the step give. The leapfrog's sequence, the fluid's and the body's together:
the fluid's force on the body and the body's on the fluid are equal and opposite at every
evaluation, so their momentum is exchanged, not made.

The acceleration the pose gives (a_w, for the hydrostatic extrapolation at a wall) is
the body's at the last kick.

After each drift the body's contacts are resolved (:meth:`BodyMotion._contact`): its
vertices against the tank's planes, the fixed walls' closed faces (``solids``) and the
other bodies (``others``), and theirs against it, with impulses of restitution that two
bodies share equally and oppositely.
"""

from __future__ import annotations

import copy
import math

import numpy as np

from sphcore.geometry.faces import Faces
from sphcore.geometry.motion import Pose
from sphcore.physics.rigid import RigidBody, cross3, cross_wr


class BodyMotion:
    """The motion of one floating body (``body``: :class:`sphcore.physics.rigid.RigidBody`)
    under ``gravity`` (m/s^2), its springs and the fluid's loads; ``restitution`` of its
    contacts with the fixed walls and the other bodies."""

    t_last = math.inf

    def __init__(self, body: RigidBody, gravity: np.ndarray, restitution: float = 0.5, vertices=None, planes=None,
                 release: float = 0.0, faces=None):
        self.dim = body.dim
        self.release = release  # held until then
        self.restitution = restitution
        #: the body's vertices (reference frame) and the fixed planes (normals, points) they stay inside
        self.vertices = np.zeros((0, body.dim)) if vertices is None else np.asarray(vertices, float)
        self.planes = planes
        #: the body's faces (reference frame, (nf, dim, dim)); the fixed walls' closed faces
        #: (:class:`Faces`, or None) and the other bodies it must not enter
        self.faces = np.zeros((0, body.dim, body.dim)) if faces is None else np.asarray(faces, float)
        self.solids = None
        self.others: list[BodyMotion] = []
        self.contacts = 0  # contacts with the fixed walls and the other bodies so far
        self.held = False
        self.body = body
        self.gravity = np.asarray(gravity, float)[: body.dim]
        self.t0, self.dt = 0.0, 0.0
        self._start = self._end = None
        self.accel = np.zeros(body.dim)
        self.alpha = np.zeros(3)

    # -- poses --------------------------------------------------------------------------------

    def pose(self, t: float) -> Pose:
        if self._start is None or self.dt == 0.0 or t <= self.t0:
            return self._now() if self._start is None else self._start
        if t >= self.t0 + self.dt:
            return self._end
        between = copy.deepcopy(self._before)
        between.drift(t - self.t0)
        return between.pose(self.accel, self.alpha)

    def _now(self) -> Pose:
        return self.body.pose(self.accel, self.alpha)

    # -- the step -------------------------------------------------------------------------------

    def _own_load(self) -> tuple[np.ndarray, np.ndarray]:
        """Gravity and the springs (F, T about the centre of mass)."""
        F, T = self.body.spring_load()
        return F + self.body.mass * self.gravity, T

    def begin_step(self, t0: float, dt: float, fluid_force, fluid_moment) -> None:
        """Half a kick with the loads at t0 (the fluid's given), then the drift to t0 + dt."""
        b = self.body
        self.t0, self.dt = t0, dt
        self.held = t0 < self.release
        if self.held:  # held where it is drawn: its pose does not change over the step
            self._start = self._end = self._now()
            return
        F, T = self._own_load()
        F, T = F + np.asarray(fluid_force, float)[: self.dim], T + _three(fluid_moment)
        self._record(F, T)
        self._start = self._now()
        b.kick(F, T, 0.5 * dt)
        self._before = copy.deepcopy(b)
        b.drift(dt)
        self._contact()
        self._end = self._now()

    # -- contacts ------------------------------------------------------------------------------

    def world_vertices(self) -> np.ndarray:
        """The body's vertices where it is now (n, dim)."""
        b = self.body
        return b.x + (self.vertices - b.centre_ref) @ b.R.T

    def world_faces(self) -> Faces:
        """The body's faces where it is now, a closed wall with the fluid outside."""
        b = self.body
        verts = b.x + (self.faces - b.centre_ref) @ b.R.T
        return Faces(np.ascontiguousarray(verts), ((0, verts.shape[0], 1),))

    def velocity_at(self, point) -> np.ndarray:
        """The velocity (m/s) of the body's point at ``point`` (zero while it is held)."""
        if self.held:
            return np.zeros(self.dim)
        b = self.body
        return b.v + cross_wr(b.omega(), np.asarray(point, float) - b.x)

    def inverse_mass(self, n, point) -> float:
        """The velocity change along n of the body's point at ``point`` per unit impulse
        along n there: 1/m + n . (I^-1 (r x n)) x r on the free axes, arm^2 / I_h on a
        hinge; zero while it is held."""
        if self.held:
            return 0.0
        b = self.body
        if b.rotation == "hinge":
            arm = float(b.hinge.axis @ cross3(np.asarray(point, float) - b.hinge.pivot, n))
            return arm * arm / b.hinge_inertia()
        r = np.asarray(point, float) - b.x
        turn = 0.0
        if b.rotation == "free":
            rn = cross3(r, n)
            inv = np.linalg.solve(b.inertia_world(), rn) if self.dim == 3 else rn / b.inertia_ref[0, 0]
            turn = float(n @ cross_wr(inv, r))
        return float((b.free * n) @ n) / b.mass + turn

    def push(self, j, n, point) -> None:
        """An impulse j n (N s) at ``point``."""
        if self.held:
            return
        b = self.body
        if b.rotation == "hinge":
            arm = float(b.hinge.axis @ cross3(np.asarray(point, float) - b.hinge.pivot, n))
            b.kick(np.zeros(self.dim), j * arm * b.hinge.axis, 1.0)
        else:
            b.kick(j * n, j * cross3(np.asarray(point, float) - b.x, n), 1.0)

    def shift(self, dx) -> None:
        """Move the body by dx (m): a contact's removal of an overlap. A body that has
        drifted already this step ends the step there."""
        self.body.x = self.body.x + np.asarray(dx, float)
        if self._start is not None:
            self._end = self._now()

    def _deepest(self):
        """The deepest penetration of this body into a fixed wall or another body, as
        (depth < 0 m, n: the direction that separates this body, the contact point, the
        other body or None), or None: its vertices against the tank's planes and the fixed
        walls' faces, its vertices inside another body and that body's inside it."""
        x = self.world_vertices()
        best = None

        def take(depth, n, point, other):
            nonlocal best
            if depth < 0.0 and (best is None or depth < best[0]):
                best = (float(depth), np.asarray(n, float), np.asarray(point, float), other)

        if self.planes is not None and len(self.planes[0]):
            normals, points = self.planes
            d = np.einsum("vpd,pd->vp", x[:, None, :] - points[None, :, :], normals)
            v, k = np.unravel_index(np.argmin(d), d.shape)
            take(d[v, k], normals[k], x[v], None)
        if self.solids is not None and self.solids.count:
            d = self.solids.signed_distance(x)
            v = int(np.argmin(d))
            if d[v] < 0.0:
                take(d[v], self.solids.normal_at(x[v:v + 1])[0], x[v], None)
        for other in self.others:
            theirs = other.world_faces()
            d = theirs.signed_distance(x)
            v = int(np.argmin(d))
            if d[v] < 0.0:
                take(d[v], theirs.normal_at(x[v:v + 1])[0], x[v], other)
            xo = other.world_vertices()
            mine = self.world_faces()
            d = mine.signed_distance(xo)
            v = int(np.argmin(d))
            if d[v] < 0.0:
                take(d[v], -mine.normal_at(xo[v:v + 1])[0], xo[v], other)
        return best

    def _contact(self, sweeps: int = 4) -> None:
        """Keep the body out of the fixed walls and the other bodies: for the deepest
        penetration (:meth:`_deepest`), an impulse along its normal that reverses the
        points' approach speed times the restitution, j = -(1 + e) v_n / (1/m_eff + 1/m_eff'),
        given to both bodies (equal and opposite), and a shift of this body back out (its
        free axes; a hinge takes the impulse only). A few sweeps for the next deepest."""
        if not len(self.vertices):
            return
        b = self.body
        for _ in range(sweeps):
            found = self._deepest()
            if found is None:
                return
            depth, n, point, other = found
            vn = float(n @ (self.velocity_at(point) - (other.velocity_at(point) if other is not None
                                                         else np.zeros(self.dim))))
            applied = False
            if vn < 0.0:
                m_inv = self.inverse_mass(n, point) + (other.inverse_mass(-n, point) if other is not None else 0.0)
                if m_inv > 0.0:
                    j = -(1.0 + self.restitution) * vn / m_inv
                    self.push(j, n, point)
                    if other is not None:
                        other.push(j, -n, point)
                    applied = True
            if b.rotation == "hinge":  # the hinge holds its place: an impulse or nothing
                if not applied:
                    return
                self.contacts += 1
                continue
            self.contacts += 1
            if other is None or other.held or other.body.rotation == "hinge":
                b.x = b.x - depth * b.free * n
            else:  # both move back, their common centre of mass where it was
                share = other.body.mass / (b.mass + other.body.mass)
                b.x = b.x - share * depth * b.free * n
                other.shift((1.0 - share) * depth * other.body.free * n)

    def impulse(self, impulse, angular_impulse) -> None:
        """The contact impulses of the step (N s, N m s about the centre of mass)."""
        if self.held:
            return
        self.body.kick(np.asarray(impulse, float)[: self.dim], _three(angular_impulse), 1.0)

    def end_step(self, fluid_force, fluid_moment) -> None:
        """The second half kick with the loads at the end of the step."""
        if self.held:
            self._start = self._end = None
            return
        F, T = self._own_load()
        F, T = F + np.asarray(fluid_force, float)[: self.dim], T + _three(fluid_moment)
        self._record(F, T)
        self.body.kick(F, T, 0.5 * self.dt)
        self._start = self._end = None

    def _record(self, F, T) -> None:
        b = self.body
        self.accel = b.free * F / b.mass
        if b.rotation == "free" and b.dim == 3:
            self.alpha = np.linalg.solve(b.inertia_world(), T)
        elif b.rotation == "free":
            self.alpha = np.array([0.0, 0.0, T[2] / b.inertia_ref[0, 0]])

    # -- what a checkpoint keeps -----------------------------------------------------------------

    def state(self) -> dict:
        b = self.body
        return {"x": b.x.tolist(), "v": b.v.tolist(), "angle": b.angle, "quat": b.quat.tolist(), "L": b.L.tolist(),
                "accel": self.accel.tolist(), "alpha": self.alpha.tolist(), "contacts": self.contacts}

    def restore(self, s: dict) -> None:
        b = self.body
        b.x, b.v, b.angle = np.array(s["x"]), np.array(s["v"]), float(s["angle"])
        b.quat, b.L = np.array(s["quat"]), np.array(s["L"])
        self.accel, self.alpha = np.array(s["accel"]), np.array(s["alpha"])
        self.contacts = int(s.get("contacts", 0))
        self._start = self._end = None


def _three(m) -> np.ndarray:
    m = np.asarray(m, float).ravel()
    if m.size == 3:
        return m
    if m.size == 1:
        return np.array([0.0, 0.0, float(m[0])])
    return np.zeros(3)
