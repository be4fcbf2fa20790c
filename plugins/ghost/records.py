"""The records the ghost kernels' Python entries take (named tuples of arrays and scalars):
the wall planes (:class:`PlaneGroup`), a moving tank's motion (:class:`WallMotion`), the
image rule (:class:`MirrorRule`), the ghosts' pressure constants (:class:`GhostPressure`),
the per-particle bookkeeping of the passes (:class:`Passes`), the output buffers
(:class:`Images`) and the fluid's constants (:class:`FluidConstants`).
"""

from __future__ import annotations

from typing import NamedTuple

import numpy as np


class PlaneGroup(NamedTuple):
    """One group of wall planes n . X = offset, each normal pointing into the domain.

    ``normals`` (k, dim) float64: unit normals; ``offsets`` (k,) float64: n . X0 (m) for a
    point X0 of each plane. Fixed walls: the case's planes; walls that move: the planes
    where they are at the force evaluation's time, with a :class:`WallMotion` beside them.
    """

    normals: np.ndarray
    offsets: np.ndarray


class WallMotion(NamedTuple):
    """The rigid motion of each wall plane at one instant (all (k, 3) float64, a row per
    plane, zero-padded in 2D): the point of plane k now at x moves with v_w =
    ``velocity[k]`` + ``omega[k]`` x r and accelerates with a_w = ``acceleration[k]`` +
    ``alpha[k]`` x r + ``omega[k]`` x (``omega[k]`` x r), r = x - ``origin[k]`` (m/s, rad/s,
    m/s^2, rad/s^2; the origin is the centre of rotation where it is now, c + D of
    :class:`sphcore.geometry.motion.Pose`). A fixed plane has rows of zeros.
    """

    origin: np.ndarray
    velocity: np.ndarray
    omega: np.ndarray
    acceleration: np.ndarray
    alpha: np.ndarray

    @classmethod
    def of(cls, pose, count: int) -> WallMotion:
        """``count`` planes that all move at a :class:`sphcore.geometry.motion.Pose`."""
        return cls.of_planes(count, [(np.arange(count), pose)])

    @classmethod
    def of_planes(cls, count: int, poses) -> WallMotion:
        """``count`` planes, those of each (plane indices, pose) of ``poses`` at that pose
        and the others at rest."""
        rows = [np.zeros((count, 3)) for _ in range(5)]
        for index, pose in poses:
            for row, v in zip(rows, (np.asarray(pose.centre) + np.asarray(pose.shift), pose.velocity, pose.omega,
                                     pose.acceleration, pose.alpha)):
                v = np.asarray(v, dtype=np.float64).ravel()
                row[index, : v.size] = v
        return cls(*rows)


class MirrorRule(NamedTuple):
    """Which images are made, and how their velocity follows.

    ``support`` (m): the kernel support 2h; a plane closer than this to a fluid particle
    mirrors it. ``tol`` (m): a particle closer than this to a plane makes no image across
    it (an image on top of itself), and an image must lie farther than this behind some
    plane to be kept. ``max_order``: the most planes one image is mirrored across.
    ``free_slip``: True mirrors the velocity with the position (normal component
    reversed), False reverses it whole (no slip).
    """

    support: float
    tol: float
    max_order: int
    free_slip: bool


class GhostPressure(NamedTuple):
    """Constants of the images' pressure and density (module docstring).

    ``hydrostatic``: add the hydrostatic correction (rho_i - rho_ref) g . (x_g - x_i) to
    the ghost pressure and take the density from it by the inverse Tait equation; else
    copy p_i and rho_i. ``gravity`` (3,) float64 (m/s^2), zero-padded in 2D. ``rho_ref``
    (kg/m^3): rho0 when the pressure is the modified (dynamic) one, else 0. ``rho0``
    (kg/m^3), ``b`` (Pa) = c0^2 rho0 / gamma, ``inv_gamma`` = 1 / gamma, ``p_background``
    (Pa), ``c0`` (m/s) and ``gamma``: the fluid's Tait constants (b = 0: no correction, as
    without SPH); b and inv_gamma are derived from c0 and gamma, and the fixed-wall pass
    derives them again in its kernel (see :func:`_fill_pass`).
    """

    hydrostatic: bool
    gravity: np.ndarray
    rho_ref: float
    rho0: float
    b: float
    inv_gamma: float
    p_background: float
    c0: float
    gamma: float


class Passes(NamedTuple):
    """Per-particle bookkeeping of the two passes, for n particles (int64 arrays).

    ``near`` (n,): bit k set when plane k lies within the support of fluid particle i;
    ``counts`` (n,): its kept images; ``start`` (n + 1,): the exclusive prefix sum of
    counts, the first output row of each particle's images.
    """

    near: np.ndarray
    counts: np.ndarray
    start: np.ndarray


class Images(NamedTuple):
    """Output buffers of the ghosts, one row per image (rows beyond the total unused).

    ``pos`` (cap, dim) m, ``vel`` (cap, dim) m/s, ``rho`` (cap,) kg/m^3, ``p`` (cap,) Pa,
    ``m`` (cap,) kg: the ghost's fields as :class:`sphcore.api.Fields`; ``src`` (cap,)
    int64: index of the fluid particle it mirrors.
    """

    pos: np.ndarray
    vel: np.ndarray
    rho: np.ndarray
    p: np.ndarray
    m: np.ndarray
    src: np.ndarray


class FluidConstants(NamedTuple):
    """The run's constants :meth:`MirrorImages.generate` reads (the same names as in
    :class:`sphcore.api.Params`, which may be passed instead).

    ``support`` (m): kernel support 2h; ``gravity`` (3,) or (dim,) m/s^2; ``rho0``
    (kg/m^3), ``c0`` (m/s), ``gamma``, ``p_background`` (Pa): the Tait constants;
    ``rho_ref`` (kg/m^3): rho0 when the pressure is the modified one, else 0.
    """

    support: float
    gravity: np.ndarray
    rho0: float
    c0: float
    gamma: float
    p_background: float = 0.0
    rho_ref: float = 0.0
