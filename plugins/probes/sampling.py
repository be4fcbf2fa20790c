"""Sampling the particle fields at fixed points: numba functions over plain arrays.

Nothing here knows the simulation object: the plugin passes positions, densities,
pressures, masses, the kernel and the wall planes. Per sample the plugin first keeps the
few fluid particles within the kernel support (2h) of any probe (:func:`select_near`, one
pass over the particles); the interpolations then loop over that short list only.

Definitions (h the smoothing length, W the run's kernel, V_j = m_j / rho_j):

- pressure, ``particle`` mode: p(x) = sum_j V_j p_j W(x - x_j) / sum_j V_j W(x - x_j)
  (Shepard-normalised, so a constant field is reproduced exactly even where the wall
  truncates the kernel);
- pressure, ``wall`` mode: p(x) = sum_j V_j (p_j + rho_j g.(x - x_j)) W / sum_j V_j W: each
  particle's pressure carried hydrostatically to the sensor point, the pressure a wall
  carries in a boundary-integral wall model. For a hydrostatic field of constant density
  it is exactly rho g (H - y) at any point; with the Tait densities of a column at rest it
  is within max_j |rho_j - rho0| |g| 2h of it. A sensor on a wall face reads only the
  particles in front of that face ((x_j - x) . n > 0, n the face's normal into the fluid):
  a transducer is pressed by the water touching its face, not by water round a convex edge
  of the wall within 2h of it (the flow over the top of an obstacle, below which a sensor
  sits); on a plane wall or inside a concave corner no particle lies behind the face, so
  the filter changes nothing there. On a sensor riding with moving walls g is the apparent
  gravity g - a_w of the wall's frame (a_w the wall's acceleration at the sensor point),
  the field in which water at rest relative to the wall is hydrostatic;
- no fluid particle within 2h of the point: the point is dry, p = 0 (gauge) and flagged;
- fluid fraction: phi(x) = sum_j V_j W(x - x_j), each particle also counted through its
  mirror image across every wall plane closer than 2h to x (a wall would otherwise cut the
  kernel and halve phi at the floor); phi is ~1 in water, 0 in air, 0.5 at a free surface;
- water depth above a floor point x0: scanning up from x0 along -g (a gauge riding with
  moving walls: -g turned with them) in steps ds, the distance s at which phi first drops
  below 0.5 (linear interpolation between the last step at or above 0.5 and the first
  below it); 0 when phi(x0) < 0.5 (dry). Water above an air gap (spray, an overturning
  jet) does not count: only the first crossing does.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

from sphcore.api import SUPPORT, kernel_w

SURFACE_FRACTION = 0.5  # fluid fraction that marks the free surface


@njit(cache=True)
def _dist2_segment(x, a, b):
    """Squared distance (m^2) from point x to the segment [a, b] (a == b: a point)."""
    dim = x.shape[0]
    ab2 = 0.0
    t = 0.0
    for d in range(dim):
        ab = b[d] - a[d]
        ab2 += ab * ab
        t += (x[d] - a[d]) * ab
    t = 0.0 if ab2 == 0.0 else min(1.0, max(0.0, t / ab2))
    r2 = 0.0
    for d in range(dim):
        e = x[d] - (a[d] + t * (b[d] - a[d]))
        r2 += e * e
    return r2


@njit(cache=True)
def select_near(pos, kind, seg_a, seg_b, reach, out):
    """Write into ``out`` the indices of fluid particles (kind 0) within ``reach`` (m) of
    any segment [seg_a[k], seg_b[k]] (shapes (k, dim)); returns how many.

    A bounding-box test rejects most particles before the segment distance is computed.
    ``out`` must hold pos.shape[0] entries.
    """
    n, dim = pos.shape
    ns = seg_a.shape[0]
    lo = np.empty((ns, dim))
    hi = np.empty((ns, dim))
    for k in range(ns):
        for d in range(dim):
            lo[k, d] = min(seg_a[k, d], seg_b[k, d]) - reach
            hi[k, d] = max(seg_a[k, d], seg_b[k, d]) + reach
    r2 = reach * reach
    c = 0
    for i in range(n):
        if kind[i] != 0:
            continue
        for k in range(ns):
            inside = True
            for d in range(dim):
                if pos[i, d] < lo[k, d] or pos[i, d] > hi[k, d]:
                    inside = False
                    break
            if inside and _dist2_segment(pos[i], seg_a[k], seg_b[k]) < r2:
                out[c] = i
                c += 1
                break
    return c


@njit(cache=True)
def interpolate_pressure(points, pos, p, rho, m, kernel_id, h, gravity, wall, face_n, out_p, out_w):
    """Shepard-normalised pressure (Pa) at each of ``points`` (k, dim) into ``out_p``, and the
    Shepard sum sum_j V_j W (1) into ``out_w`` (0: no particle in the support, out_p = 0).

    ``wall``: add rho_j g.(x - x_j) to each particle's pressure (wall mode, see the module
    docstring). ``gravity`` has at least dim components (m/s^2). ``face_n`` (dim,): the
    normal of the wall face the sensor sits on, into the fluid; particles with
    (x_j - x) . face_n <= 0 are not read. A zero vector reads every particle.
    """
    k, dim = points.shape
    n = pos.shape[0]
    rmax = SUPPORT * h
    facing = False
    for d in range(dim):
        facing = facing or face_n[d] != 0.0
    for s in range(k):
        num = 0.0
        den = 0.0
        for j in range(n):
            r2 = 0.0
            front = 0.0
            for d in range(dim):
                e = points[s, d] - pos[j, d]
                r2 += e * e
                front -= e * face_n[d]
            if facing and front <= 0.0:
                continue
            r = math.sqrt(r2)
            if r >= rmax:
                continue
            w = kernel_w(kernel_id, r, h, dim) * m[j] / rho[j]
            pj = p[j]
            if wall:
                gh = 0.0
                for d in range(dim):
                    gh += gravity[d] * (points[s, d] - pos[j, d])
                pj += rho[j] * gh
            num += w * pj
            den += w
        out_w[s] = den
        out_p[s] = num / den if den > 0.0 else 0.0


@njit(cache=True)
def _fraction(x, pos, rho, m, order, first, last, kernel_id, h, normals, offsets):
    """phi(x) over the particles order[first:last] (see :func:`fluid_fraction`)."""
    dim = x.shape[0]
    rmax = SUPPORT * h
    nq = normals.shape[0]
    phi = 0.0
    for jj in range(first, last):
        j = order[jj]
        v = m[j] / rho[j]
        r2 = 0.0
        for d in range(dim):
            e = x[d] - pos[j, d]
            r2 += e * e
        if r2 < rmax * rmax:
            phi += v * kernel_w(kernel_id, math.sqrt(r2), h, dim)
        for q in range(nq):
            dx_ = -offsets[q]
            dj = -offsets[q]
            for d in range(dim):
                dx_ += normals[q, d] * x[d]
                dj += normals[q, d] * pos[j, d]
            if dx_ >= rmax:
                continue
            r2 = 0.0
            for d in range(dim):
                e = x[d] - (pos[j, d] - 2.0 * dj * normals[q, d])
                r2 += e * e
            if r2 < rmax * rmax:
                phi += v * kernel_w(kernel_id, math.sqrt(r2), h, dim)
    return phi


@njit(cache=True)
def fluid_fraction(x, pos, rho, m, kernel_id, h, normals, offsets):
    """phi(x) = sum_j V_j W(x - x_j), with mirror images across every wall plane (normals
    (q, dim) into the fluid, offsets (q,): distance = n.x - offset) closer than 2h to x."""
    order = np.arange(pos.shape[0])
    return _fraction(x, pos, rho, m, order, 0, pos.shape[0], kernel_id, h, normals, offsets)


@njit(cache=True)
def depth_above(x0, up, ds, pos, rho, m, kernel_id, h, normals, offsets):
    """Water depth (m) above the floor point ``x0`` along the unit vector ``up``: see the
    module docstring. ``ds`` (m) is the scan step; candidates ``pos`` etc. should hold every
    fluid particle within 2h of the vertical line.

    The candidates are sorted by height, so each scan position only visits those within 2h
    of it in height (a window that moves up with the scan).
    """
    dim = x0.shape[0]
    n = pos.shape[0]
    rmax = SUPPORT * h
    z = np.empty(n)
    for j in range(n):
        zj = 0.0
        for d in range(dim):
            zj += (pos[j, d] - x0[d]) * up[d]
        z[j] = zj
    order = np.argsort(z)
    x = x0.copy()
    first, last = 0, 0
    while last < n and z[order[last]] < rmax:
        last += 1
    phi_prev = _fraction(x, pos, rho, m, order, first, last, kernel_id, h, normals, offsets)
    if phi_prev < SURFACE_FRACTION:
        return 0.0
    s_max = z[order[n - 1]] + rmax  # nothing lies above the highest candidate plus the support
    s = 0.0
    while s < s_max:
        s_next = s + ds
        for d in range(dim):
            x[d] = x0[d] + s_next * up[d]
        while first < n and z[order[first]] <= s_next - rmax:
            first += 1
        while last < n and z[order[last]] < s_next + rmax:
            last += 1
        phi = _fraction(x, pos, rho, m, order, first, last, kernel_id, h, normals, offsets)
        if phi < SURFACE_FRACTION:
            return s + (phi_prev - SURFACE_FRACTION) / (phi_prev - phi) * ds
        s, phi_prev = s_next, phi
    return s_max


def line_points(start, end, n):
    """``n`` sample points (n, dim) at the centres of n equal pieces of [start, end]
    (one point: the start itself)."""
    start, end = np.asarray(start, float), np.asarray(end, float)
    if n == 1 or np.array_equal(start, end):
        return start[None, :].copy()
    f = (np.arange(n) + 0.5) / n
    return np.ascontiguousarray(start[None, :] + f[:, None] * (end - start)[None, :])
