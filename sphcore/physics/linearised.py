"""The rates of a state, linearised: what the scheme does with a small disturbance of it.

    from sphcore.physics.linearised import rate_jacobian, modes, mode_like, column_at_rest, state_rates

For n particles in dim dimensions the state is y = (x, v, rho) and the rates are
dx/dt = v, dv/dt = a(x, v, rho), drho/dt = D(x, v, rho): the pair sums of
:mod:`sphcore.physics.equations` with the walls' terms (``sph_wall_terms``), the plugins' sources
(``sph_extra_sources``, ghosts) and accelerations, the pressure from the equation of state.
:func:`rate_jacobian` builds J = d(rates)/dy by central differences, two force evaluations
per degree of freedom (n (2 dim + 1) of them: 400 particles in 2D take about two seconds).
The boundary's after-step correction (the reflective contact) is not a rate and is not in J.
The artificial viscosity acts on approaching pairs only, so at rest the rates are not
differentiable in the velocities: J holds the mean of the two sides (half the viscosity of
an approaching pair), and the damping read from it is that mean's. The wall model's fill
min(1, Gamma_i / Gamma_lattice) (:mod:`sphcore_plugins.wall_integral.completion`) has such a kink at the
initial lattice: there J holds the mean of the two sides as well.

About a state at rest the eigenvalues lambda of J say how a disturbance evolves,
exp(lambda t): a pair Re lambda +- i omega with Re lambda <= 0 is a wave (acoustic, or a
gravity wave at a free surface) damped by the viscosity; Re lambda > 0 is an instability,
which grows from any disturbance, round-off included. A lattice that sits exactly on an
unstable equilibrium stays there only while nothing breaks its symmetry, which is why
stability is read here rather than from a run. Known answers a scheme must give (used by
``validation/hydrostatic_tank/rest_stability.py`` and ``tests/test_rest_linearised.py``): a column of
depth H over a rigid floor rings at omega = pi c0 / (2 H) (quarter wave, p = 0 at the free
surface); the first sloshing mode of a tank of width L has omega^2 = g k tanh(k H), k = pi / L
(linear water waves, e.g. Lamb, Hydrodynamics, art. 227).
"""

from __future__ import annotations

import math

import numpy as np


def blocks(n: int, dim: int) -> dict:
    """Slices of the state vector y = (x, v, rho): positions, velocities, densities."""
    nd = n * dim
    return {"x": slice(0, nd), "v": slice(nd, 2 * nd), "rho": slice(2 * nd, 2 * nd + n)}


def state_vector(sim) -> np.ndarray:
    """y = (x, v, rho) of ``sim``'s particles, flattened (see :func:`blocks`)."""
    st = sim.state
    return np.concatenate([st.pos.ravel(), st.vel.ravel(), st.rho])


def state_rates(sim, y: np.ndarray) -> np.ndarray:
    """dy/dt at the state ``y``: ``sim``'s particles are set to it (and left there), the
    pressure follows from the equation of state, the forces are evaluated."""
    st, dim = sim.state, sim.params.dim
    n = st.n
    b = blocks(n, dim)
    st.pos[:] = y[b["x"]].reshape(n, dim)
    st.vel[:] = y[b["v"]].reshape(n, dim)
    st.rho[:] = y[b["rho"]]
    sim.update_pressure()
    acc, drho = np.zeros((n, dim)), np.zeros(n)
    sim.forces.evaluate(acc, drho)
    return np.concatenate([y[b["v"]], acc.ravel(), drho])


def rate_jacobian(sim, rel_step: float = 1e-6) -> np.ndarray:
    """J = d(rates)/d(x, v, rho) of ``sim``'s current state, by central differences (steps:
    ``rel_step`` times dx for positions, times c0 for velocities, times rho0 for densities).
    The state is left as it was."""
    prm = sim.params
    b = blocks(sim.state.n, prm.dim)
    y0 = state_vector(sim)
    m = y0.size
    step = np.empty(m)
    step[b["x"]] = rel_step * sim.case.dx
    step[b["v"]] = rel_step * (prm.c0 or 1.0)
    step[b["rho"]] = rel_step * prm.rho0
    jac = np.zeros((m, m))
    try:
        y = y0.copy()
        for k in range(m):
            y[k] = y0[k] + step[k]
            up = state_rates(sim, y)
            y[k] = y0[k] - step[k]
            down = state_rates(sim, y)
            y[k] = y0[k]
            jac[:, k] = (up - down) / (2.0 * step[k])
    finally:
        state_rates(sim, y0)
    return jac


