"""Rigid-body dynamics of a floating body: Newton-Euler advanced by the leapfrog's
kick-drift-kick, the step the fluid takes.

State: the centre of mass x (m) and its velocity v (m/s); the orientation as the rotation
R from the body's reference frame (as case.toml draws it) to the world, kept as an angle
(2D) or a unit quaternion (3D); the angular momentum L about the centre of mass in the
world frame (kg m^2/s; 2D: per metre of span, about z). A step of dt with the force F and
torque T (about the centre of mass) at its start and F', T' at its end:

    kick    v += dt/2 F/m,           L += dt/2 T
    drift   x += dt v,               R <- the torque-free rotation over dt
    kick    v += dt/2 F'/m,          L += dt/2 T'

The torque-free rotation (3D) is split after Dullweber, Leimkuhler & McLachlan (1997,
J. Chem. Phys. 107, 5840): with the principal moments I_a, I_b, I_s (I_s the one that
differs most from the others) and Pi = R^T L the angular momentum in the body frame,

    H = |L|^2 / (2 I_a) + (1/I_b - 1/I_a) Pi_b^2 / 2 + (1/I_s - 1/I_a) Pi_s^2 / 2.

Each term's flow is a rotation: the first about the fixed L by |L| t / I_a, the others
about the body's own axis k by (1/I_k - 1/I_a) Pi_k t (Pi_k is constant along it). The
first commutes with both; the drift is F_0(dt) F_b(dt/2) F_s(dt) F_b(dt/2), second order,
and exact for a symmetric body (I_a = I_b: the b term vanishes), whose free precession it
then follows to round-off. 2D needs none of it: theta += dt L / I.

Constraints: ``free`` marks the translation's world axes that move; ``rotation`` is
``"free"``, ``"fixed"`` or a hinge, a fixed world ``axis`` (3D; 2D about z) through a fixed
``pivot``, about which the body turns as one degree of freedom with the moment of inertia
about the hinge (parallel axis theorem), its centre of mass carried round. A linear
spring and dashpot from a body point to a fixed anchor (a simple mooring) adds its force
(:meth:`RigidBody.spring_load`).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field

import numpy as np

from sphcore.geometry.motion import Pose, rotation_matrix

# -- quaternions (w, x, y, z) -------------------------------------------------------------------


def quat_mul(p: np.ndarray, q: np.ndarray) -> np.ndarray:
    pw, px, py, pz = p
    qw, qx, qy, qz = q
    return np.array([pw * qw - px * qx - py * qy - pz * qz,
                     pw * qx + px * qw + py * qz - pz * qy,
                     pw * qy - px * qz + py * qw + pz * qx,
                     pw * qz + px * qy - py * qx + pz * qw])


def quat_axis_angle(axis: np.ndarray, angle: float) -> np.ndarray:
    """The unit quaternion of the rotation by ``angle`` (rad) about the unit ``axis``."""
    h = 0.5 * angle
    return np.concatenate([[math.cos(h)], math.sin(h) * np.asarray(axis, float)])


def quat_matrix(q: np.ndarray) -> np.ndarray:
    w, x, y, z = q
    return np.array([[1 - 2 * (y * y + z * z), 2 * (x * y - w * z), 2 * (x * z + w * y)],
                     [2 * (x * y + w * z), 1 - 2 * (x * x + z * z), 2 * (y * z - w * x)],
                     [2 * (x * z - w * y), 2 * (y * z + w * x), 1 - 2 * (x * x + y * y)]])


def _unit(v: np.ndarray) -> tuple[np.ndarray, float]:
    n = float(np.linalg.norm(v))
    return (v / n, n) if n > 0.0 else (v, 0.0)


# -- the body ----------------------------------------------------------------------------------


@dataclass
class Hinge:
    """A fixed world ``axis`` (unit; 2D: z) through the fixed ``pivot`` (m)."""

    axis: np.ndarray
    pivot: np.ndarray


@dataclass
class Spring:
    """A linear spring (``stiffness`` N/m, ``rest_length`` m) and dashpot (``damping``
    N s/m) from the body point ``attach`` (reference frame) to the fixed ``anchor``."""

    anchor: np.ndarray
    attach: np.ndarray
    stiffness: float
    damping: float = 0.0
    rest_length: float = 0.0


@dataclass
class RigidBody:
    """One body: its constant properties and its state (module docstring).

    ``centre_ref`` is the centre of mass in the reference frame and ``inertia_ref`` the
    inertia about it there (2D (1, 1), 3D (3, 3)); ``x`` starts at ``centre_ref`` plus the
    initial offset. ``free``: 1 for each world axis the centre may move along."""

    dim: int
    mass: float
    centre_ref: np.ndarray
    inertia_ref: np.ndarray
    x: np.ndarray
    v: np.ndarray
    angle: float = 0.0  # 2D orientation (rad)
    quat: np.ndarray = field(default_factory=lambda: np.array([1.0, 0.0, 0.0, 0.0]))  # 3D orientation
    L: np.ndarray = field(default_factory=lambda: np.zeros(3))  # angular momentum about the centre (world)
    free: np.ndarray | None = None
    rotation: str = "free"  # "free", "fixed" or "hinge"
    hinge: Hinge | None = None
    springs: tuple = ()

    def __post_init__(self):
        self.free = np.ones(self.dim) if self.free is None else np.asarray(self.free, float)
        if self.dim == 3:
            moments, axes = np.linalg.eigh(self.inertia_ref)
            # the axis whose moment differs most from the other two is the symmetric one
            gaps = [abs(moments[k] - 0.5 * (moments.sum() - moments[k])) for k in range(3)]
            s = int(np.argmax(gaps))
            a, b = [k for k in range(3) if k != s]
            self._moments, self._axes, self._abs = moments, axes, (a, b, s)

    # -- kinematics -----------------------------------------------------------------------

    @property
    def R(self) -> np.ndarray:
        """The rotation from the reference frame to the world (dim, dim)."""
        return rotation_matrix(2, None, self.angle) if self.dim == 2 else quat_matrix(self.quat)

    def inertia_world(self) -> np.ndarray:
        """The inertia tensor about the centre of mass in the world frame (3D; 2D (1, 1))."""
        if self.dim == 2:
            return self.inertia_ref
        R = self.R
        return R @ self.inertia_ref @ R.T

    def omega(self) -> np.ndarray:
        """The angular velocity (rad/s) as a 3-vector (2D: along z)."""
        if self.rotation == "fixed":
            return np.zeros(3)
        if self.rotation == "hinge":
            return self.L / self.hinge_inertia()
        if self.dim == 2:
            return np.array([0.0, 0.0, self.L[2] / self.inertia_ref[0, 0]])
        return np.linalg.solve(self.inertia_world(), self.L)

    def pose(self, acceleration=None, alpha=None) -> Pose:
        """The body as a wall group's pose: a point X of the reference frame is at
        x + R (X - centre_ref)."""
        z = np.zeros(self.dim)
        return Pose(self.R, self.centre_ref.copy(), self.x - self.centre_ref, self.v.copy(),
                    z if acceleration is None else acceleration, self.omega(),
                    np.zeros(3) if alpha is None else alpha)

    def kinetic_energy(self) -> float:
        w = self.omega()
        return 0.5 * self.mass * float(self.v @ self.v) + 0.5 * float(w @ self.L)

    # -- loads ------------------------------------------------------------------------------

    def spring_load(self) -> tuple[np.ndarray, np.ndarray]:
        """(F, T about the centre of mass) of the springs and dashpots now."""
        F, T = np.zeros(self.dim), np.zeros(3)
        R, w = self.R, self.omega()
        for s in self.springs:
            r = R @ (np.asarray(s.attach, float) - self.centre_ref)
            p = self.x + r
            d, length = _unit(p - np.asarray(s.anchor, float))
            vp = self.v + cross_wr(w, r)
            f = -(s.stiffness * (length - s.rest_length) + s.damping * float(vp @ d)) * d
            F = F + f
            T = T + cross3(r, f)
        return F, T

    # -- the step ---------------------------------------------------------------------------

    def kick(self, F: np.ndarray, T: np.ndarray, h: float) -> None:
        """Advance the momenta by h under the force F (N) and torque T (N m, about the
        centre of mass, 3-vector)."""
        if self.rotation == "hinge":
            a, p = self.hinge.axis, self.hinge.pivot
            torque = float(a @ (np.asarray(T, float) + cross3(self.x - p, F)))  # about the hinge
            self.L = self.L + h * torque * a
            self.v = cross_wr(self.omega(), self.x - p)
            return
        self.v = self.v + h * self.free * np.asarray(F, float) / self.mass
        if self.rotation == "free":
            self.L = self.L + h * (np.asarray(T, float) if self.dim == 3 else np.array([0.0, 0.0, T[2]]))

    def drift(self, dt: float) -> None:
        """Advance the position and orientation by dt at the current momenta."""
        if self.rotation == "hinge":
            a, p = self.hinge.axis, self.hinge.pivot
            phi = float(a @ self.omega()) * dt
            turn = rotation_matrix(self.dim, a, phi)
            self.x = p + turn @ (self.x - p)
            self._turn_world(a, phi)
            self.v = cross_wr(self.omega(), self.x - p)
            return
        self.x = self.x + dt * self.v
        if self.rotation == "fixed":
            return
        if self.dim == 2:
            self.angle += dt * self.L[2] / self.inertia_ref[0, 0]
            return
        a, b, s = self._abs
        Ia = self._moments[a]
        self._body_flow(b, 0.5 * dt)
        self._body_flow(s, dt)
        self._body_flow(b, 0.5 * dt)
        axis, size = _unit(self.L)
        if size:
            self._turn_world(axis, size * dt / Ia)

    def _body_flow(self, k: int, t: float) -> None:
        """The flow of (1/I_k - 1/I_a) Pi_k^2 / 2 over t: a turn about body axis k."""
        Ia, Ik = self._moments[self._abs[0]], self._moments[k]
        coef = 1.0 / Ik - 1.0 / Ia
        if coef == 0.0:
            return
        e = self._axes[:, k]
        pi_k = float(e @ (self.R.T @ self.L))
        self.quat = quat_mul(self.quat, quat_axis_angle(e, coef * pi_k * t))
        self.quat /= np.linalg.norm(self.quat)

    def _turn_world(self, axis: np.ndarray, phi: float) -> None:
        if self.dim == 2:
            self.angle += phi * float(axis[2]) if len(axis) == 3 else phi
            return
        self.quat = quat_mul(quat_axis_angle(axis, phi), self.quat)
        self.quat /= np.linalg.norm(self.quat)

    def hinge_inertia(self) -> float:
        """The moment of inertia about the hinge (parallel axis theorem)."""
        a, p = self.hinge.axis, self.hinge.pivot
        r = self.x - p
        r3 = np.concatenate([r, [0.0]]) if self.dim == 2 else r
        off = r3 - (r3 @ a) * a
        if self.dim == 2:
            own = self.inertia_ref[0, 0]
        else:
            own = float(a @ self.inertia_world() @ a)
        return own + self.mass * float(off @ off)


def cross_wr(w: np.ndarray, r: np.ndarray) -> np.ndarray:
    """w x r for a 3-vector w and a point r (dim)."""
    if len(r) == 2:
        return np.array([-w[2] * r[1], w[2] * r[0]])
    return np.cross(w, r)


def cross3(r: np.ndarray, f: np.ndarray) -> np.ndarray:
    """r x f as a 3-vector (2D: along z)."""
    if len(r) == 2:
        return np.array([0.0, 0.0, r[0] * f[1] - r[1] * f[0]])
    return np.cross(r, f)


def rotation_vector(R: np.ndarray) -> np.ndarray:
    """The rotation vector (unit axis times angle in [0, pi], rad) of the rotation matrix R
    (2D: about z)."""
    if R.shape == (2, 2):
        return np.array([0.0, 0.0, math.atan2(R[1, 0], R[0, 0])])
    angle = math.acos(max(-1.0, min(1.0, 0.5 * (np.trace(R) - 1.0))))
    if angle < 1e-12:
        return np.zeros(3)
    axis = np.array([R[2, 1] - R[1, 2], R[0, 2] - R[2, 0], R[1, 0] - R[0, 1]])
    if angle > math.pi - 1e-6:  # near a half turn the skew part vanishes: the axis from R + I
        M = 0.5 * (R + np.eye(3))
        axis = M[:, int(np.argmax(np.diag(M)))]
    return angle * axis / np.linalg.norm(axis)
