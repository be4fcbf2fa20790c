"""Collision detection and response against wall planes (paper sections 2 and 3).

A particle is a rigid sphere of radius r (m) whose centre moved, with no walls present,
from C0 (``pos0``, start of the step) to C1 (``pos``, end of the step). Each wall is a
plane n . (X - X0) = 0 (Eq. 3) with the unit normal n pointing into the domain, and the
signed distance of a centre C to it is d = n . (C - X0) = n . C - offset (Eq. 4, m),
``offset = n . X0``. The particle is inside when d >= r for every plane.

Per particle and step (section 2.2), with the segment A = C0, B = C1:

1. Detection: a plane collides when d_B < r - tol (Fig. 2 B and C).
2. First contact (Eqs. 5-7): along A -> B the sphere touches a plane at the fraction
   f = (d_A - r) / (d_A - d_B) (Eq. 7 divided by |C1 - C0|); f = 0 when d_A <= r. The
   colliding plane with the smallest f is the collision plane (Fig. 5).
3. Response: B += (1 + CR)(r - d_B) n (Eqs. 1 and 8); the normal velocity component
   u = v . n, if negative (moving out of the domain), becomes +CR |u_c| (Eq. 2, see
   below); the tangential velocity is never changed.
4. The new segment runs from the contact point A' = A + f (B_old - A) (C0', Fig. 6) to
   the reflected B; repeat until no plane collides (Fig. 7), at most ``max_reflections``
   times. A particle still outside then is put back at C0 (admissible at the start of
   the step) with its reflected velocity: the *guard*. No particle ever ends outside.

Restitution. The paper calls CR a restitution coefficient of kinetic energy, but Eq. 2
scales the normal *velocity* by CR, so the normal kinetic energy is multiplied by CR**2
(CR = 1: elastic, CR = 0: the normal motion stops at the wall); the tangential kinetic
energy is kept. The position response (Eq. 1) puts the centre CR (r - d_B) back inside,
the distance a particle rebounding with CR times its speed covers in the rest of the step.

Velocity at contact (the default). The integrator hands over the end-of-step velocity
and the step's acceleration a. Under constant a the normal speed at the contact is
u_c**2 = u**2 + 2 a_n (r - d_B), a_n = a . n (free motion from contact to B), and after
rebounding with CR |u_c| the particle sits CR (r - d_B) inside, hence
u_f**2 = CR**2 u_c**2 + 2 a_n CR (r - d_B), u_f = +sqrt(max(0, u_f**2)). With a_n = 0 this
is Eq. 2 exactly (u_f = -CR u). With it, a ball under gravity keeps its mechanical
energy v**2/2 - a . x to round-off across bounces when CR = 1, and leaves each bounce with
exactly CR**2 times the normal energy it hit the wall with. Eq. 2 applied literally at
the end point (``velocity_at_contact=False``: u_f = -CR u) changes the energy of a ball
in a gravity field by O(|a| |v| dt) per bounce, because the position is mirrored but the
velocity is not corrected for the work of gravity between contact and mirror point.
The max(0, .) only matters for a bounce lower than one step's travel (the mirror point
is then above the bounce's apex); the particle is left there at rest along n.

Tolerance. tol = 1e-9 r (a femtometre for a micrometre particle): particles resting
exactly at d = r, as in the paper's static cases (section 4.1), stay untouched bit for
bit even when d evaluates to r minus an ulp on slanted planes. It must stay well above
the round-off of n . C (about 1e-16 |C|), i.e. r >> 1e-7 |C|, true for any SPH case.
"""

from __future__ import annotations

from typing import NamedTuple

import numba
import numpy as np

from sphcore.api import box_cells, by_size, face_distance, particle_distance, plane_distance

from .corner import MAX_ACTIVE, respond
from .facecontact import contact_normal, earliest_face, near_any_face

#: side of the face grid's cells in particle radii. A step's box (2 r + the step) spans at
#: most three cells per axis for steps up to 2 r; cells of 2 r list few faces each: with a
#: 10^4-triangle mesh the kernel took 6 % of a 3D step, against 17 % with cells of 4 r
#: (benchmarks/speed/bench_faces.py)
CELL_RADII = 2.0

#: relative contact allowance: a plane collides only when d < r - TOL_REL * r
TOL_REL = 1e-9


