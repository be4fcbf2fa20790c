"""Prescribed rigid motion of a group of walls: where it is, how fast it moves and how it
accelerates at any time.

A wall group (the tank, or one ``[[domain.walls]]`` entry) is written in case.toml at its
reference pose. At time t a point X of the group is at

    x(t) = c + D(t) + R(t) (X - c),

c the centre of rotation (reference frame), D(t) the translation, R(t) the rotation by the
angle theta(t) about the axis a (2D: about the out-of-plane axis). A point of the wall
moves with

    v_w = D' + Omega x (x - c - D),        a_w = D'' + alpha x r + Omega x (Omega x r),

with r = x - c - D, Omega = theta' a and alpha = theta'' a (a fixed axis). D is a sum of
translation parts and theta the angle of at most one rotation part (rotations about
different axes do not add). Every part gives its value and its first two time derivatives
in closed form, so the velocity and the acceleration are those of the position the walls
are drawn at, to round-off: a time series is a natural cubic spline through its samples
(C2: the acceleration is continuous), never differences of positions.

A part's ramp (start, duration) multiplies each oscillation's and series' value by the quintic
smooth step s(tau) = 10 tau^3 - 15 tau^4 + 6 tau^5 (tau = (t - start) / duration,
clipped to [0, 1]), whose first two derivatives vanish at both ends, so that a wave maker
or a tank starts without a jump in velocity or acceleration; a constant velocity is ramped
in its velocity (the displacement is its integral), so that it reaches its speed and never
overshoots it.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


# -- the ramp ---------------------------------------------------------------------------------


@dataclass(frozen=True)
class Ramp:
    """The quintic smooth step from 0 at ``start`` to 1 at ``start + duration`` (s);
    ``duration`` 0: a step at ``start`` (no motion before it)."""

    start: float = 0.0
    duration: float = 0.0

    def value(self, t: float) -> tuple[float, float, float]:
        """(s, s', s'') at t."""
        if self.duration <= 0.0:
            return (1.0, 0.0, 0.0) if t >= self.start else (0.0, 0.0, 0.0)
        tau = (t - self.start) / self.duration
        if tau <= 0.0:
            return 0.0, 0.0, 0.0
        if tau >= 1.0:
            return 1.0, 0.0, 0.0
        d = self.duration
        s = tau * tau * tau * (10.0 + tau * (-15.0 + 6.0 * tau))
        s1 = 30.0 * tau * tau * (1.0 - tau) ** 2 / d
        s2 = 60.0 * tau * (1.0 - tau) * (1.0 - 2.0 * tau) / (d * d)
        return s, s1, s2

    def integral(self, t: float) -> float:
        """int_start^t s dt' (s)."""
        if t <= self.start:
            return 0.0
        if self.duration <= 0.0:
            return t - self.start
        tau = min((t - self.start) / self.duration, 1.0)
        inside = self.duration * tau ** 4 * (2.5 + tau * (-3.0 + tau))
        return inside + max(t - self.start - self.duration, 0.0)


def _ramped(ramp: Ramp, t: float, q, q1, q2):
    """(r q, (r q)', (r q)'') from q, q', q'' at t (arrays or floats)."""
    s, s1, s2 = ramp.value(t)
    return s * q, s1 * q + s * q1, s2 * q + 2.0 * s1 * q1 + s * q2


def _sine(amplitude, omega, phase, t):
    """(q, q', q'') of q = amplitude sin(omega t + phase)."""
    arg = omega * t + phase
    return amplitude * math.sin(arg), amplitude * omega * math.cos(arg), -amplitude * omega ** 2 * math.sin(arg)


# -- time series --------------------------------------------------------------------------------


class Spline:
    """The natural cubic spline through samples (t_k, y_k) (t increasing; y (n,) or
    (n, m)), with its first and second derivatives. Two samples: the straight line."""

    def __init__(self, t, y):
        t = np.asarray(t, float)
        y = np.asarray(y, float)
        if y.ndim == 1:
            y = y[:, None]
        self.t, self.y = t, y
        n = t.shape[0]
        h = np.diff(t)
        m = np.zeros_like(y)  # second derivatives at the samples; natural: zero at the ends
        if n > 2:
            # tridiagonal system for m[1:-1] (Thomas algorithm, diagonally dominant)
            a = h[:-1].copy()
            b = 2.0 * (h[:-1] + h[1:])
            c = h[1:].copy()
            r = 6.0 * ((y[2:] - y[1:-1]) / h[1:, None] - (y[1:-1] - y[:-2]) / h[:-1, None])
            k = n - 2
            for i in range(1, k):
                w = a[i] / b[i - 1]
                b[i] -= w * c[i - 1]
                r[i] -= w * r[i - 1]
            x = np.empty_like(r)
            x[-1] = r[-1] / b[-1]
            for i in range(k - 2, -1, -1):
                x[i] = (r[i] - c[i] * x[i + 1]) / b[i]
            m[1:-1] = x
        self.m = m

    def __call__(self, t: float):
        """(y, y', y'') at t; t outside the samples is clipped to them (the caller checks
        that a run stays within the series)."""
        ts = self.t
        t = min(max(t, ts[0]), ts[-1])
        k = int(np.searchsorted(ts, t, side="right")) - 1
        k = min(max(k, 0), ts.shape[0] - 2)
        h = ts[k + 1] - ts[k]
        a = (ts[k + 1] - t) / h
        b = (t - ts[k]) / h
        y0, y1, m0, m1 = self.y[k], self.y[k + 1], self.m[k], self.m[k + 1]
        y = a * y0 + b * y1 + ((a ** 3 - a) * m0 + (b ** 3 - b) * m1) * h * h / 6.0
        dy = (y1 - y0) / h + ((1.0 - 3.0 * a * a) * m0 + (3.0 * b * b - 1.0) * m1) * h / 6.0
        ddy = a * m0 + b * m1
        return y, dy, ddy


# -- the parts of a motion --------------------------------------------------------------------------


@dataclass(frozen=True)
class ConstantVelocity:
    """D = velocity * (t - ramp.start), the velocity ramped (m/s)."""

    velocity: np.ndarray
    ramp: Ramp = Ramp()

    def translation(self, t: float):
        s, s1, _ = self.ramp.value(t)
        return self.velocity * self.ramp.integral(t), self.velocity * s, self.velocity * s1


@dataclass(frozen=True)
class SineTranslation:
    """D = amplitude sin(omega t + phase) axis (amplitude in m, axis a unit vector, omega
    in rad/s, phase in rad)."""

    axis: np.ndarray
    amplitude: float
    omega: float
    phase: float
    ramp: Ramp = Ramp()

    def translation(self, t: float):
        q, q1, q2 = _ramped(self.ramp, t, *_sine(self.amplitude, self.omega, self.phase, t))
        return q * self.axis, q1 * self.axis, q2 * self.axis


@dataclass(frozen=True)
class TranslationSeries:
    """D(t) from samples (``spline`` of dim columns, m)."""

    spline: Spline
    ramp: Ramp = Ramp()

    def translation(self, t: float):
        q, q1, q2 = self.spline(t)
        return _ramped(self.ramp, t, q, q1, q2)


@dataclass(frozen=True)
class SineRotation:
    """theta = amplitude sin(omega t + phase) (rad)."""

    amplitude: float
    omega: float
    phase: float
    ramp: Ramp = Ramp()

    def angle(self, t: float):
        return _ramped(self.ramp, t, *_sine(self.amplitude, self.omega, self.phase, t))


@dataclass(frozen=True)
class RotationSeries:
    """theta(t) from samples (``spline`` of one column, rad)."""

    spline: Spline
    ramp: Ramp = Ramp()

    def angle(self, t: float):
        q, q1, q2 = self.spline(t)
        return _ramped(self.ramp, t, float(q[0]), float(q1[0]), float(q2[0]))


# -- the pose --------------------------------------------------------------------------------------


@dataclass(frozen=True)
class Pose:
    """A wall group at one instant (module docstring): ``rotation`` R (dim, dim), ``centre``
    c (the reference centre of rotation), ``shift`` D (m), ``velocity`` D' (m/s),
    ``acceleration`` D'' (m/s^2), ``omega`` and ``alpha`` the angular velocity (rad/s) and
    acceleration (rad/s^2) as 3-vectors (2D: along z)."""

    rotation: np.ndarray
    centre: np.ndarray
    shift: np.ndarray
    velocity: np.ndarray
    acceleration: np.ndarray
    omega: np.ndarray
    alpha: np.ndarray

    @classmethod
    def rest(cls, dim: int) -> "Pose":
        z = np.zeros(dim)
        return cls(np.eye(dim), z, z, z, z, np.zeros(3), np.zeros(3))

    def to_world(self, X: np.ndarray) -> np.ndarray:
        """World positions of reference points X (..., dim)."""
        return self.centre + self.shift + (X - self.centre) @ self.rotation.T

    def to_body(self, x: np.ndarray) -> np.ndarray:
        """Reference positions of world points x (..., dim): the inverse of :meth:`to_world`."""
        return self.centre + (x - self.centre - self.shift) @ self.rotation

    def direction_to_world(self, n: np.ndarray) -> np.ndarray:
        return n @ self.rotation.T

    def point_velocity(self, x: np.ndarray) -> np.ndarray:
        """Velocity (m/s) of the wall's material point now at world position x (..., dim)."""
        r = x - self.centre - self.shift
        return self.velocity + _cross(self.omega, r)

    def point_acceleration(self, x: np.ndarray) -> np.ndarray:
        """Acceleration (m/s^2) of the wall's material point now at world position x."""
        r = x - self.centre - self.shift
        return self.acceleration + _cross(self.alpha, r) + _cross(self.omega, _cross(self.omega, r))

    @property
    def moving(self) -> bool:
        return bool(np.any(self.velocity) or np.any(self.omega))


def _cross(w: np.ndarray, r: np.ndarray) -> np.ndarray:
    """w x r for a 3-vector w and points r (..., dim); in 2D w is along z."""
    if r.shape[-1] == 2:
        return np.stack([-w[2] * r[..., 1], w[2] * r[..., 0]], axis=-1)
    return np.cross(w, r)


def rotation_matrix(dim: int, axis: np.ndarray | None, theta: float) -> np.ndarray:
    """R for the angle theta (rad) about the unit ``axis`` (3D, Rodrigues) or about z (2D)."""
    c, s = math.cos(theta), math.sin(theta)
    if dim == 2:
        return np.array([[c, -s], [s, c]])
    k = np.asarray(axis, float)
    K = np.array([[0.0, -k[2], k[1]], [k[2], 0.0, -k[0]], [-k[1], k[0], 0.0]])
    return np.eye(3) + s * K + (1.0 - c) * (K @ K)


@dataclass(frozen=True)
class Motion:
    """The prescribed motion of one wall group: translation parts, at most one rotation
    (about ``centre`` and ``axis``: 3D; 2D about z); each part has its own ramp."""

    dim: int
    translations: tuple = ()
    rotation: object = None
    centre: np.ndarray | None = None
    axis: np.ndarray | None = None
    #: the last time the motion is defined for (a series' last sample; inf otherwise)
    t_last: float = math.inf

    def pose(self, t: float) -> Pose:
        dim = self.dim
        D, D1, D2 = np.zeros(dim), np.zeros(dim), np.zeros(dim)
        for part in self.translations:
            q, q1, q2 = part.translation(t)
            D, D1, D2 = D + q, D1 + q1, D2 + q2
        if self.rotation is None:
            return Pose(np.eye(dim), np.zeros(dim), D, D1, D2, np.zeros(3), np.zeros(3))
        theta, w, a = self.rotation.angle(t)
        axis = np.array([0.0, 0.0, 1.0]) if dim == 2 else np.asarray(self.axis, float)
        return Pose(rotation_matrix(dim, axis, theta), np.asarray(self.centre, float), D, D1, D2, w * axis, a * axis)


@dataclass(frozen=True)
class MovingGroup:
    """Walls that move together: the planes ``planes`` and the finite faces ``faces``
    (indices into the case's planes and faces), with their ``motion``; ``name`` is where
    case.toml gives the motion (``domain.motion``: the tank, every plane without a motion of
    its own; ``domain.planes[k].motion``: one plane, a piston; ``domain.walls[k].motion``)."""

    name: str
    motion: Motion
    planes: np.ndarray
    faces: np.ndarray
    #: the largest distance (m) of a point of the group's walls from its centre of rotation
    #: (inf: unbounded planes); |Omega| reach bounds the rotation's share of the walls' speed
    reach: float = math.inf


def moved_planes(planes, pose: Pose):
    """The planes (:class:`sphcore.geometry.planes.Planes`) of a moving tank at ``pose``."""
    return type(planes)(np.ascontiguousarray(pose.direction_to_world(planes.normals)),
                        np.ascontiguousarray(pose.to_world(planes.points)))


def planes_at(planes, groups, t: float):
    """The case's ``planes`` at time t: each moving group's planes (``groups``:
    :class:`MovingGroup`) at its pose, the others where case.toml draws them."""
    moving = [g for g in groups if len(g.planes)]
    if not moving:
        return planes
    if len(moving) == 1 and len(moving[0].planes) == planes.count:  # the tank, all its planes
        return moved_planes(planes, moving[0].motion.pose(t))
    normals, points = planes.normals.copy(), planes.points.copy()
    for g in moving:
        pose = g.motion.pose(t)
        normals[g.planes] = pose.direction_to_world(planes.normals[g.planes])
        points[g.planes] = pose.to_world(planes.points[g.planes])
    return type(planes)(np.ascontiguousarray(normals), np.ascontiguousarray(points))


def plane_groups(groups):
    """The groups that move planes."""
    return tuple(g for g in groups if len(g.planes))


def wall_speed(groups, t: float, pos: np.ndarray) -> float:
    """An upper bound of the speed (m/s) of every point of the moving walls:
    |D'| + |Omega| reach over the groups, reach the walls' largest distance from the centre
    of rotation (a rigid motion keeps it), or for unbounded planes the particles' ``pos``
    (the time step's limit counts the walls' speed as it counts the particles')."""
    fastest = 0.0
    for g in groups:
        pose = g.motion.pose(t)
        w = float(np.linalg.norm(pose.omega))
        reach = 0.0
        if w:
            reach = g.reach  # the walls' own extent; unbounded planes: where the particles are
            if not math.isfinite(reach):
                reach = float(np.sqrt(((pos - pose.centre - pose.shift) ** 2).sum(axis=1).max())) if len(pos) else 0.0
        fastest = max(fastest, float(np.linalg.norm(pose.velocity)) + w * reach)
    return fastest
