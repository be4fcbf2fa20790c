"""The load of the fluid on each group of moving planes, from the ghost images' pair forces.

Where one group holds every plane (a tank) the plugin takes the load from the fluid's
momentum balance instead, which is exact (:func:`sphcore.api.tank_load`). Where the
planes move in several groups (a piston in a fixed flume) the walls' total force does not
say which wall took what, and the load of group k is summed pair by pair: the image j of a
fluid particle pushes fluid particle i with the momentum equation's pressure term,

    f_ij = -m_i m_j (p_i / rho_i^2 + p_j / rho_j^2) grad_i W_ij,

and the wall the image stands for takes -f_ij (the artificial viscosity's share, small
next to a free-slip wall, is left out). An image made across one plane is that plane's; an
image across several (a corner) shares -f_ij out along the planes' normals,
-f_ij = sum_a c_a n_a (the rest, out of their span in 3D, to the first plane), each part to
its plane's group. Moments are taken about each group's centre of rotation where it is.

Images are found per fluid particle through a cell list of the images (cells of 2h), each
image once per particle; the images of a plane are those outside it (d < 0).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from sphcore.api import kernel_f, normal_parts, plane_distance


@njit(cache=True)
def group_loads(pos, rho, p, m, gpos, grho, gp, gm, normals, offsets, owner, origins, kernel_id, h, out):
    """out (groups, 6) += each plane group's force and moment (module docstring). Fluid
    ``pos``, ``rho``, ``p`` (the momentum equation's pressure), ``m``; images ``gpos`` ...;
    planes where they are now; ``owner`` (k,) the group of each plane (-1: fixed);
    ``origins`` (groups, 3) the groups' centres of rotation now."""
    dim = pos.shape[1]
    ng = gpos.shape[0]
    if ng == 0:
        return
    support = 2.0 * h
    # a cell list of the images over their bounding box
    lo = np.empty(dim)
    hi = np.empty(dim)
    for d in range(dim):
        lo[d] = gpos[0, d]
        hi[d] = gpos[0, d]
    for j in range(ng):
        for d in range(dim):
            lo[d] = min(lo[d], gpos[j, d])
            hi[d] = max(hi[d], gpos[j, d])
    shape = np.ones(3, np.int64)
    for d in range(dim):
        shape[d] = int((hi[d] - lo[d]) / support) + 1
    ncell = shape[0] * shape[1] * shape[2]
    start = np.zeros(ncell + 1, np.int64)
    cell = np.empty(ng, np.int64)
    for j in range(ng):
        c = 0
        for d in range(dim):
            c = c * shape[d] + min(int((gpos[j, d] - lo[d]) / support), shape[d] - 1)
        cell[j] = c
        start[c + 1] += 1
    for c in range(ncell):
        start[c + 1] += start[c]
    fill = start[:-1].copy()
    items = np.empty(ng, np.int64)
    for j in range(ng):
        items[fill[cell[j]]] = j
        fill[cell[j]] += 1
    kmax = normals.shape[0]
    near = np.empty(kmax, np.int64)
    for i in range(pos.shape[0]):
        # the particle's cell range among the images' cells
        c_lo = np.zeros(3, np.int64)
        c_hi = np.zeros(3, np.int64)
        outside = False
        for d in range(dim):
            a = int(np.floor((pos[i, d] - lo[d]) / support)) - 1
            b = a + 2
            if b < 0 or a > shape[d] - 1:
                outside = True
            c_lo[d] = max(a, 0)
            c_hi[d] = min(b, shape[d] - 1)
        if outside:
            continue
        pr_i = p[i] / (rho[i] * rho[i])
        for c0 in range(c_lo[0], c_hi[0] + 1):
            for c1 in range(c_lo[1], c_hi[1] + 1):
                for c2 in range(c_lo[2], c_hi[2] + 1):
                    c = (c0 * shape[1] + c1) * shape[2] + c2 if dim == 3 else c0 * shape[1] + c1
                    for e in range(start[c], start[c + 1]):
                        j = items[e]
                        r2 = 0.0
                        for d in range(dim):
                            r2 += (pos[i, d] - gpos[j, d]) ** 2
                        if r2 >= support * support or r2 == 0.0:
                            continue
                        x0 = gpos[j, 0]
                        x1 = gpos[j, 1]
                        x2 = gpos[j, 2] if dim == 3 else 0.0
                        m_near = 0
                        moving = False
                        for k in range(kmax):
                            if plane_distance(normals, offsets, k, x0, x1, x2) < 0.0:
                                near[m_near] = k
                                m_near += 1
                                moving = moving or owner[k] >= 0
                        if not moving:
                            continue
                        F = kernel_f(kernel_id, np.sqrt(r2), h, dim)
                        coef = m[i] * gm[j] * (pr_i + gp[j] / (grho[j] * grho[j])) * F  # -f_ij = coef (x_i - x_j)
                        f0 = coef * (pos[i, 0] - x0)
                        f1 = coef * (pos[i, 1] - x1)
                        f2 = coef * (pos[i, 2] - x2) if dim == 3 else 0.0
                        _share_out(f0, f1, f2, near, m_near, normals, owner, origins, pos, i, dim, out)


@njit(cache=True, inline="always")
def _share_out(f0, f1, f2, near, m, normals, owner, origins, pos, i, dim, out):
    """Give the force (f0, f1, f2) on the walls to the groups of the image's planes near[:m]:
    all of it to one group, or along the planes' normals (:func:`sphcore.api.normal_parts`)."""
    first = near[0]
    same = True
    for u in range(1, m):
        same = same and owner[near[u]] == owner[first]
    if same or m > 3:
        _add(out, owner[first], origins, pos, i, dim, f0, f1, f2)
        return
    c = np.empty(3)
    if not normal_parts(normals, near, m, dim, f0, f1, f2, c):
        _add(out, owner[first], origins, pos, i, dim, f0, f1, f2)
        return
    rest0, rest1, rest2 = f0, f1, f2
    for u in range(m):
        a = near[u]
        p0 = c[u] * normals[a, 0]
        p1 = c[u] * normals[a, 1]
        p2 = c[u] * normals[a, 2] if dim == 3 else 0.0
        _add(out, owner[a], origins, pos, i, dim, p0, p1, p2)
        rest0 -= p0
        rest1 -= p1
        rest2 -= p2
    _add(out, owner[first], origins, pos, i, dim, rest0, rest1, rest2)


@njit(cache=True, inline="always")
def _add(out, g, origins, pos, i, dim, f0, f1, f2):
    """Group g's row += the force f at fluid particle i and its moment about its origin."""
    if g < 0:
        return
    out[g, 0] += f0
    out[g, 1] += f1
    out[g, 2] += f2
    r0 = pos[i, 0] - origins[g, 0]
    r1 = pos[i, 1] - origins[g, 1]
    r2 = pos[i, 2] - origins[g, 2] if dim == 3 else 0.0
    out[g, 3] += r1 * f2 - r2 * f1
    out[g, 4] += r2 * f0 - r0 * f2
    out[g, 5] += r0 * f1 - r1 * f0
