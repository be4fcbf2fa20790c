"""The terms of one SPH pair, and the two ways the pair loop of :mod:`sphcore.physics.equations`
walks a particle's partners with them.

- **Fused** (2D): each partner j's fields are loaded, its pair's terms computed and added to
  both particles in one loop (:func:`fused_partners`).
- **Three passes** (3D): :func:`gather` copies what the pairs read of each partner into
  contiguous rows (``gat``), :func:`terms` computes every pair's terms from those rows alone
  into ``out`` (a loop with neither indirect loads nor scattered stores, which the compiler
  turns into SIMD instructions), and :func:`scatter` adds them to i and to each j in the
  partners' order.

Both compute each term with the same arithmetic (:func:`pair_terms`) and add them in the
same order: the same bits. Which pays depends on how many partners a particle has: each
pair is evaluated once, so a particle has ~10 partners in 2D at h = 1.3 dx and ~37 in 3D.
Measured on a frozen state, one thread, on a quiet 2-vCPU Xeon
(``benchmarks/tools/bench_pair_ab.py``: rounds alternating, fastest calls and median of
rounds): in 3D three passes take 0.77-0.84 of the fused walk's time (the 3D dam break at
t = 0.01 s, 16,384 particles); in 2D (PySPH's dam break) the two walks are within the
A/A spread (0.91-1.05): the copies cost what the vector instructions save, so 2D stays
fused.

Constants of the pair terms are passed as one tuple ``k`` (:func:`constants`).
"""

from __future__ import annotations

import numpy as np
from numba import njit

from sphcore.physics.corrections import corrected_gradient
from sphcore.physics.kernels import kernel_f_of_q, kernel_f_scale, kernel_w

# rows of the three-pass scratch ``gat``: what the pairs read of each partner j (x_ij and
# v_ij rather than x_j and v_j: each pair needs the differences)
# the pair loop's per-source scratch (``work``, n_sources x WORK_COLUMNS), filled before the pairs
W_GAMMA = 0  # near-wall sum of the kernel, sum_j V_j W_ij (the wall completion's gamma)
W_B = 1  # near-wall sums of V_j (x_ij . g) grad W_ij: columns 1-3
W_PR = 4  # p / rho^2
W_INV_RHO = 5  # 1 / rho
W_KH = 6  # density diffusion: k / 2
W_VOL = 7  # density diffusion: the volume m / rho
W_GP = 8  # density diffusion: g . x
WORK_COLUMNS = 9

G_X = 0  # x_ij: rows 0-2
G_V = 3  # v_ij: rows 3-5
G_RHO = 6  # rho_j
G_M = 7  # m_j
G_PR = 8  # p_j / rho_j^2
G_VOL = 9  # density diffusion: m_j / rho_j, k_j / 2, g . x_j
G_KH = 10
G_GP = 11
G_LID = 12  # 1 where L_j is the identity (a source beyond L), else 0
G_L = 13  # L_j row-major: rows 13-21
GATHER_ROWS = 22
# rows of ``out``: each pair's terms
O_AI = 0  # m_j e, subtracted from a_i: rows 0-2
O_AJ = 3  # m_i e, added to a_j: rows 3-5
O_DRI = 6  # the drho_i / dt and drho_j / dt terms
O_DRJ = 7
O_G = 8  # grad_i W_ij (corrected where asked): rows 8-10; r for the wall completion
O_R = 11
OUT_ROWS = 12


@njit(cache=True, inline="always")
def constants(prm, dim):
    """The pair terms' constants: (h, c0, alpha, beta, nu, eta2, 2 delta h c0, do_av,
    do_lam, do_diff, diff_h, any_visc, 1 / h, the kernel's F scale); a term whose
    coefficient is zero is skipped. Computed once per slab: the scale is a power of h,
    which once per particle cost 1.4x the whole pair loop (measured)."""
    do_av = prm.alpha > 0.0 or prm.beta > 0.0
    do_lam = prm.nu > 0.0
    do_diff = prm.delta > 0.0
    diff_h = do_diff and prm.diffusion_hydrostatic  # k_ij g . x_ij subtracted from psi_ij
    return (prm.h, prm.c0, prm.alpha, prm.beta, prm.nu, prm.eta2, 2.0 * prm.delta * prm.h * prm.c0, do_av, do_lam,
            do_diff, diff_h, do_av or do_lam or do_diff, 1.0 / prm.h, kernel_f_scale(prm.kernel_id, prm.h, dim))


