"""The load of the fluid on walls that hold it all: a moving tank's, from the fluid's
momentum balance.

The fluid's pair forces (pressure, artificial and laminar viscosity) act along the line
between two particles, equal and opposite: they cancel in the sum over the fluid and in its
moment. What is left of sum_i m_i a_i is gravity and what the walls do through the forces
(a wall model's completion, ghost images): the walls' force on the fluid is
sum_i m_i (a_i - g_i), g_i the gravity term the core added (g, or g (1 - rho_ref / rho_i)
with modified pressure), and the fluid's load on walls that hold it all (a tank whose every
wall moves as one) is its opposite, exactly, with its moment about the tank's centre of
rotation. Reflective contacts act outside the forces and add their own impulses. With the
kernel gradient correction the pair forces are not antisymmetric and the load carries that
scheme's momentum error too.

A scheme that solves for its pressure (dfsph) gives the particles the walls' part of that
pressure outside the rates, as kicks (``ctx.solved_impulse``): the tank's load adds their
opposite, with its moment (:func:`impulse_load`).
"""

from __future__ import annotations

import numpy as np
from numba import njit


@njit(cache=True)
def wall_reaction(pos, acc, m, rho, gravity, rho_ref, origin, out):
    """out (6,) <- -sum_i m_i (a_i - g_i) and its moment about ``origin`` (3,) at the
    positions ``pos`` the accelerations were evaluated at (module docstring). One pass."""
    dim = pos.shape[1]
    for e in range(6):
        out[e] = 0.0
    for i in range(pos.shape[0]):
        s = 1.0 - rho_ref / rho[i] if rho_ref != 0.0 else 1.0
        f0 = -m[i] * (acc[i, 0] - s * gravity[0])
        f1 = -m[i] * (acc[i, 1] - s * gravity[1])
        f2 = -m[i] * (acc[i, 2] - s * gravity[2]) if dim == 3 else 0.0
        r0 = pos[i, 0] - origin[0]
        r1 = pos[i, 1] - origin[1]
        r2 = pos[i, 2] - origin[2] if dim == 3 else 0.0
        out[0] += f0
        out[1] += f1
        out[2] += f2
        out[3] += r1 * f2 - r2 * f1
        out[4] += r2 * f0 - r0 * f2
        out[5] += r0 * f1 - r1 * f0


def tank_load(ctx, group, pos0, acc):
    """(force (dim,), moment (3,), about z in 2D) of the fluid on ``group``, a moving group
    that holds every wall, from the accelerations ``acc`` evaluated at ``pos0`` at the step's
    start (``ctx.t`` in ``sph_after_integrate``): :func:`wall_reaction`."""
    st, prm = ctx.state, ctx.params
    dim = prm.dim
    g = np.zeros(3)
    g[:dim] = np.asarray(prm.gravity, np.float64)[:dim]
    pose = group.motion.pose(ctx.t)
    origin = np.zeros(3)
    origin[:dim] = pose.centre + pose.shift
    out = np.zeros(6)
    wall_reaction(pos0, acc, st.m, st.rho, g, float(prm.rho_ref), origin, out)
    return out[:dim], out[3:]


def impulse_load(ctx, group, pos, impulse):
    """(impulse (dim,), angular impulse (3,), about z in 2D) the fluid gave the moving
    ``group`` when the group's walls gave the particles at ``pos`` the momenta ``impulse``
    (n, dim; N s): their opposite, summed, and its moment about the group's centre of
    rotation where it is at ``ctx.t``. A tank that holds every wall takes the whole of a
    solved pressure's kicks; another group its part of each (``wall_integral``)."""
    dim = ctx.params.dim
    pose = group.motion.pose(ctx.t)
    arm = pos - np.asarray(pose.centre + pose.shift, np.float64)[:dim]
    total = -impulse.sum(axis=0)
    angular = np.zeros(3)
    if dim == 2:
        angular[2] = -float((arm[:, 0] * impulse[:, 1] - arm[:, 1] * impulse[:, 0]).sum())
    else:
        angular[:] = -np.cross(arm, impulse).sum(axis=0)
    return total, angular