def modes(jac: np.ndarray):
    """Eigenvalues and eigenvectors (columns) of ``jac``, the fastest-growing first."""
    values, vectors = np.linalg.eig(jac)
    order = np.argsort(-values.real, kind="stable")
    return values[order], vectors[:, order]


def mode_like(values, vectors, shape: np.ndarray, part: slice) -> tuple[complex, float]:
    """The oscillating mode (Im lambda > 0) whose eigenvector, restricted to ``part`` of the
    state (a slice from :func:`blocks`), is most nearly parallel to ``shape``; returns its
    eigenvalue and the cosine of the angle between the two (1: the same shape; -1 when no
    mode oscillates)."""
    s = shape / np.linalg.norm(shape)
    sub = vectors[part, :]
    norms = np.linalg.norm(sub, axis=0)
    cos = np.abs(s @ sub) / np.where(norms > 0, norms, np.inf)
    cos[values.imag <= 0] = -1.0
    k = int(np.argmax(cos))
    return complex(values[k]), float(cos[k])


def column_at_rest(sim) -> dict:
    """The known answers of the module docstring for a rectangular block of water at rest
    that fills a tank's width along x (``sim`` at its start; 2D or 3D, depth along the case's
    up axis): the largest growth rate (1/s) and where that mode moves most (column along x,
    row along the up axis, of the initial lattice from the lower corner), the quarter wave's
    omega against pi c0 / (2 H) with the cosine of its fit and the depth excess
    pi c0 / (2 omega) - H in dx (how far below the floor the scheme's wall acts), the first
    sloshing mode along x, its omega and damping against sqrt(g k tanh(k H)) with its fit."""
    st, prm, dx = sim.state, sim.params, sim.case.dx
    n, dim = st.n, prm.dim
    up = int(np.argmax(np.abs(prm.up[:dim])))
    if up == 0:
        raise ValueError("column_at_rest needs x horizontal (the sloshing runs along x); this case's up axis is x")
    values, vectors = modes(rate_jacobian(sim))
    b = blocks(n, dim)
    x0 = st.pos[:, 0] - (st.pos[:, 0].min() - dx / 2)
    z0 = st.pos[:, up] - (st.pos[:, up].min() - dx / 2)
    width, depth = float(x0.max() + dx / 2), float(z0.max() + dx / 2)
    amp = np.linalg.norm(np.abs(vectors[b["x"], 0]).reshape(n, dim), axis=1)
    worst = int(np.argmax(amp))
    acoustic, fit_a = mode_like(values, vectors, np.cos(np.pi * z0 / (2 * depth)), b["rho"])
    k = np.pi / width  # the first sloshing mode: velocity potential cos(k x) cosh(k z)
    wave = np.zeros((n, dim))
    wave[:, 0] = -np.sin(k * x0) * np.cosh(k * z0)
    wave[:, up] = np.cos(k * x0) * np.sinh(k * z0)
    slosh, fit_s = mode_like(values, vectors, wave.ravel(), b["v"])
    return {"growth": float(values[0].real), "where": (int(x0[worst] / dx), int(z0[worst] / dx)),
            "acoustic": acoustic.imag, "acoustic_theory": math.pi * prm.c0 / (2 * depth), "acoustic_fit": fit_a,
            "wall_offset_dx": (math.pi * prm.c0 / (2 * acoustic.imag) - depth) / dx,
            "slosh": slosh.imag, "slosh_damping": -slosh.real, "slosh_fit": fit_s,
            "slosh_theory": math.sqrt(prm.g_abs * k * math.tanh(k * depth))}
