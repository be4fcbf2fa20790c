"""Boundary-integral walls that move: the terms of a moving wall group, where it is now.

A moving group (:class:`sphcore.geometry.motion.MovingGroup`: the tank's planes, or finite
faces) is a rigid body with the pose x = c + D + R (X - c) (:class:`sphcore.geometry.motion.Pose`).
Its wall integrals are those of fixed walls evaluated where the walls are:

- planes are taken where they are (``ctx.planes`` at the run's time: the tank's moved as a
  whole, a piston's on its own); share, gradient, moment, lattice correction and projector
  are those of fixed planes at that place (``planes.py``), the lattice tables included (a
  tank's rigid motion keeps the walls' distances and angles);
- finite faces keep their reference vertices and face grid: each particle is taken into
  the group's frame, X = c + R^T (x - c - D), the terms are computed there with gravity
  in that frame, R^T g, and s, G, T g and the projector's directions are turned back
  with R (:func:`moving_face_terms`). A grid built once stays valid.

Both add the two terms of a moving wall (:class:`sphcore.physics.equations.WallTerms`):
``flux`` += v_w . G_k, with v_w = D' + Omega x (x - c - D) the wall's velocity at the
particle (the rigid motion's field at the particle rather than at the wall's nearest
point: they differ by |Omega| d < 2h |Omega|), and ``accel`` += T (-a_w) + s (-a_w), the
outside first moment of minus the wall's acceleration a_w = D'' + alpha x r + Omega x
(Omega x r) at the particle (the moment integral evaluated with -a_w in place of g).

A tank holding every wall takes its load from the fluid's momentum balance, exactly
(:func:`sphcore.api.tank_load`), and a solved pressure's part from the walls' kicks
(``ctx.solved_impulse``, :func:`sphcore.api.impulse_load`); another group takes that part
as its share of each kick, the kick's multiple of G written with the group's part G_k of G
(:func:`group_parts`, or the gradient its faces added). Otherwise (a piston, a paddle among
fixed walls) the load the fluid puts on the group is the reaction of the completion's terms
of its walls, F = sum_i m_i (2 (p_i / rho_i) G_k,i + ((rho_i - rho_ref)/rho_i) lambda A_k,i (g - a_w))
over the particles near it, with the exact first moment A_k (g - a_w) = T_k (g - a_w) +
s_k (g - a_w) of the group's walls, and its moment about the group's centre of rotation
where it is now, sum_i (x_i - c - D) x f_i (:func:`moving_face_terms` and
:func:`tank_terms` return both). The completion's neighbourhood scaling phi (<= 1, below 1
only for particles with a thin neighbourhood) and the discrete complement it takes for the
moment along the walls' normals are not separable by group: the load uses phi = 1 and the
exact moment, what they are on a full neighbourhood.
"""

from __future__ import annotations

import numpy as np
from numba import njit, prange

from sphcore.api import normal_parts, plane_distance

from .facewalls import add_terms, point_terms
from .normals import set_projector
from .share import wall_point

LOAD_ROWS = 64  # blocks of particles, one partial load sum each (threads write their own)


@njit(cache=True, inline="always")
def _rigid(x0, x1, x2, dim, origin, vel, acc, omega, alpha):
    """(v_w, a_w) as 6 scalars at the point x: the rigid motion's velocity and acceleration
    there, r = x - origin (origin = c + D)."""
    r0 = x0 - origin[0]
    r1 = x1 - origin[1]
    r2 = x2 - origin[2] if dim == 3 else 0.0
    w0, w1, w2 = omega[0], omega[1], omega[2]
    c0 = w1 * r2 - w2 * r1  # Omega x r
    c1 = w2 * r0 - w0 * r2
    c2 = w0 * r1 - w1 * r0
    e0 = w1 * c2 - w2 * c1  # Omega x (Omega x r)
    e1 = w2 * c0 - w0 * c2
    e2 = w0 * c1 - w1 * c0
    b0, b1, b2 = alpha[0], alpha[1], alpha[2]
    f0 = b1 * r2 - b2 * r1  # alpha x r
    f1 = b2 * r0 - b0 * r2
    f2 = b0 * r1 - b1 * r0
    v2 = vel[2] + c2 if dim == 3 else 0.0
    a2 = acc[2] + f2 + e2 if dim == 3 else 0.0
    return vel[0] + c0, vel[1] + c1, v2, acc[0] + f0 + e0, acc[1] + f1 + e1, a2


