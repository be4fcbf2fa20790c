"""The ghost kernels of walls that move: images across the planes where they are, with each
plane's velocity and acceleration (:class:`.records.WallMotion`, a row per plane: the tank's
planes share one motion, a piston has its own); see the plugin's docstring and :mod:`.mirror`
for the fixed-wall kernels they follow.

An image made across several planes (a corner) takes each plane's motion on its own leg:
free slip reflects the velocity relative to plane k's point at the foot of that reflection.
The hydrostatic correction integrates g - a_w from the particle to its image: along the
straight line by the midpoint rule, a_w(m) . (x_g - x_i), when all the image's planes move
as one (a tank); leg by leg, sum_k a_w,k . (-2 d_k n_k) with a_w,k the acceleration of plane
k's point at that leg's foot, when they move differently (a piston meeting a fixed floor:
each wall's acceleration along its own normal). No slip gives 2 v_w - v_i with v_w of the
first plane of the image at the midpoint of particle and image (in a corner of walls of
different motions the slip condition of one wall is all an image can meet).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from sphcore.api import eos, plane_distance

from .mirror import popcount


@njit(cache=True, inline="always")
def _wall_velocity(motion, k, x0, x1, x2):
    """(vx, vy, vz) of plane k's point now at (x0, x1, x2): V + Omega x r (:class:`WallMotion`)."""
    o, w, v = motion.origin[k], motion.omega[k], motion.velocity[k]
    r0, r1, r2 = x0 - o[0], x1 - o[1], x2 - o[2]
    return (v[0] + w[1] * r2 - w[2] * r1,
            v[1] + w[2] * r0 - w[0] * r2,
            v[2] + w[0] * r1 - w[1] * r0)


@njit(cache=True, inline="always")
def _wall_acceleration(motion, k, x0, x1, x2):
    """(ax, ay, az) of plane k's point now at (x0, x1, x2): A + alpha x r + Omega x (Omega x r)."""
    o, w, al, a = motion.origin[k], motion.omega[k], motion.alpha[k], motion.acceleration[k]
    r0, r1, r2 = x0 - o[0], x1 - o[1], x2 - o[2]
    c0 = w[1] * r2 - w[2] * r1  # Omega x r
    c1 = w[2] * r0 - w[0] * r2
    c2 = w[0] * r1 - w[1] * r0
    return (a[0] + al[1] * r2 - al[2] * r1 + w[1] * c2 - w[2] * c1,
            a[1] + al[2] * r0 - al[0] * r2 + w[2] * c0 - w[0] * c2,
            a[2] + al[0] * r1 - al[1] * r0 + w[0] * c1 - w[1] * c0)


@njit(cache=True, inline="always")
def _image_moving(fluid, i, walls, sub, rule, motion):
    """:func:`_image` with walls that move as ``motion`` (:class:`WallMotion`): the same
    position and keep; free slip reflects the velocity relative to the wall point at the
    foot of each plane's mirroring, no slip gives 2 v_w(m) - v_i, m the midpoint of the
    particle and its image; also returns sum over the legs of a_w,k . (-2 d_k n_k), the
    image's first plane and whether all its planes move as one (module docstring)."""
    pos, vel = fluid.pos, fluid.vel
    normals, offsets = walls.normals, walls.offsets
    free_slip, tol = rule.free_slip, rule.tol
    dim = pos.shape[1]
    x0, x1 = pos[i, 0], pos[i, 1]
    v0, v1 = vel[i, 0], vel[i, 1]
    x2 = pos[i, 2] if dim == 3 else 0.0
    v2 = vel[i, 2] if dim == 3 else 0.0
    k = 0
    s = sub
    first = -1
    rise = 0.0
    same = True
    while s:
        if s & 1:
            if first < 0:
                first = k
            else:
                same = same and _same_motion(motion, first, k)
            n0, n1 = normals[k, 0], normals[k, 1]
            n2 = normals[k, 2] if dim == 3 else 0.0
            d = plane_distance(normals, offsets, k, x0, x1, x2)
            f0, f1, f2 = x0 - d * n0, x1 - d * n1, x2 - d * n2
            a0, a1, a2 = _wall_acceleration(motion, k, f0, f1, f2)
            rise -= 2.0 * d * (a0 * n0 + a1 * n1 + a2 * n2)
            if free_slip:
                w0, w1, w2 = _wall_velocity(motion, k, f0, f1, f2)
                vn = (v0 - w0) * n0 + (v1 - w1) * n1 + (v2 - w2) * n2
                v0 -= 2.0 * vn * n0
                v1 -= 2.0 * vn * n1
                v2 -= 2.0 * vn * n2
            x0 -= 2.0 * d * n0
            x1 -= 2.0 * d * n1
            x2 -= 2.0 * d * n2
        s >>= 1
        k += 1
    if not free_slip:
        xi2 = pos[i, 2] if dim == 3 else 0.0
        w0, w1, w2 = _wall_velocity(motion, first, 0.5 * (pos[i, 0] + x0), 0.5 * (pos[i, 1] + x1), 0.5 * (xi2 + x2))
        v0, v1, v2 = 2.0 * w0 - v0, 2.0 * w1 - v1, 2.0 * w2 - v2
    dmin = np.inf
    for k in range(normals.shape[0]):
        dmin = min(dmin, plane_distance(normals, offsets, k, x0, x1, x2))
    return dmin < -tol, x0, x1, x2, v0, v1, v2, rise, first, same