class WallGroup(NamedTuple):
    """The walls of one group: planes and finite faces, in the frame of the particles.

    ``normals`` (k, dim) float64: unit normals of the planes, pointing into the domain;
    ``offsets`` (k,) float64: n . X0 (m) for a point X0 of each plane; then the fields of
    :class:`.facecontact.FaceSet`, the finite faces with their grid (no faces: nf = 0):
    ``verts`` (nf, dim, dim) float64 vertices (m), ``lo`` (3,) float64 the grid's lower
    corner (m), ``inv_cell`` 1 / its cell side (1/m), ``shape`` (3,) int64 cells per axis,
    ``start`` (ncells + 1,) int64 and ``items`` int32, the faces of each cell. A group is
    the unit a pose (rotation, centre, velocity) would attach to; the walls here are
    fixed. Flat, not a FaceSet inside: a record within a record cannot enter a numba
    parallel loop (its lowering fails).
    """

    normals: np.ndarray
    offsets: np.ndarray
    verts: np.ndarray
    lo: np.ndarray
    inv_cell: float
    shape: np.ndarray
    start: np.ndarray
    items: np.ndarray

    @classmethod
    def of(cls, normals, offsets, faces):
        """The group of planes (``normals``, ``offsets``) and ``faces`` (a FaceSet)."""
        return cls(normals, offsets, *faces)


class Paths(NamedTuple):
    """The particles' paths over one step, (n, dim) C-contiguous float64 unless noted.

    ``pos0``: start positions C0 (m), only read; ``pos``: end positions C1 (m), changed in
    place; ``vel``: end-of-step velocity (m/s), changed in place; ``acc``: the step's
    acceleration (m/s^2), only read; ``radius`` (n,): the particles' radii (m).
    """

    pos0: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    acc: np.ndarray
    radius: np.ndarray


class Response(NamedTuple):
    """How a collision is answered.

    ``cr``: restitution coefficient (Eq. 2), 0 <= cr <= 1 (no unit); ``max_reflections``:
    reflections per particle and step before the guard (int >= 0);
    ``velocity_at_contact``: Eq. 2 at the contact point (True) or at the end point.
    """

    cr: float
    max_reflections: int
    velocity_at_contact: bool


class Tally(NamedTuple):
    """Per-particle outputs of a step, written for every particle.

    ``guarded`` (n,) int8: 1 where the guard put the particle back at pos0, else 0;
    ``reflections`` (n,) int32: reflections performed (0: untouched).
    """

    guarded: np.ndarray
    reflections: np.ndarray


@numba.njit(cache=True)
def contact_limit(r):
    """The collision threshold r - tol (m): a plane collides when d < contact_limit(r)."""
    return r - TOL_REL * r


