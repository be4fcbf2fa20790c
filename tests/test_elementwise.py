"""The per-step element-wise kernels (integrator updates, largest norms, the instability
scan) are compiled serial and parallel (sphcore.jit.parallel.by_size): both builds must give
the serial loop's answer exactly, whatever the thread count."""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sphcore.physics import checks, integrators, timestep

BUILDS = ("serial", "parallel")


def reference_scan(pos, vel, rho, rho_lo, rho_hi, check_rho, normals, offsets):
    """The scan written plainly in Python, one particle after the other."""
    worst_lo, i_lo, worst_hi, i_hi, worst_out, i_out = rho_lo, -1, rho_hi, -1, 0.0, -1
    for i in range(pos.shape[0]):
        s = rho[i] + sum(pos[i, d] + vel[i, d] for d in range(pos.shape[1]))
        if not np.isfinite(s):
            return checks.NONFINITE, i
        if check_rho and rho[i] < worst_lo:
            worst_lo, i_lo = rho[i], i
        if check_rho and rho[i] > worst_hi:
            worst_hi, i_hi = rho[i], i
        for k in range(normals.shape[0]):
            dist = checks.plane_distance(normals, offsets, k, pos[i, 0], pos[i, 1],
                                         pos[i, 2] if pos.shape[1] == 3 else 0.0)
            if dist < worst_out:
                worst_out, i_out = dist, i
    for code, i in ((checks.OUTSIDE, i_out), (checks.RHO_LOW, i_lo), (checks.RHO_HIGH, i_hi)):
        if i >= 0:
            return code, i
    return checks.OK, -1


@st.composite
def scanned_states(draw):
    dim = draw(st.sampled_from([2, 3]))
    n = draw(st.integers(1, 60))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    pos = rng.uniform(0.0, 1.0, (n, dim))
    vel = rng.normal(0.0, 1.0, (n, dim))
    # densities on a coarse set, so that equal extremes (ties) occur
    rho = rng.choice([960.0, 990.0, 1000.0, 1010.0, 1040.0], n)
    for _ in range(draw(st.integers(0, 3))):  # particles outside, some equally far
        pos[rng.integers(n), rng.integers(dim)] = draw(st.sampled_from([-0.1, -0.2, 1.2]))
    if draw(st.booleans()):
        field = draw(st.sampled_from(["pos", "vel", "rho"]))
        bad = draw(st.sampled_from([np.nan, np.inf, -np.inf]))
        {"pos": pos, "vel": vel, "rho": rho}[field].reshape(n, -1)[rng.integers(n), 0] = bad
    box = np.eye(dim)
    normals = np.ascontiguousarray(np.concatenate([box, -box]))
    offsets = np.concatenate([np.zeros(dim), -np.ones(dim)])
    return pos, vel, rho, 980.0, 1020.0, draw(st.booleans()), normals, offsets


@settings(max_examples=150, deadline=None)
@given(scanned_states())
def test_scan_finds_what_a_plain_loop_finds_in_both_builds(state):
    want = reference_scan(*state)
    for build in BUILDS:
        code, i, value = getattr(checks.scan, build)(*state)
        assert (code, i) == want
        if code in (checks.RHO_LOW, checks.RHO_HIGH):
            assert value == state[2][i]


@settings(max_examples=60, deadline=None)
@given(st.integers(1, 200), st.sampled_from([2, 3]), st.integers(0, 2**32 - 1))
def test_largest_norms_are_numpys_in_both_builds(n, dim, seed):
    rng = np.random.default_rng(seed)
    vel, acc = rng.normal(size=(n, dim)), rng.normal(size=(n, dim))
    want = (np.sqrt(np.max(np.einsum("ij,ij->i", vel, vel))), np.sqrt(np.max(np.einsum("ij,ij->i", acc, acc))))
    for build in BUILDS:
        got = getattr(timestep.max_norms, build)(vel, acc)
        assert got == pytest.approx(want, rel=1e-15)
    assert timestep.max_norms.serial(vel, acc) == timestep.max_norms.parallel(vel, acc)


def test_integrator_updates_give_the_same_bits_in_both_builds():
    rng = np.random.default_rng(7)
    pos, vel, acc, old = (rng.normal(size=(5000, 3)) for _ in range(4))
    rho, drho, drho_old = rng.uniform(990, 1010, 5000), rng.normal(size=5000), rng.normal(size=5000)
    out = {}
    for build in BUILDS:
        p, v, r, p0 = pos.copy(), vel.copy(), rho.copy(), np.empty_like(pos)
        getattr(integrators._drift_kick, build)(p0, p, v, acc, r, drho, 1e-3, 1.0, True)
        getattr(integrators._correct, build)(v, acc, old, r, drho, drho_old, 5e-4, True)
        out[build] = (p0, p, v, r)
    for a, b in zip(out["serial"], out["parallel"]):
        assert np.array_equal(a, b)
    p0, p, v, r = out["serial"]
    assert np.array_equal(p0, pos)
    assert np.allclose(p, pos + 1e-3 * (vel + 0.5e-3 * acc), rtol=0, atol=1e-15)
    assert np.allclose(v, vel + 1e-3 * acc + 5e-4 * (acc - old), rtol=0, atol=1e-15)
    assert np.allclose(r, rho + 1e-3 * drho + 5e-4 * (drho - drho_old), rtol=1e-15, atol=0)
    # without density evolution rho is left alone
    r = rho.copy()
    integrators._drift_kick.serial(np.empty_like(pos), pos.copy(), vel.copy(), acc, r, drho, 1e-3, 1.0, False)
    assert np.array_equal(r, rho)


@settings(max_examples=80, deadline=None)
@given(st.integers(0, 80), st.sampled_from([2, 3]), st.integers(0, 2**32 - 1), st.integers(-1, 80))
def test_the_cell_grids_bounding_box_is_numpys_in_both_builds(n, dim, seed, nan_at):
    """Lower and upper corners of the particles in both builds of the grid's box (16 ranges
    merged); a NaN coordinate makes the lower corner NaN on that axis."""
    from sphcore.neighbours import cellkeys

    pos = np.random.default_rng(seed).normal(size=(n, dim))
    if 0 <= nan_at < n:
        pos[nan_at, nan_at % dim] = np.nan
    for build in (cellkeys._box_serial, cellkeys._box_parallel):
        lo, hi = build(pos)
        for d in range(dim):
            column = pos[:, d]
            if np.isnan(column).any():
                assert np.isnan(lo[d])
            else:
                assert lo[d] == (column.min() if n else np.inf)
            finite = column[~np.isnan(column)]
            assert hi[d] == (finite.max() if finite.size else -np.inf)
        assert not lo[dim:].any() and not hi[dim:].any()


def test_the_equation_of_state_gives_the_same_bits_in_both_builds():
    from sphcore.physics import eos

    rho = np.random.default_rng(3).uniform(950.0, 1050.0, 30_000)
    p_serial, p_parallel = np.empty_like(rho), np.empty_like(rho)
    eos.fill_pressure.serial(rho, 1000.0, 30.0, 7.0, 0.0, p_serial)
    eos.fill_pressure.parallel(rho, 1000.0, 30.0, 7.0, 0.0, p_parallel)
    assert np.array_equal(p_serial, p_parallel)
    b = 30.0**2 * 1000.0 / 7.0
    assert np.allclose(p_serial, b * ((rho / 1000.0) ** 7 - 1.0), rtol=1e-12, atol=1e-9)
