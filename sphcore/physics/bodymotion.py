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
"""

from __future__ import annotations

import copy
import math

import numpy as np

from sphcore.geometry.motion import Pose
from sphcore.physics.rigid import RigidBody, cross3, cross_wr


class BodyMotion:
    """The motion of one floating body (``body``: :class:`sphcore.physics.rigid.RigidBody`)
    under ``gravity`` (m/s^2), its springs and the fluid's loads; ``restitution`` of its
    contacts with the fixed walls."""

    t_last = math.inf

    def __init__(self, body: RigidBody, gravity: np.ndarray, restitution: float = 0.5, vertices=None, planes=None,
                 release: float = 0.0):
        self.dim = body.dim
        self.release = release  # held until then
        self.restitution = restitution
        #: the body's vertices (reference frame) and the fixed planes (normals, points) they stay inside
        self.vertices = np.zeros((0, body.dim)) if vertices is None else np.asarray(vertices, float)
        self.planes = planes
        self.contacts = 0  # contacts with the fixed walls so far
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

    def _contact(self, sweeps: int = 4) -> None:
        """Keep the body's vertices inside the fixed planes: for the deepest vertex past a
        plane, an impulse along the plane's normal that reverses its normal velocity times
        the restitution, 1/m_eff = 1/m + n . (I^-1 (r x n)) x r, and a shift back to
        the plane (the body's free axes only)."""
        if self.planes is None or not len(self.vertices):
            return
        b = self.body
        normals, points = self.planes
        for _ in range(sweeps):
            R = b.R
            x = b.x + (self.vertices - b.centre_ref) @ R.T
            d = np.einsum("vpd,pd->vp", x[:, None, :] - points[None, :, :], normals)
            v_idx, p_idx = np.unravel_index(np.argmin(d), d.shape)
            depth = d[v_idx, p_idx]
            if depth >= 0.0:
                return
            n, r = normals[p_idx], x[v_idx] - b.x
            w = b.omega()
            vn = float(n @ (b.v + cross_wr(w, r)))
            if b.rotation == "hinge":  # turn about the hinge only; the hinge holds the rest
                a = b.hinge.axis
                arm = float(a @ cross3(x[v_idx] - b.hinge.pivot, n))
                if vn < 0.0 and arm != 0.0:
                    j = -(1.0 + self.restitution) * vn / (arm * arm / b.hinge_inertia())
                    b.kick(np.zeros(self.dim), j * arm * a, 1.0)
                    self.contacts += 1
                    continue
                return
            if vn < 0.0:
                rn = cross3(r, n)
                if b.rotation == "free":
                    inv = np.linalg.solve(b.inertia_world(), rn) if self.dim == 3 else rn / b.inertia_ref[0, 0]
                    turn = float(n @ cross_wr(inv, r))
                else:
                    turn = 0.0
                free_n = b.free * n
                m_inv = float(free_n @ n) / b.mass + turn
                if m_inv > 0.0:
                    j = -(1.0 + self.restitution) * vn / m_inv
                    b.kick(j * n, j * rn, 1.0)
            b.x = b.x - depth * b.free * n
            self.contacts += 1

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
                "accel": self.accel.tolist(), "alpha": self.alpha.tolist()}

    def restore(self, s: dict) -> None:
        b = self.body
        b.x, b.v, b.angle = np.array(s["x"]), np.array(s["v"]), float(s["angle"])
        b.quat, b.L = np.array(s["quat"]), np.array(s["L"])
        self.accel, self.alpha = np.array(s["accel"]), np.array(s["alpha"])
        self._start = self._end = None


def _three(m) -> np.ndarray:
    m = np.asarray(m, float).ravel()
    if m.size == 3:
        return m
    if m.size == 1:
        return np.array([0.0, 0.0, float(m[0])])
    return np.zeros(3)
