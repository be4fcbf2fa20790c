"""Mirror (ghost) particles across wall planes, as numba kernels over struct-of-arrays.

Each wall is a plane n . X = offset (``sphcore.geometry.planes.Planes``) with the unit normal n
pointing into the domain; the signed distance of a point x is d = n . x - offset (m),
positive inside. The reflection of x across plane k is R_k(x) = x - 2 d_k(x) n_k.

Images (Fraga Filho 2017, ghost particles in an extended domain; Libersky et al. 1993):

- every fluid particle with 0 < d_k < 2h (the kernel support) gets R_k(x);
- a particle within the support of several planes also gets the image across each
  subset of them, up to ``max_order`` planes (2 in 2D, 3 in 3D): R_b(R_a(x)) for a < b,
  composed in plane index order, so the support of a particle in a corner is full;
- an image is kept only if it lies outside the domain (d < -tol for some plane). A single
  image always does; a double image at a non-right-angle corner may fall back inside the
  fluid region, and is dropped. Mirror images tile the exterior exactly only at right
  angles; at other angles the corner is covered approximately (the usual limitation of
  mirror ghosts).

Ghost state, from the mirrored fluid particle i:

- mass m_g = m_i;
- pressure p_g = p_i + (rho_i - rho_ref) g . (x_g - x_i) with the hydrostatic correction
  (a ghost below a floor sits deeper and carries the higher hydrostatic pressure, so water
  at rest feels no net wall force; Fraga Filho 2017 builds the same balance with modified
  pressure), else p_i. p is the pressure the momentum equation uses: the Tait pressure
  (rho_ref = 0), or with the core's modified pressure (Batchelor 1967) its dynamic part
  P = p - rho0 g (z_s - z), whose mirror then carries only the non-hydrostatic remainder
  (rho_ref = rho0, since P_g = p_g - rho0 |g| (z_s - z_g));
- density from that pressure through the inverse Tait equation (Monaghan 1994)
  rho_g = rho0 ((p_g - p_b) / B + 1)^(1/gamma), B = c0^2 rho0 / gamma, the base clamped at
  ``TAIT_BASE_MIN``; without the correction rho_g = rho_i;
- velocity: free slip reflects it with the position (normal component reversed,
  tangential kept, v_g = v - 2 (v . n) n per plane); no slip reverses it, v_g = -v_i, so
  the wall velocity (zero) is the average of the pair.

Walls that move (a tank on a prescribed path, :mod:`sphcore.geometry.motion`): the planes
are those of the force evaluation's time, and the tank is a rigid body whose point now at x
moves with v_w(x) = V + Omega x r and accelerates with a_w(x) = A + alpha x r + Omega x
(Omega x r), r = x - c - D (:class:`WallMotion`). The images' state follows the wall:

- free slip: the rule above on the velocity relative to the wall, plane by plane, at the
  foot f = x - d n of the point being mirrored (for a single image the mirror point on the
  wall): v <- v - 2 ((v - v_w(f)) . n) n;
- no slip: v_g = 2 v_w(m) - v_i, m = (x_i + x_g) / 2 the wall point between the pair (the
  foot for a single image, the corner for a corner image), so that the pair again averages
  to the wall's velocity;
- pressure (with the hydrostatic correction): the fluid at rest relative to an
  accelerating wall has grad p = rho (g - a_w), so the correction carries the pressure with
  g - a_w instead of g, as Adami, Hu & Adams (2012, J. Comput. Phys. 231, 7057-7075,
  Eq. 27) do for the pressure of dummy wall particles,
  p_w = (sum_f p_f W_wf + (g - a_w) . sum_f rho_f r_wf W_wf) / sum_f W_wf, r_wf = x_w - x_f:
  p_g = p_i + (rho_i - rho_ref) g . (x_g - x_i) - rho_i a_w(m) . (x_g - x_i).
  The wall's acceleration enters with the full density rho_i also under modified pressure,
  which removes rho0 g only. a_w is taken at the midpoint m of the segment from x_i to x_g,
  where the line integral of the affine field rho_i (g - a_w(x)) along the segment is exact
  (midpoint rule); Adami et al. take it at the dummy particle, the same for a translation.

A case whose walls do not move takes the fixed-wall kernels (the same bits as ever).

Generation is two numba passes over the particles (count, then fill at exclusive
prefix-sum offsets), so no Python list is built; both run over all threads from
``PARALLEL_MIN`` particles on. :class:`.images.MirrorImages` keeps the output buffers and
grows them geometrically; the kernels of a moving tank are in :mod:`.moving`.

The passes take their arguments as records (named tuples, :mod:`.records`): the fluid as
:class:`sphcore.api.Fields`, the wall planes as a :class:`PlaneGroup`, the image rule as a
:class:`MirrorRule`, the ghost state's constants as a :class:`GhostPressure`, the motion of
moving walls as a :class:`WallMotion`, the per-particle bookkeeping of the passes as
:class:`Passes` and the output buffers as :class:`Images`. For fixed walls,
:func:`count_images` and :func:`fill_images` hand the records' arrays and scalars to their
numba kernels one by one: numba types a named-tuple argument in Python at every call (about
1 us a record), and with the records as the kernels' arguments the passes ran 2-4 % slower;
passed on to the helpers called per particle, 1.2 to 1.5 times slower (measured).
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from sphcore.api import FLUID, eos, plane_distance

#: smallest base (p - p_b)/B + 1 of the inverse Tait equation: keeps rho_g real and
#: positive (>= 0.37 rho0 for gamma = 7) under strong tension
TAIT_BASE_MIN = eos.BASE_MIN

#: plane subsets are bit masks of one int64
MAX_PLANES = 62

#: particle count from which the two passes run on all threads. The passes are light
#: (a few plane distances per particle; the images only near walls), so below this a
#: thread start costs more than it saves: on the shared 2-core test machine the serial
#: passes took 1.4 + 1.1 ms for 160 000 particles, the parallel ones 2.7 + 0.5 ms
PARALLEL_MIN = 250_000

#: relative tolerance (of the support) for "on the plane": a particle exactly on a wall
#: makes an image on top of itself, which carries no information
TOL_REL = 1e-9


@njit(cache=True, inline="always")
def popcount(mask):
    c = 0
    while mask:
        c += mask & 1
        mask >>= 1
    return c


@njit(cache=True, inline="always")
def _image(pos, vel, i, normals, offsets, sub, free_slip, tol):
    """Image of particle i across the planes in ``sub`` (index order).

    Returns (keep, x0, x1, x2, v0, v1, v2); keep is True when the image lies outside the
    domain (behind at least one plane by more than tol).
    """
    dim = pos.shape[1]
    x0, x1 = pos[i, 0], pos[i, 1]
    v0, v1 = vel[i, 0], vel[i, 1]
    x2 = pos[i, 2] if dim == 3 else 0.0
    v2 = vel[i, 2] if dim == 3 else 0.0
    k = 0
    s = sub
    while s:
        if s & 1:
            n0, n1 = normals[k, 0], normals[k, 1]
            n2 = normals[k, 2] if dim == 3 else 0.0
            d = plane_distance(normals, offsets, k, x0, x1, x2)
            x0 -= 2.0 * d * n0
            x1 -= 2.0 * d * n1
            x2 -= 2.0 * d * n2
            if free_slip:
                vn = v0 * n0 + v1 * n1 + v2 * n2
                v0 -= 2.0 * vn * n0
                v1 -= 2.0 * vn * n1
                v2 -= 2.0 * vn * n2
        s >>= 1
        k += 1
    if not free_slip:
        v0, v1, v2 = -vel[i, 0], -vel[i, 1], (-vel[i, 2] if dim == 3 else 0.0)
    dmin = np.inf
    for k in range(normals.shape[0]):
        dmin = min(dmin, plane_distance(normals, offsets, k, x0, x1, x2))
    return dmin < -tol, x0, x1, x2, v0, v1, v2


@njit(cache=True, inline="always")
def near_chunk(pos, kind, normals, offsets, support, tol, near, lo, hi):
    """near[i] for lo <= i < hi: bit k set when tol < d_k < support (0 for non-fluid).

    Plane by plane over a chunk of particles: the inner loop has no data-dependent
    control flow, so it runs twice as fast as a particle-by-particle loop (measured), and
    this pass is all the work the bulk of the particles, far from every wall, ever costs.
    """
    dim = pos.shape[1]
    for i in range(lo, hi):
        near[i] = 0
    for k in range(normals.shape[0]):
        n0, n1, off = normals[k, 0], normals[k, 1], offsets[k]
        bit = np.int64(1) << k
        if dim == 2:
            for i in range(lo, hi):
                d = n0 * pos[i, 0] + n1 * pos[i, 1] - off
                if d > tol and d < support:
                    near[i] |= bit
        else:
            n2 = normals[k, 2]
            for i in range(lo, hi):
                d = n0 * pos[i, 0] + n1 * pos[i, 1] + n2 * pos[i, 2] - off
                if d > tol and d < support:
                    near[i] |= bit
    for i in range(lo, hi):
        if kind[i] != FLUID:
            near[i] = 0


@njit(cache=True, inline="always")
def _count_one(pos, vel, i, near, normals, offsets, max_order, free_slip, tol):
    """Number of kept images of a particle with near-plane mask ``near``."""
    c = 0
    sub = near
    while sub:  # every non-empty subset of the near planes
        if popcount(sub) <= max_order:
            if _image(pos, vel, i, normals, offsets, sub, free_slip, tol)[0]:
                c += 1
        sub = (sub - 1) & near
    return c


#: particles per chunk of the near-plane pass (64 KiB of 2D positions: stays in cache
#: while the planes are looped over)
CHUNK = 4096


@njit(cache=True, parallel=True)
def _count_pass(pos, vel, kind, normals, offsets, support, max_order, free_slip, tol, near, counts):
    """Pass 1: near[i] = mask of the planes within support of fluid particle i (0 for
    non-fluid), counts[i] = number of its kept images."""
    n = pos.shape[0]
    for c in prange((n + CHUNK - 1) // CHUNK):
        near_chunk(pos, kind, normals, offsets, support, tol, near, c * CHUNK, min(n, (c + 1) * CHUNK))
    for i in prange(n):
        counts[i] = _count_one(pos, vel, i, near[i], normals, offsets, max_order, free_slip, tol) if near[i] else 0


@njit(cache=True)
def _count_pass_serial(pos, vel, kind, normals, offsets, support, max_order, free_slip, tol, near, counts):
    """:func:`_count_pass` on one thread (small particle counts: no thread start-up)."""
    n = pos.shape[0]
    near_chunk(pos, kind, normals, offsets, support, tol, near, 0, n)
    for i in range(n):
        counts[i] = _count_one(pos, vel, i, near[i], normals, offsets, max_order, free_slip, tol) if near[i] else 0


def count_images(fluid, kind, walls, rule, passes):
    """Pass 1 over the particles of ``fluid`` (:class:`sphcore.api.Fields`; pos and vel are
    read) with ``kind`` (n,) int8 codes, against ``walls`` (:class:`PlaneGroup`) under
    ``rule`` (:class:`MirrorRule`): passes.near[i] = mask of the planes within the
    support of fluid particle i (0 for non-fluid), passes.counts[i] = number of its kept
    images (:class:`Passes`; start is not touched). On all threads."""
    _count_pass(fluid.pos, fluid.vel, kind, walls.normals, walls.offsets, rule.support, rule.max_order,
                rule.free_slip, rule.tol, passes.near, passes.counts)


def count_images_serial(fluid, kind, walls, rule, passes):
    """:func:`count_images` on one thread (small particle counts: no thread start-up)."""
    _count_pass_serial(fluid.pos, fluid.vel, kind, walls.normals, walls.offsets, rule.support, rule.max_order,
                       rule.free_slip, rule.tol, passes.near, passes.counts)


@njit(cache=True)
def exclusive_scan(counts, start):
    """start[0] = 0, start[i+1] = start[i] + counts[i]; returns the total."""
    start[0] = 0
    for i in range(counts.shape[0]):
        start[i + 1] = start[i] + counts[i]
    return start[counts.shape[0]]


@njit(cache=True, inline="always")
def _fill_one(pos, vel, rho, p, m, i, near, normals, offsets, max_order, free_slip, tol,
              hydrostatic, gravity, rho0, b, inv_gamma, p_background, rho_ref, j, gpos, gvel, grho, gp, gm, gsrc):
    """Write the images of particle i from row j on, in the order of :func:`_count_one`.

    Loose arrays and scalars, not the kernels' records: with a record passed in (even
    :class:`MirrorRule`, four scalars) this per-particle helper ran 1.5 times slower
    (pass 2, 40 000 particles, measured)."""
    dim = pos.shape[1]
    sub = near
    while sub:
        if popcount(sub) <= max_order:
            keep, x0, x1, x2, v0, v1, v2 = _image(pos, vel, i, normals, offsets, sub, free_slip, tol)
            if keep:
                gpos[j, 0] = x0
                gpos[j, 1] = x1
                gvel[j, 0] = v0
                gvel[j, 1] = v1
                rise = gravity[0] * (x0 - pos[i, 0]) + gravity[1] * (x1 - pos[i, 1])
                if dim == 3:
                    gpos[j, 2] = x2
                    gvel[j, 2] = v2
                    rise += gravity[2] * (x2 - pos[i, 2])
                if hydrostatic and b > 0.0:
                    # g . (x_g - x_i) > 0 when the ghost lies lower: more pressure there
                    pg = p[i] + (rho[i] - rho_ref) * rise
                    gp[j] = pg
                    grho[j] = eos.density(pg, rho0, b, inv_gamma, p_background)
                else:
                    gp[j] = p[i]
                    grho[j] = rho[i]
                gm[j] = m[i]
                gsrc[j] = i
                j += 1
        sub = (sub - 1) & near


@njit(cache=True, parallel=True)
def _fill_pass(pos, vel, rho, p, m, near, normals, offsets, max_order, free_slip, tol,
                hydrostatic, gravity, rho0, c0, gamma, p_background, rho_ref, start,
                gpos, gvel, grho, gp, gm, gsrc):
    """Pass 2: write the images of particle i at rows start[i]:start[i+1] (same order as pass 1).

    Ghost pressure and density: see the module docstring; b = c0^2 rho0 / gamma (Pa),
    computed here: with b given instead, the pass ran 5 % slower (160 000 particles, measured).
    """
    b = eos.tait_b(c0, rho0, gamma)
    for i in prange(pos.shape[0]):
        if start[i + 1] > start[i]:
            _fill_one(pos, vel, rho, p, m, i, near[i], normals, offsets, max_order, free_slip, tol, hydrostatic,
                      gravity, rho0, b, 1.0 / gamma, p_background, rho_ref, start[i], gpos, gvel, grho, gp, gm, gsrc)


@njit(cache=True)
def _fill_pass_serial(pos, vel, rho, p, m, near, normals, offsets, max_order, free_slip, tol,
                       hydrostatic, gravity, rho0, c0, gamma, p_background, rho_ref, start,
                       gpos, gvel, grho, gp, gm, gsrc):
    """:func:`_fill_pass` on one thread."""
    b = eos.tait_b(c0, rho0, gamma)
    for i in range(pos.shape[0]):
        if start[i + 1] > start[i]:
            _fill_one(pos, vel, rho, p, m, i, near[i], normals, offsets, max_order, free_slip, tol, hydrostatic,
                      gravity, rho0, b, 1.0 / gamma, p_background, rho_ref, start[i], gpos, gvel, grho, gp, gm, gsrc)


def fill_images(fluid, walls, rule, ghost, passes, out):
    """Pass 2: write the images of particle i of ``fluid`` (:class:`sphcore.api.Fields`) at
    rows passes.start[i]:passes.start[i + 1] of ``out`` (:class:`Images`), in the order of
    pass 1 (same ``walls`` and ``rule``); their pressure and density from ``ghost``
    (:class:`GhostPressure`, see the module docstring). On all threads."""
    _fill_by(_fill_pass, fluid, walls, rule, ghost, passes, out)


def fill_images_serial(fluid, walls, rule, ghost, passes, out):
    """:func:`fill_images` on one thread."""
    _fill_by(_fill_pass_serial, fluid, walls, rule, ghost, passes, out)


def _fill_by(kernel, fluid, walls, rule, ghost, passes, out):
    """Pass 2 by ``kernel`` (:func:`_fill_pass` or its serial twin), the records' fields one by one."""
    kernel(fluid.pos, fluid.vel, fluid.rho, fluid.p, fluid.m, passes.near, walls.normals, walls.offsets,
           rule.max_order, rule.free_slip, rule.tol, ghost.hydrostatic, ghost.gravity, ghost.rho0, ghost.c0,
           ghost.gamma, ghost.p_background, ghost.rho_ref, passes.start, out.pos, out.vel, out.rho, out.p, out.m,
           out.src)