@njit(cache=True, inline="always")
def _add_load(load, b, dim, x0, x1, x2, origin, cp, ch, G0, G1, G2, A0, A1, A2):
    """Block b's load row += the force f = cp G + ch A at x and its moment about origin."""
    f0 = cp * G0 + ch * A0
    f1 = cp * G1 + ch * A1
    f2 = cp * G2 + ch * A2
    load[b, 0] += f0
    load[b, 1] += f1
    load[b, 2] += f2
    r0 = x0 - origin[0]
    r1 = x1 - origin[1]
    r2 = x2 - origin[2] if dim == 3 else 0.0
    load[b, 3] += r1 * f2 - r2 * f1
    load[b, 4] += r2 * f0 - r0 * f2
    load[b, 5] += r0 * f1 - r1 * f0


@njit(cache=True, inline="always")
def _group_part(x0, x1, x2, dim, normals, offsets, member, support, g0, g1, g2):
    """The part of the wall gradient G = (g0, g1, g2) that belongs to the planes with
    member[a]: G written in the normals of the planes within ``support`` of x,
    G = sum_a c_a n_a (G lies in their span), and the members' terms summed. Every near
    plane a member: G itself. Normals not independent (more than dim near planes, or
    parallel ones): all of G to the group of the nearest plane
    (:func:`sphcore.geometry.planes.normal_parts`)."""
    near = np.empty(3, np.int64)
    m = 0
    all_in = True
    some_in = False
    nearest = -1
    dmin = np.inf
    for a in range(normals.shape[0]):
        d = plane_distance(normals, offsets, a, x0, x1, x2)
        if d < support:
            if d < dmin:
                dmin, nearest = d, a
            if m < 3:
                near[m] = a
            m += 1
            all_in = all_in and member[a]
            some_in = some_in or member[a]
    if not some_in:
        return 0.0, 0.0, 0.0
    if all_in:
        return g0, g1, g2
    c = np.empty(3)
    if m <= dim and normal_parts(normals, near, m, dim, g0, g1, g2, c):
        p0 = 0.0
        p1 = 0.0
        p2 = 0.0
        for u in range(m):
            a = near[u]
            if member[a]:
                p0 += c[u] * normals[a, 0]
                p1 += c[u] * normals[a, 1]
                if dim == 3:
                    p2 += c[u] * normals[a, 2]
        return p0, p1, p2
    if member[nearest]:
        return g0, g1, g2
    return 0.0, 0.0, 0.0