@by_size
def reflect(pos0, pos, vel, acc, radius, normals, offsets, verts, glo, ginv, gshape, gstart,
            gitems, ws, wi, cr, max_reflections, velocity_at_contact, guarded_flags, reflection_counts):
    """Reflect every particle that left the domain during a step; return (guard returns,
    particles reflected, reflections performed) of the step.

    pos0, pos, vel, acc: (n, dim) C-contiguous float64: start and end positions (m),
    end-of-step velocity (m/s), the step's acceleration (m/s^2). radius (n,) m.
    normals (k, dim) unit vectors into the domain, offsets (k,) = n . X0 (m).
    verts (nf, dim, dim): finite faces (:mod:`sphcore.geometry.faces`), with their grid
    (glo, ginv, gshape, gstart, gitems: :meth:`sphcore.geometry.facegrid.FaceGrid.arrays`).
    ws, wi: scratch rows for corner contacts, one per block of particles (:func:`.corner.scratch`).
    cr: restitution coefficient (Eq. 2), 0 <= cr <= 1. max_reflections: int >= 0.
    velocity_at_contact: bool, Eq. 2 at the contact point (True) or at the end point.
    guarded_flags (n,) int8 out: 1 where the guard put the particle back at pos0.
    reflection_counts (n,) int32 out: reflections performed (0: untouched).
    ``pos`` and ``vel`` are changed in place; ``pos0`` and ``acc`` are only read.
    """
    n = pos.shape[0]
    three = pos.shape[1] == 3
    rows = ws.shape[0]
    guarded = 0
    reflected = 0
    events = 0
    # blocks of particles, each with its own scratch row for corner contacts
    for b in numba.prange(rows):
        g = 0
        r = 0
        e = 0
        for i in range(b * n // rows, (b + 1) * n // rows):
            guarded_flags[i] = 0
            reflection_counts[i] = 0
            # most particles touch no wall: one cheap pass over the planes (and the faces
            # listed near the step) decides; the full loop costs ten times more per particle
            lim = contact_limit(radius[i])
            hit = False
            for k in range(normals.shape[0]):
                if particle_distance(normals, offsets, k, pos, i) < lim:
                    hit = True
                    break
            if not hit and verts.shape[0]:
                hit = near_any_face(verts, glo, ginv, gshape, gstart, gitems, pos0[i, 0], pos0[i, 1],
                                    pos0[i, 2] if three else 0.0, pos[i, 0], pos[i, 1],
                                    pos[i, 2] if three else 0.0, lim)
            if hit:
                g += _reflect_one(i, pos0, pos, vel, acc, radius, normals, offsets, verts, glo, ginv,
                                  gshape, gstart, gitems, ws[b], wi[b], cr, max_reflections,
                                  velocity_at_contact, guarded_flags, reflection_counts)
                if reflection_counts[i] > 0:
                    r += 1
                    e += reflection_counts[i]
        guarded += g
        reflected += r
        events += e
    return guarded, reflected, events


@numba.njit(cache=True)
def _reflect_one(i, pos0, pos, vel, acc, radius, normals, offsets, verts, glo, ginv, gshape, gstart,
                 gitems, ws, wi, cr, max_reflections, velocity_at_contact, guarded_flags, reflection_counts):
    """The paper's loop for particle i (earliest contact first, until inside or the guard);
    returns 1 if the guard put it back at pos0, else 0. Planes and faces compete for the
    earliest contact; when a wall is met a second time in the step and the contact touches
    two or more walls, that contact is resolved as one (:mod:`.corner`) if CR < 1. With
    CR = 1 the paper's sequence is the exact (billiard) answer and ends in any corner (a
    wedge of angle a lets a path through after about pi / a reflections): it is kept."""
    dim = pos.shape[1]
    nplanes = normals.shape[0]
    guarded = 0
    # start A of the current sub-segment: C0, then C0' after a reflection (no allocation)
    a0 = pos0[i, 0]
    a1 = pos0[i, 1]
    a2 = pos0[i, 2] if dim == 3 else 0.0
    r = radius[i]
    lim = contact_limit(r)
    count = 0
    while True:
        best = -1
        fbest = np.inf
        dbest = 0.0
        for k in range(nplanes):
            db = particle_distance(normals, offsets, k, pos, i)
            if db < lim:
                da = plane_distance(normals, offsets, k, a0, a1, a2)
                # d_A <= r: touching at the start (rest, C1 = C0, parallel motion): f = 0
                # otherwise d_A > r > d_B, so the denominator is positive
                f = 0.0 if da <= r else (da - r) / (da - db)
                if f < fbest:
                    fbest = f
                    best = k
                    dbest = db
        b2 = pos[i, 2] if dim == 3 else 0.0
        face, fbest = earliest_face(verts, glo, ginv, gshape, gstart, gitems, a0, a1, a2,
                                    pos[i, 0], pos[i, 1], b2, r, lim, fbest)
        if best < 0 and face < 0:
            break
        if count == max_reflections:
            # guard: C0 is inside (the invariant); keep the velocity reflected so far
            for j in range(dim):
                pos[i, j] = pos0[i, j]
            guarded_flags[i] = 1
            guarded = 1
            break
        # contact point C0' (Fig. 6): inside every wall, so the invariant holds for A
        a0 += fbest * (pos[i, 0] - a0)
        a1 += fbest * (pos[i, 1] - a1)
        if dim == 3:
            a2 += fbest * (pos[i, 2] - a2)
        if face >= 0:  # the plane tangent at the contact (see .facecontact)
            n0, n1, n2, off = contact_normal(verts, face, a0, a1, a2, pos0[i, 0], pos0[i, 1],
                                             pos0[i, 2] if dim == 3 else 0.0)
            dbest = plane_distance_n(n0, n1, n2, off, pos[i, 0], pos[i, 1], b2)
        else:
            n0 = normals[best, 0]
            n1 = normals[best, 1]
            n2 = normals[best, 2] if dim == 3 else 0.0
        # a wall met again in this step means ping-pong between walls (a wedge): then the
        # contact is resolved with every wall touching there at once (wi[11:19]: the last
        # eight walls met, planes by index, faces after them); not with CR = 1, whose
        # sequence ends (the joint response's point reflection through a corner is the
        # billiard's end point only where the walls are perpendicular)
        wall = best if face < 0 else nplanes + face
        revisit = False
        for h in range(min(count, 8)):
            if wi[11 + h] == wall:
                revisit = True
        wi[11 + count % 8] = wall
        count += 1
        if revisit and cr < 1.0 and _corner(i, pos, vel, normals, offsets, verts, glo, ginv, gshape,
                                            gstart, gitems, a0, a1, a2, r, cr, ws, wi):
            continue
        depth = r - dbest  # > 0, how far the end point lies beyond contact (m)
        u = vel[i, 0] * n0 + vel[i, 1] * n1
        an = acc[i, 0] * n0 + acc[i, 1] * n1
        if dim == 3:
            u += vel[i, 2] * n2
            an += acc[i, 2] * n2
        if u < 0.0:  # never reverse a particle already moving back in
            if velocity_at_contact:
                uc2 = max(u * u + 2.0 * an * depth, 0.0)
                uf = np.sqrt(max(cr * cr * uc2 + 2.0 * an * cr * depth, 0.0))
            else:
                uf = -cr * u
            vel[i, 0] += (uf - u) * n0
            vel[i, 1] += (uf - u) * n1
            if dim == 3:
                vel[i, 2] += (uf - u) * n2
        shift = (1.0 + cr) * depth  # |t| of Eq. 1
        pos[i, 0] += shift * n0
        pos[i, 1] += shift * n1
        if dim == 3:
            pos[i, 2] += shift * n2
    reflection_counts[i] = count
    return guarded


@numba.njit(cache=True)
def plane_distance_n(n0, n1, n2, off, x0, x1, x2):
    """n . x - off for a plane given by scalars (the tangent plane of a face contact)."""
    return n0 * x0 + n1 * x1 + n2 * x2 - off


@numba.njit(cache=True)
def _corner(i, pos, vel, normals, offsets, verts, glo, ginv, gshape, gstart, gitems, a0, a1, a2,
            r, cr, ws, wi):
    """Resolve the contact at A as one with every wall touching there (:mod:`.corner`) when
    two or more do; False (nothing changed) otherwise. ws, wi: this thread's scratch."""
    dim = pos.shape[1]
    touch = r * (1.0 + 1e-6)
    nrm = ws[0:MAX_ACTIVE * dim].reshape((MAX_ACTIVE, dim))
    c = ws[24:24 + MAX_ACTIVE]
    ids = wi[3:3 + MAX_ACTIVE]  # faces already taken (a face is listed in several cells)
    nf_seen = 0
    m = 0
    for k in range(normals.shape[0]):
        if m < MAX_ACTIVE and plane_distance(normals, offsets, k, a0, a1, a2) <= touch:
            nrm[m, :] = normals[k, :]
            c[m] = offsets[k] + r
            m += 1
    if verts.shape[0]:
        x0, x1, y0, y1, z0, z1 = box_cells(glo, ginv, gshape, dim, a0, a1, a2, a0, a1, a2, touch)
        for x in range(x0, x1 + 1):
            for y in range(y0, y1 + 1):
                for z in range(z0, z1 + 1):
                    cc = (x * gshape[1] + y) * gshape[2] + z
                    for s in range(gstart[cc], gstart[cc + 1]):
                        f = gitems[s]
                        seen = False
                        for k in range(nf_seen):
                            if ids[k] == f:
                                seen = True
                        if not seen and m < MAX_ACTIVE and face_distance(verts, f, a0, a1, a2) <= touch:
                            ids[nf_seen] = f
                            nf_seen += 1
                            n0, n1, n2, off = contact_normal(verts, f, a0, a1, a2, a0, a1, a2)
                            nrm[m, 0] = n0
                            nrm[m, 1] = n1
                            if dim == 3:
                                nrm[m, 2] = n2
                            c[m] = off + r
                            m += 1
    if m < 2:
        return False
    return respond(nrm, c, m, pos, vel, i, cr, TOL_REL * r, ws, wi)


def reflect_step(paths, walls, response, tally, work):
    """Reflect every particle that left the domain during a step; return (guard returns,
    particles reflected, reflections performed) of the step.

    ``paths``: :class:`Paths` (``pos`` and ``vel`` are changed in place); ``walls``: a
    :class:`WallGroup`; ``response``: :class:`Response`; ``tally``: :class:`Tally`,
    written for every particle; ``work``: :class:`.corner.Scratch` as :func:`.corner.scratch`
    allocates it, one row per block of particles.

    The records stop here: the kernel :func:`reflect` takes their arrays and scalars one by
    one. numba types a named-tuple argument in Python at every call, about 1 us per
    record, and the records as the kernel's arguments cost 1-4 % of a step's reflection
    (10 000 to 160 000 particles, measured); passed further down, to the functions
    called per reflected particle, 5-8 %.
    """
    return reflect(paths.pos0, paths.pos, paths.vel, paths.acc, paths.radius, walls.normals, walls.offsets,
                   walls.verts, walls.lo, walls.inv_cell, walls.shape, walls.start, walls.items, work.floats,
                   work.ints, response.cr, response.max_reflections, response.velocity_at_contact, tally.guarded,
                   tally.reflections)