@njit(cache=True, inline="always")
def pair_terms(k, x0, x1, x2, r2, g0, g1, g2, v0, v1, v2, m_i, m_j, rho_i, rho_j, pi_r, pr_j, vol_i, vol_j, kh_i,
               kh_j, gp_i, gp_j):
    """(e0, e1, e2, dr_i, dr_j) of the pair i, j (module docstring of
    :mod:`sphcore.physics.equations`): dv_i/dt gets -m_j e and dv_j/dt +m_i e (pressure, artificial
    and laminar viscosity), drho_i/dt dr_i and drho_j/dt dr_j (continuity and density
    diffusion). x = x_ij, r2 = |x|^2, g = grad_i W_ij, v = v_ij; pi_r, pr_j = p / rho^2;
    vol = m / rho, kh = k / 2 and gp = g . x of each (density diffusion only)."""
    h, c0, alpha, beta, nu, eta2, dcoef, do_av, do_lam, do_diff, diff_h, any_visc, inv_h, fscale = k
    vg = v0 * g0 + v1 * g1 + v2 * g2  # v_ij . grad_i W_ij = v_ji . grad_j W_ji
    dr_i = m_j * vg
    dr_j = m_i * vg
    s = pi_r + pr_j
    e0 = 0.0
    e1 = 0.0
    e2 = 0.0
    if any_visc:
        xg = x0 * g0 + x1 * g1 + x2 * g2  # x_ij . grad_i W_ij (< 0)
        ir2 = 1.0 / (r2 + eta2)
        if do_diff:
            psi = rho_i - rho_j  # psi_ji = -psi_ij
            if diff_h:
                psi -= (kh_i + kh_j) * (gp_i - gp_j)
            cd = dcoef * psi * xg * ir2
            dr_i += cd * vol_j
            dr_j -= cd * vol_i
        if do_av:
            # approaching pairs only (v_ij . x_ij < 0); min() rather than a branch, which
            # the CPU would mispredict for half the pairs of a flow
            mu = h * min(v0 * x0 + v1 * x1 + v2 * x2, 0.0) * ir2
            s += (-alpha * c0 * mu + beta * mu * mu) * 2.0 / (rho_i + rho_j)
        if do_lam:
            lam = 4.0 * nu / (rho_i + rho_j) * xg * ir2
            e0 = -lam * v0
            e1 = -lam * v1
            e2 = -lam * v2
    e0 += s * g0
    e1 += s * g1
    e2 += s * g2
    return e0, e1, e2, dr_i, dr_j


@njit(cache=True, inline="always")
def add_to_partner(j, dim, near_j, aj0, aj1, aj2, dr_j, w, gx, g0, g1, g2, vol_i, acc, drho, work):
    """Add one pair's terms to its partner j (a fluid particle): ``aj`` = m_i e to acc,
    dr_j to drho, and near a wall the completion's sums (work columns 0-3); w = W_ij, gx =
    (x_j - x_i) . g, g = grad_i W_ij, vol_i = m_i / rho_i. Particle i's own sums are locals of
    the loops (carried through a function as a tuple, they made the 2D pair loop 1.45x
    slower: measured)."""
    acc[j, 0] += aj0
    acc[j, 1] += aj1
    if dim == 3:
        acc[j, 2] += aj2
    drho[j] += dr_j
    if near_j:
        work[j, W_GAMMA] += vol_i * w
        work[j, W_B] += vol_i * gx * g0
        work[j, W_B + 1] += vol_i * gx * g1
        work[j, W_B + 2] += vol_i * gx * g2


