"""The wall completion of a particle's SPH sums: what boundary-integral walls add to the
rates once the pair loop (:func:`sphcore.physics.equations.sph_rates`) has summed the particle's
neighbours. The terms and their derivation are in :func:`complete_at_wall`; the plugin
computes the wall integrals it uses (:class:`sphcore.physics.equations.WallTerms`) in
``sph_wall_terms`` and hands the core this function in ``sph_wall_completion``, which the
core compiles into its pair loop.
"""

from __future__ import annotations

from numba import njit


@njit(cache=True, inline="always")
def complete_at_wall(wall, i, dim, vel, rho_i, p_i, rho_ref, lam, gravity, a0, a1, a2, dr, b0, b1, b2, gam):
    """:func:`complete` for walls that do not move (the terms of moving walls compiled out)."""
    return complete(wall, i, dim, vel, rho_i, p_i, rho_ref, lam, gravity, a0, a1, a2, dr, b0, b1, b2, gam, False)


@njit(cache=True, inline="always")
def complete_at_moving_wall(wall, i, dim, vel, rho_i, p_i, rho_ref, lam, gravity, a0, a1, a2, dr, b0, b1, b2, gam):
    """:func:`complete` with the terms of walls that move (``wall.flux``, ``wall.accel``)."""
    return complete(wall, i, dim, vel, rho_i, p_i, rho_ref, lam, gravity, a0, a1, a2, dr, b0, b1, b2, gam, True)


@njit(cache=True, inline="always")
def complete(wall, i, dim, vel, rho_i, p_i, rho_ref, lam, gravity, a0, a1, a2, dr, b0, b1, b2, gam, moving):
    """Add the wall's boundary integrals to particle i's sums (module docstring).

    The wall stands for the missing part of the support, filled with the mirror image of
    the fluid (velocity mirrored, pressure extrapolated hydrostatically): continuity gains
    2 rho_i v_i . G_w, momentum 2 (p_i/rho_i) G_w + ((rho_i - rho_ref)/rho_i) A_w g, with
    A_w g = T g + s g the first moment of the outside region. The same G_w in both terms
    makes the wall do no net work (the power of the wall force equals minus the rate of
    the Tait internal energy it stores), like mirror ghosts, with no ghost particle.

    G_w is ``wall.grad`` as the plugins supply it: a function of the particle's position
    alone, so that the wall pushes harder the closer a particle comes (the wall's
    stiffness). The ``wall_integral`` plugin gives the exact G minus the lattice error of
    the truncated sum on the initial lattice (:mod:`sphcore_plugins.wall_integral.lattice`),
    which makes a uniform pressure exert no force on that lattice, corners included.
    (The discrete complement -Q D of the particle's own sum, used before, balances any
    arrangement but does not depend on the wall distance at all: particles then rested on
    the reflective contact, not on the wall pressure.)

    The whole completion is scaled by phi = min(1, gam / wall.fill), the particle's own
    neighbour sum against the initial lattice's at that place: the mirror image of a full
    neighbourhood is the lattice the wall terms stand for, the mirror image of a splash
    particle or of a thin film is (nearly) nothing. Without it a lone particle near a wall
    would be pushed and decompressed as if the fluid surrounded it (measured: a splash
    particle of the Lobovsky impact fell below 0.5 rho0). phi = 1 on the initial lattice.

    Walls that move (``moving``, a constant of each compiled completion): continuity takes the velocity relative to
    the walls, 2 rho_i (v_i - v_w) . G_w = 2 rho_i (v_i . G_w - phi sum_k v_wk . G_k), and
    the hydrostatic extrapolation the walls' acceleration: in a wall's frame the mirror
    fluid's pressure grows along g - a_w (Adami et al. 2012, Eq. 27, for the same
    extrapolation with dummy particles), so the first moment gains lambda A_w (-a_w) =
    lambda (T (-a_w) + s (-a_w)) (``wall.accel``), scaled by phi along the walls' normals
    as the discrete complement of gravity is. The walls have no viscous term (free slip),
    so their velocity enters nothing else.
    """
    ref = wall.fill[i]
    phi = min(1.0, gam / ref) if ref > 0.0 else 1.0
    w0 = phi * wall.grad[i, 0]
    w1 = phi * wall.grad[i, 1]
    w2 = phi * wall.grad[i, 2] if dim == 3 else 0.0
    q = wall.normals
    # first moment: along the wall normals the discrete complement (lam I - B) g of the
    # particle's own sum b = B g, so that the hydrostatic pressure of the particles is in
    # balance there whatever their arrangement; along the walls (a side wall's vertical,
    # where the particle's missing support may be free surface) lam times the exact
    # A_w g = T g + s g. lam (Params.moment_norm) is what the interior's discrete sum gives
    # on the initial lattice (B = lam I): a particle next to a wall is then held up as an
    # interior one is (lam rho g), and no column along a wall slides against its neighbours
    s = wall.share[i]
    en0, en1, en2 = _project(q, i, dim, lam * gravity[0] - b0, lam * gravity[1] - b1, lam * gravity[2] - b2)
    t0 = lam * (wall.hydro[i, 0] + s * gravity[0])
    t1 = lam * (wall.hydro[i, 1] + s * gravity[1])
    t2 = lam * (wall.hydro[i, 2] + s * gravity[2]) if dim == 3 else 0.0
    tn0, tn1, tn2 = _project(q, i, dim, t0, t1, t2)
    h0 = phi * en0 + t0 - tn0
    h1 = phi * en1 + t1 - tn1
    h2 = phi * en2 + t2 - tn2
    if moving:  # the walls' acceleration: in their frame the mirror's pressure follows g - a_w
        m0 = lam * wall.accel[i, 0]
        m1 = lam * wall.accel[i, 1]
        m2 = lam * wall.accel[i, 2] if dim == 3 else 0.0
        mn0, mn1, mn2 = _project(q, i, dim, m0, m1, m2)
        h0 += phi * mn0 + m0 - mn0
        h1 += phi * mn1 + m1 - mn1
        h2 += phi * mn2 + m2 - mn2
    cp = 2.0 * p_i / rho_i
    ch = (rho_i - rho_ref) / rho_i
    a0 -= cp * w0 + ch * h0
    a1 -= cp * w1 + ch * h1
    a2 -= cp * w2 + ch * h2
    vw = vel[i, 0] * w0 + vel[i, 1] * w1
    if dim == 3:
        vw += vel[i, 2] * w2
    if moving:  # the velocity relative to the walls: (v_i - v_w) . G_w, group by group
        vw -= phi * wall.flux[i]
    dr += 2.0 * rho_i * vw
    return a0, a1, a2, dr


@njit(cache=True, inline="always")
def _project(q, i, dim, v0, v1, v2):
    """q[i] applied to (v0, v1, v2)."""
    if dim == 2:
        return q[i, 0, 0] * v0 + q[i, 0, 1] * v1, q[i, 1, 0] * v0 + q[i, 1, 1] * v1, 0.0
    return (q[i, 0, 0] * v0 + q[i, 0, 1] * v1 + q[i, 0, 2] * v2,
            q[i, 1, 0] * v0 + q[i, 1, 1] * v1 + q[i, 1, 2] * v2,
            q[i, 2, 0] * v0 + q[i, 2, 1] * v1 + q[i, 2, 2] * v2)