@njit(cache=True, inline="always")
def _same_motion(motion, a, b):
    """Planes a and b move as one (the same rows of :class:`WallMotion`)."""
    for row in (motion.origin, motion.velocity, motion.omega, motion.acceleration, motion.alpha):
        for e in range(3):
            if row[a, e] != row[b, e]:
                return False
    return True




@njit(cache=True, inline="always")
def _fill_one_moving(fluid, i, near, walls, rule, ghost, motion, j, out):
    """:func:`_fill_one` with walls that move as ``motion`` (:class:`WallMotion`): velocity
    by :func:`_image_moving`, and the hydrostatic correction with g - a_w (Adami, Hu & Adams
    2012, Eq. 27; module docstring)."""
    pos, rho, p, m = fluid.pos, fluid.rho, fluid.p, fluid.m
    gpos, gvel, grho, gp, gm, gsrc = out.pos, out.vel, out.rho, out.p, out.m, out.src
    gravity, b = ghost.gravity, ghost.b
    hydrostatic, rho_ref = ghost.hydrostatic, ghost.rho_ref
    max_order = rule.max_order
    dim = pos.shape[1]
    xi0, xi1 = pos[i, 0], pos[i, 1]
    xi2 = pos[i, 2] if dim == 3 else 0.0
    sub = near
    while sub:
        if popcount(sub) <= max_order:
            keep, x0, x1, x2, v0, v1, v2, rise_a, first, same = _image_moving(fluid, i, walls, sub, rule, motion)
            if keep:
                gpos[j, 0] = x0
                gpos[j, 1] = x1
                gvel[j, 0] = v0
                gvel[j, 1] = v1
                if dim == 3:
                    gpos[j, 2] = x2
                    gvel[j, 2] = v2
                if hydrostatic and b > 0.0:
                    e0, e1, e2 = x0 - xi0, x1 - xi1, x2 - xi2
                    rise = gravity[0] * e0 + gravity[1] * e1 + gravity[2] * e2
                    if same:  # one rigid motion: a_w at the midpoint, along the straight line
                        a0, a1, a2 = _wall_acceleration(motion, first, xi0 + 0.5 * e0, xi1 + 0.5 * e1, xi2 + 0.5 * e2)
                        rise_a = a0 * e0 + a1 * e1 + a2 * e2
                    # grad p = rho (g - a_w) in water at rest relative to the wall; the
                    # modified pressure removes rho0 g only, so a_w counts with all of rho_i
                    pg = p[i] + (rho[i] - rho_ref) * rise - rho[i] * rise_a
                    gp[j] = pg
                    grho[j] = eos.density(pg, ghost.rho0, b, ghost.inv_gamma, ghost.p_background)
                else:
                    gp[j] = p[i]
                    grho[j] = rho[i]
                gm[j] = m[i]
                gsrc[j] = i
                j += 1
        sub = (sub - 1) & near


@njit(cache=True, parallel=True)
def fill_images_moving(fluid, walls, rule, ghost, motion, passes, out):
    """:func:`fill_images` with walls that move as ``motion`` (:class:`WallMotion`);
    ``walls``: the planes where they are now."""
    near, start = passes.near, passes.start
    for i in prange(fluid.pos.shape[0]):
        if start[i + 1] > start[i]:
            _fill_one_moving(fluid, i, near[i], walls, rule, ghost, motion, start[i], out)


@njit(cache=True)
def fill_images_moving_serial(fluid, walls, rule, ghost, motion, passes, out):
    """:func:`fill_images_moving` on one thread."""
    near, start = passes.near, passes.start
    for i in range(fluid.pos.shape[0]):
        if start[i + 1] > start[i]:
            _fill_one_moving(fluid, i, near[i], walls, rule, ghost, motion, start[i], out)