@njit(cache=True, inline="always")
def finish_particle(i, dim, near_i, acc, drho, work, a0, a1, a2, dr, gam, b0, b1, b2):
    """Add particle i's sums over its pairs to its rows: a to acc, dr to drho, near a wall
    the completion's gam = sum_j V_j W_ij and b = sum_j V_j grad_i W_ij (x_j - x_i) . g."""
    acc[i, 0] += a0
    acc[i, 1] += a1
    if dim == 3:
        acc[i, 2] += a2
    drho[i] += dr
    if near_i:
        work[i, W_GAMMA] += gam
        work[i, W_B] += b0
        work[i, W_B + 1] += b1
        work[i, W_B + 2] += b2


@njit(cache=True, inline="always")
def fused_partners(i, npart, buf, n_dest, dim, walls, pos, vel, rho, m, kid, gv0, gv1, gv2, k, L, n_L, share, acc,
                   drho, work):
    """Particle i's pairs with its partners buf[:npart], one partner at a time. ``kid``: the
    kernel; gv: gravity; ``share``: the wall share of each particle (walls only). Arrays
    and scalars rather than the structured arguments of the pair loop: a field taken from
    those inside a function called per particle costs a reference count each time."""
    h = k[0]
    do_diff, diff_h, any_visc, inv_h, fscale = k[9], k[10], k[11], k[12], k[13]
    di = i < n_dest
    near_i = walls and di and share[i] > 0.0
    rho_i, m_i = rho[i], m[i]
    pi_r, vol_i, kh_i, gp_i = work[i, W_PR], work[i, W_VOL], work[i, W_KH], work[i, W_GP]
    vi = m_i * work[i, W_INV_RHO]
    # particle i's position and velocity in scalars, loaded once
    px0, px1 = pos[i, 0], pos[i, 1]
    px2 = pos[i, 2] if dim == 3 else 0.0
    vi0, vi1 = vel[i, 0], vel[i, 1]
    vi2 = vel[i, 2] if dim == 3 else 0.0
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    dr = 0.0
    gam = 0.0
    b0 = 0.0
    b1 = 0.0
    b2 = 0.0
    for u in range(npart):
        j = buf[u]
        dj = j < n_dest
        x0 = px0 - pos[j, 0]  # as sphcore.neighbours.cellgrid.separation
        x1 = px1 - pos[j, 1]
        x2 = px2 - pos[j, 2] if dim == 3 else 0.0
        r2 = x0 * x0 + x1 * x1 + x2 * x2
        r = np.sqrt(r2)
        f = fscale * kernel_f_of_q(kid, r * inv_h)
        g0 = f * x0  # grad_i W_ij = -grad_j W_ji
        g1 = f * x1
        g2 = f * x2
        if n_L > 0:
            g0, g1, g2 = corrected_gradient(L, n_L, i, j, g0, g1, g2)
        v0 = vi0 - vel[j, 0]
        v1 = vi1 - vel[j, 1]
        v2 = vi2 - vel[j, 2] if dim == 3 else 0.0
        m_j = m[j]
        rho_j = rho[j] if any_visc else 0.0
        vol_j = work[j, W_VOL] if do_diff else 0.0
        kh_j = work[j, W_KH] if diff_h else 0.0
        gp_j = work[j, W_GP] if diff_h else 0.0
        e0, e1, e2, dr_i, dr_j = pair_terms(k, x0, x1, x2, r2, g0, g1, g2, v0, v1, v2, m_i, m_j, rho_i, rho_j, pi_r,
                                            work[j, W_PR], vol_i, vol_j, kh_i, kh_j, gp_i, gp_j)
        near_j = walls and dj and share[j] > 0.0
        w = 0.0
        gx = 0.0
        if near_i or near_j:
            w = kernel_w(kid, r, h, dim)
            gx = -(x0 * gv0 + x1 * gv1 + x2 * gv2)
        if di:
            a0 -= m_j * e0
            a1 -= m_j * e1
            a2 -= m_j * e2
            dr += dr_i
            if near_i:
                vj = m_j * work[j, W_INV_RHO]
                gam += vj * w
                b0 += vj * gx * g0
                b1 += vj * gx * g1
                b2 += vj * gx * g2
        if dj:
            add_to_partner(j, dim, near_j, m_i * e0, m_i * e1, m_i * e2, dr_j, w, gx, g0, g1, g2, vi, acc, drho, work)
    if di:
        finish_particle(i, dim, near_i, acc, drho, work, a0, a1, a2, dr, gam, b0, b1, b2)