@njit(cache=True, parallel=True)
def plane_group_terms(idx, count, pos, normals, offsets, member, own_normals, own_offsets, support, kernel_id, h,
                      origin, vel, acc, omega, alpha, gravity, coef_p, coef_h, share, grad, hydro, flux, accel, load):
    """A moving group's planes (member[a]: plane a of ``normals``, ``offsets`` is the
    group's; ``own_normals``, ``own_offsets``: those planes alone; all where they are now)
    for the particles idx[:count] near some plane, after the planes' own terms are in
    share, grad and hydro.

    The group's part of the wall gradient, G_k, is G_w written in the near planes' normals
    with the group's terms kept (:func:`_group_part`: G_w itself where every near plane is
    the group's, so that a tank carried at constant velocity sees 2 rho (v - v_w) . G_w
    with the lattice-corrected G_w of continuity; a piston's share where it meets a fixed
    floor). flux += v_w . G_k, accel += T_k (-a_w) + s_k (-a_w) of the group's planes alone;
    load (LOAD_ROWS, 6) += force and moment about ``origin`` of coef_p G_k + coef_h (T_k g
    + s_k g + accel_k) (coef_p = 2 m p / rho, coef_h = m lambda (rho - rho_ref) / rho), with
    share and hydro (lattice correction included) where the group holds every near plane.
    A group of one plane among others (a piston) takes the first moment's part along its
    normal only: the part along the wall holds the fluid next to it up (the mirror fluid's
    weight), which a free-slip plane does not carry; a tank carries it all, so that its load
    is the model's whole reaction.
    vel, acc, omega, alpha, gravity: 3-vectors (module docstring)."""
    dim = pos.shape[1]
    rows = load.shape[0]
    for b in prange(rows):
        for t in range(b * count // rows, (b + 1) * count // rows):
            i = idx[t]
            x0, x1 = pos[i, 0], pos[i, 1]
            x2 = pos[i, 2] if dim == 3 else 0.0
            G2 = grad[i, 2] if dim == 3 else 0.0
            k0, k1, k2 = _group_part(x0, x1, x2, dim, normals, offsets, member, support, grad[i, 0], grad[i, 1], G2)
            if k0 == 0.0 and k1 == 0.0 and k2 == 0.0:
                continue
            v0, v1, v2, a0, a1, a2 = _rigid(x0, x1, x2, dim, origin, vel, acc, omega, alpha)
            flux[i] += v0 * k0 + v1 * k1 + v2 * k2
            s, _, _, _, t0, t1, t2 = wall_point(x0, x1, x2, own_normals, own_offsets, kernel_id, h, -a0, -a1, -a2)
            m0 = t0 - s * a0
            m1 = t1 - s * a1
            m2 = t2 - s * a2 if dim == 3 else 0.0
            accel[i, 0] += m0
            accel[i, 1] += m1
            if dim == 3:
                accel[i, 2] += m2
            if k0 == grad[i, 0] and k1 == grad[i, 1] and k2 == G2:  # every near plane the group's
                s_k = share[i]
                h0, h1 = hydro[i, 0], hydro[i, 1]
                h2 = hydro[i, 2] if dim == 3 else 0.0
            else:
                s_k, _, _, _, h0, h1, h2 = wall_point(x0, x1, x2, own_normals, own_offsets, kernel_id, h,
                                                      gravity[0], gravity[1], gravity[2])
            A0 = h0 + s_k * gravity[0] + m0
            A1 = h1 + s_k * gravity[1] + m1
            A2 = h2 + s_k * gravity[2] + m2
            if own_normals.shape[0] == 1 and normals.shape[0] > 1:  # a plane of its own: the normal part
                nn = A0 * own_normals[0, 0] + A1 * own_normals[0, 1]
                if dim == 3:
                    nn += A2 * own_normals[0, 2]
                A0 = nn * own_normals[0, 0]
                A1 = nn * own_normals[0, 1]
                A2 = nn * own_normals[0, 2] if dim == 3 else 0.0
            _add_load(load, b, dim, x0, x1, x2, origin, coef_p[i], coef_h[i], k0, k1, k2, A0, A1, A2)


@njit(cache=True)
def group_parts(idx, count, pos, normals, offsets, member, support, grad, out):
    """out[t] <- G_k, the part of particle idx[t]'s wall gradient ``grad`` that belongs to
    the planes with member[a] (:func:`_group_part`, as :func:`plane_group_terms` takes it),
    for the particles idx[:count]: what a solved pressure's walls kick (the load of a scheme
    that solves for its pressure, ``ctx.solved_impulse``) splits into by group."""
    dim = pos.shape[1]
    for t in range(count):
        i = idx[t]
        x2 = pos[i, 2] if dim == 3 else 0.0
        G2 = grad[i, 2] if dim == 3 else 0.0
        k0, k1, k2 = _group_part(pos[i, 0], pos[i, 1], x2, dim, normals, offsets, member, support, grad[i, 0],
                                 grad[i, 1], G2)
        out[t, 0] = k0
        out[t, 1] = k1
        if dim == 3:
            out[t, 2] = k2


@njit(cache=True, parallel=True)
def moving_face_terms(pos, rot, centre, origin, vel, acc, omega, alpha, verts, flat, glo, ginv, gshape, gstart, gitems,
                      stamps, epoch, kernel_id, h, gravity, world_gravity, full, coef_p, coef_h, share, grad, hydro,
                      fill, q, flux, accel, load):
    """Add a moving group's faces (reference ``verts`` and their grid) to the terms of every
    particle within 2h of them: s, R G, R T g (T computed with R^T g, ``gravity`` given in
    the group's frame), fill, the projector (its directions turned back with R), flux and
    accel (module docstring); load (stamps.shape[0], 6) += each block's force and moment
    (:func:`plane_group_terms`; ``world_gravity`` g as a 3-vector).
    ``rot`` R (dim, dim), ``centre`` c (dim,), ``origin`` c + D (3,). ``stamps`` marks as in
    :func:`.facewalls.face_wall_terms`, two marks per particle: ``epoch`` and epoch + 1 must
    differ from every earlier call's."""
    n, dim = pos.shape
    rows = stamps.shape[0]
    first = epoch * (n + 1)
    second = (epoch + 1) * (n + 1)
    for b in prange(rows):
        qb = np.zeros((dim, dim))
        gb = np.zeros(3)
        X = np.zeros(3)
        for i in range(b * n // rows, (b + 1) * n // rows):
            x0, x1 = pos[i, 0], pos[i, 1]
            x2 = pos[i, 2] if dim == 3 else 0.0
            # X = c + R^T (x - c - D), the particle in the group's frame
            _to_body(X, x0, x1, x2, dim, rot, centre, origin)
            for a in range(dim):  # the projector already there, in the group's frame: R^T q R
                for e in range(dim):
                    acc_ = 0.0
                    for u in range(dim):
                        for w in range(dim):
                            acc_ += rot[u, a] * q[i, u, w] * rot[w, e]
                    qb[a, e] = acc_
            near, s, gr0, gr1, gr2, t0, t1, t2, basis, count = point_terms(
                X[0], X[1], X[2], dim, verts, flat, glo, ginv, gshape, gstart, gitems, stamps, np.int64(b), first + i,
                kernel_id, h, gravity, qb)
            if near == 0:
                continue
            G0, G1, G2 = _turn(rot, dim, gr0, gr1, gr2)
            T0, T1, T2 = _turn(rot, dim, t0, t1, t2)
            add_terms(i, dim, s, G0, G1, G2, T0, T1, T2, full, share, grad, hydro, fill)
            set_projector(q[i], dim, _turn_basis(rot, dim, basis, count), count)
            v0, v1, v2, a0, a1, a2 = _rigid(x0, x1, x2, dim, origin, vel, acc, omega, alpha)
            flux[i] += v0 * G0 + v1 * G1 + v2 * G2
            # T (-a_w): the same faces' moment with -a_w (in the group's frame) for gravity
            gb[0], gb[1], gb[2] = _turn_back(rot, dim, -a0, -a1, -a2)
            _, sa, _, _, _, m0, m1, m2, _, _ = point_terms(
                X[0], X[1], X[2], dim, verts, flat, glo, ginv, gshape, gstart, gitems, stamps, np.int64(b), second + i,
                kernel_id, h, gb, qb)
            M0, M1, M2 = _turn(rot, dim, m0, m1, m2)
            M0 -= sa * a0
            M1 -= sa * a1
            M2 = M2 - sa * a2 if dim == 3 else 0.0
            accel[i, 0] += M0
            accel[i, 1] += M1
            if dim == 3:
                accel[i, 2] += M2
            _add_load(load, b, dim, x0, x1, x2, origin, coef_p[i], coef_h[i], G0, G1, G2,
                      T0 + s * world_gravity[0] + M0, T1 + s * world_gravity[1] + M1,
                      T2 + s * world_gravity[2] + M2)


@njit(cache=True, inline="always")
def _to_body(X, x0, x1, x2, dim, rot, centre, origin):
    """X (3,) <- c + R^T (x - origin) (third entry 0 in 2D)."""
    d0 = x0 - origin[0]
    d1 = x1 - origin[1]
    d2 = x2 - origin[2] if dim == 3 else 0.0
    for a in range(dim):
        X[a] = centre[a] + rot[0, a] * d0 + rot[1, a] * d1 + (rot[2, a] * d2 if dim == 3 else 0.0)


@njit(cache=True, inline="always")
def _turn(rot, dim, v0, v1, v2):
    """R v for a vector of the group's frame."""
    if dim == 2:
        return rot[0, 0] * v0 + rot[0, 1] * v1, rot[1, 0] * v0 + rot[1, 1] * v1, 0.0
    return (rot[0, 0] * v0 + rot[0, 1] * v1 + rot[0, 2] * v2,
            rot[1, 0] * v0 + rot[1, 1] * v1 + rot[1, 2] * v2,
            rot[2, 0] * v0 + rot[2, 1] * v1 + rot[2, 2] * v2)


@njit(cache=True, inline="always")
def _turn_back(rot, dim, v0, v1, v2):
    """R^T v: a world vector in the group's frame."""
    if dim == 2:
        return rot[0, 0] * v0 + rot[1, 0] * v1, rot[0, 1] * v0 + rot[1, 1] * v1, 0.0
    return (rot[0, 0] * v0 + rot[1, 0] * v1 + rot[2, 0] * v2,
            rot[0, 1] * v0 + rot[1, 1] * v1 + rot[2, 1] * v2,
            rot[0, 2] * v0 + rot[1, 2] * v1 + rot[2, 2] * v2)


@njit(cache=True, inline="always")
def _turn_basis(rot, dim, basis, count):
    """The basis rows (a 9-tuple) turned with R."""
    a0, a1, a2 = _turn(rot, dim, basis[0], basis[1], basis[2])
    b0, b1, b2 = _turn(rot, dim, basis[3], basis[4], basis[5])
    c0, c1, c2 = _turn(rot, dim, basis[6], basis[7], basis[8])
    return (a0, a1, a2, b0, b1, b2, c0, c1, c2)


def pose_arrays(pose, dim):
    """The pose as the kernels take it: (rot (dim, dim), centre (dim,), origin (3,), vel (3,),
    acc (3,), omega (3,), alpha (3,))."""
    def three(v):
        out = np.zeros(3)
        out[:dim] = v
        return out

    return (np.ascontiguousarray(pose.rotation, dtype=np.float64), np.ascontiguousarray(pose.centre, dtype=np.float64),
            three(pose.centre + pose.shift), three(pose.velocity), three(pose.acceleration),
            np.asarray(pose.omega, np.float64), np.asarray(pose.alpha, np.float64))


def load_of(load, dim):
    """(force (dim,), moment (3,): about z in 2D) from the blocks' partial sums."""
    total = load.sum(axis=0)
    return total[:dim], total[3:]


def empty_load():
    return np.zeros((LOAD_ROWS, 6))



@njit(cache=True)
def within(pos, centre, radius, out):
    """The particles within ``radius`` of ``centre`` (a bounding sphere of a group's faces
    grown by the support): their indices in ``out``, in order; the count."""
    r2 = radius * radius
    count = 0
    for i in range(pos.shape[0]):
        d2 = 0.0
        for d in range(pos.shape[1]):
            x = pos[i, d] - centre[d]
            d2 += x * x
        if d2 <= r2:
            out[count] = i
            count += 1
    return count