@njit(cache=True, inline="always")
def gather(i, npart, buf, dim, pos, vel, rho, m, work, k, L, n_L, gat):
    """Rows of ``gat`` (G_X...) for particle i's partners buf[:npart]."""
    do_diff, diff_h = k[9], k[10]
    px0, px1 = pos[i, 0], pos[i, 1]
    px2 = pos[i, 2] if dim == 3 else 0.0
    vi0, vi1 = vel[i, 0], vel[i, 1]
    vi2 = vel[i, 2] if dim == 3 else 0.0
    for u in range(npart):
        j = buf[u]
        gat[G_X, u] = px0 - pos[j, 0]  # as sphcore.neighbours.cellgrid.separation
        gat[G_X + 1, u] = px1 - pos[j, 1]
        gat[G_V, u] = vi0 - vel[j, 0]
        gat[G_V + 1, u] = vi1 - vel[j, 1]
        if dim == 3:
            gat[G_X + 2, u] = px2 - pos[j, 2]
            gat[G_V + 2, u] = vi2 - vel[j, 2]
        gat[G_RHO, u] = rho[j]
        gat[G_M, u] = m[j]
        gat[G_PR, u] = work[j, W_PR]
        if do_diff:
            gat[G_VOL, u] = work[j, W_VOL]
            if diff_h:
                gat[G_KH, u] = work[j, W_KH]
                gat[G_GP, u] = work[j, W_GP]
        if n_L > 0:
            if j < n_L:
                gat[G_LID, u] = 0.0
                for e in range(9):
                    gat[G_L + e, u] = L[j, e // 3, e % 3]
            else:
                gat[G_LID, u] = 1.0


@njit(cache=True, inline="always")
def terms(npart, dim, walls, kid, k, rho_i, m_i, pi_r, vol_i, kh_i, gp_i, use_L, Li, gat, out):
    """Rows of ``out`` (O_AI...) for particle i's partners, from ``gat`` alone. ``use_L``:
    apply the kernel gradient correction, with ``Li`` = L_i row-major (an empty array where
    i has none: a source beyond L); called with a constant, so that the loop without the
    correction has none of its loads (and is vectorised)."""
    do_diff, diff_h, any_visc, inv_h, fscale = k[9], k[10], k[11], k[12], k[13]
    for u in range(npart):
        x0 = gat[G_X, u]
        x1 = gat[G_X + 1, u]
        x2 = gat[G_X + 2, u] if dim == 3 else 0.0
        r2 = x0 * x0 + x1 * x1 + x2 * x2
        r = np.sqrt(r2)
        f = fscale * kernel_f_of_q(kid, r * inv_h)
        g0 = f * x0
        g1 = f * x1
        g2 = f * x2
        if use_L:  # (L_i + L_j) / 2 applied to g, as sphcore.physics.corrections.corrected_gradient
            a0, a1, a2 = g0, g1, g2
            if Li.shape[0] == 9:
                a0 = Li[0] * g0 + Li[1] * g1 + Li[2] * g2
                a1 = Li[3] * g0 + Li[4] * g1 + Li[5] * g2
                a2 = Li[6] * g0 + Li[7] * g1 + Li[8] * g2
            b0, b1, b2 = g0, g1, g2
            if gat[G_LID, u] == 0.0:
                b0 = gat[G_L, u] * g0 + gat[G_L + 1, u] * g1 + gat[G_L + 2, u] * g2
                b1 = gat[G_L + 3, u] * g0 + gat[G_L + 4, u] * g1 + gat[G_L + 5, u] * g2
                b2 = gat[G_L + 6, u] * g0 + gat[G_L + 7, u] * g1 + gat[G_L + 8, u] * g2
            g0, g1, g2 = 0.5 * (a0 + b0), 0.5 * (a1 + b1), 0.5 * (a2 + b2)
        v2 = gat[G_V + 2, u] if dim == 3 else 0.0
        m_j = gat[G_M, u]
        rho_j = gat[G_RHO, u] if any_visc else 0.0
        vol_j = gat[G_VOL, u] if do_diff else 0.0
        kh_j = gat[G_KH, u] if diff_h else 0.0
        gp_j = gat[G_GP, u] if diff_h else 0.0
        e0, e1, e2, dr_i, dr_j = pair_terms(k, x0, x1, x2, r2, g0, g1, g2, gat[G_V, u], gat[G_V + 1, u], v2, m_i, m_j,
                                            rho_i, rho_j, pi_r, gat[G_PR, u], vol_i, vol_j, kh_i, kh_j, gp_i, gp_j)
        out[O_AI, u] = m_j * e0
        out[O_AI + 1, u] = m_j * e1
        out[O_AJ, u] = m_i * e0
        out[O_AJ + 1, u] = m_i * e1
        if dim == 3:
            out[O_AI + 2, u] = m_j * e2
            out[O_AJ + 2, u] = m_i * e2
        out[O_DRI, u] = dr_i
        out[O_DRJ, u] = dr_j
        if walls:
            out[O_G, u] = g0
            out[O_G + 1, u] = g1
            out[O_G + 2, u] = g2
            out[O_R, u] = r


@njit(cache=True, inline="always")
def scatter(i, npart, buf, n_dest, dim, walls, kid, h, gv0, gv1, gv2, share, m_i, acc, drho, work, gat, out):
    """Add the terms ``out`` of particle i's pairs to i and to its partners buf[:npart], in
    the partners' order; arguments as :func:`fused_partners`'."""
    di = i < n_dest
    near_i = walls and di and share[i] > 0.0
    vi = m_i * work[i, W_INV_RHO]
    a0 = 0.0
    a1 = 0.0
    a2 = 0.0
    dr = 0.0
    gam = 0.0
    b0 = 0.0
    b1 = 0.0
    b2 = 0.0
    for u in range(npart):
        j = buf[u]
        dj = j < n_dest
        near_j = walls and dj and share[j] > 0.0
        w = 0.0
        gx = 0.0
        g0 = 0.0
        g1 = 0.0
        g2 = 0.0
        if near_i or near_j:
            w = kernel_w(kid, out[O_R, u], h, dim)
            x2 = gat[G_X + 2, u] if dim == 3 else 0.0
            gx = -(gat[G_X, u] * gv0 + gat[G_X + 1, u] * gv1 + x2 * gv2)
            g0 = out[O_G, u]
            g1 = out[O_G + 1, u]
            g2 = out[O_G + 2, u]
        if di:
            a0 -= out[O_AI, u]
            a1 -= out[O_AI + 1, u]
            if dim == 3:
                a2 -= out[O_AI + 2, u]
            dr += out[O_DRI, u]
            if near_i:
                vj = gat[G_M, u] * work[j, W_INV_RHO]
                gam += vj * w
                b0 += vj * gx * g0
                b1 += vj * gx * g1
                b2 += vj * gx * g2
        if dj:
            add_to_partner(j, dim, near_j, out[O_AJ, u], out[O_AJ + 1, u], out[O_AJ + 2, u] if dim == 3 else 0.0,
                           out[O_DRJ, u], w, gx, g0, g1, g2, vi, acc, drho, work)
    if di:
        finish_particle(i, dim, near_i, acc, drho, work, a0, a1, a2, dr, gam, b0, b1, b2)
