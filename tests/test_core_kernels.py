"""Smoothing kernels: normalisation, positivity, compact support 2h, F = (1/r) dW/dr, and the
antisymmetry of grad W that makes pairwise forces conserve momentum.

The njit functions ``kernel_w(kernel_id, r, h, dim)`` and ``kernel_f(...)`` are called
directly, for both kernels in 2D and 3D.
"""

from __future__ import annotations

import math

import numpy as np
import pytest
from hypothesis import assume, given, settings
from hypothesis import strategies as st
from numba import njit

from sphcore.physics.kernels import CUBIC_SPLINE, KERNEL_IDS, SUPPORT, WENDLAND_C2, kernel_f, kernel_w

KERNELS = [pytest.param(CUBIC_SPLINE, id="cubic_spline"), pytest.param(WENDLAND_C2, id="wendland_c2")]
DIMS = [2, 3]

radii_q = st.floats(min_value=0.0, max_value=3.0, allow_nan=False)  # r / h
lengths = st.floats(min_value=1e-3, max_value=1e2, allow_nan=False)  # h (m)


def test_kernel_ids_cover_both_kernels():
    assert KERNEL_IDS == {"cubic_spline": CUBIC_SPLINE, "wendland_c2": WENDLAND_C2}
    assert SUPPORT == 2.0


@pytest.mark.parametrize("dim", DIMS)
@pytest.mark.parametrize("kid", KERNELS)
def test_radial_integral_is_one(kid, dim):
    """int W dV = 1: Gauss-Legendre on [0, h] and [h, 2h], exact for these piecewise polynomials."""
    x, w = np.polynomial.legendre.leggauss(20)
    for h in (0.013, 1.0, 7.5):
        total = 0.0
        for a, b in ((0.0, h), (h, 2.0 * h)):
            r = 0.5 * (b - a) * x + 0.5 * (a + b)
            shell = 2.0 * math.pi * r if dim == 2 else 4.0 * math.pi * r * r
            total += 0.5 * (b - a) * sum(wk * kernel_w(kid, rk, h, dim) * sk for wk, rk, sk in zip(w, r, shell))
        assert total == pytest.approx(1.0, abs=1e-12)


@njit(cache=False)
def _lattice_sum(kid, h, dim, spacing, offset):
    """sum_k W(|x_k - offset|, h) spacing^dim over the lattice x_k = k * spacing (k integer)."""
    m = int(2.0 * h / spacing) + 2
    total = 0.0
    kz = m if dim == 3 else 0
    for i in range(-m, m + 1):
        for j in range(-m, m + 1):
            for k in range(-kz, kz + 1):
                dx = i * spacing - offset[0]
                dy = j * spacing - offset[1]
                dz = k * spacing - offset[2] if dim == 3 else 0.0
                total += kernel_w(kid, math.sqrt(dx * dx + dy * dy + dz * dz), h, dim)
    return total * spacing**dim


@settings(max_examples=20, deadline=None)
@given(kid=st.sampled_from([CUBIC_SPLINE, WENDLAND_C2]), dim=st.sampled_from(DIMS),
       frac=st.tuples(*[st.floats(0.0, 1.0)] * 3), h=st.sampled_from([0.01, 1.0, 3.0]))
def test_lattice_sum_is_one(kid, dim, frac, h):
    """The discrete normalisation SPH actually uses: sum W dx^dim on a lattice with dx = h/8,
    shifted by an arbitrary fraction of a cell, is 1 to 1e-5 (measured: ~1e-6)."""
    spacing = h / 8.0
    offset = np.array(frac) * spacing
    assert _lattice_sum(kid, h, dim, spacing, offset) == pytest.approx(1.0, abs=1e-5)


@settings(max_examples=200, deadline=None)
@given(kid=st.sampled_from([CUBIC_SPLINE, WENDLAND_C2]), dim=st.sampled_from(DIMS), q=radii_q, h=lengths)
def test_positive_with_compact_support(kid, dim, q, h):
    r = q * h
    w = kernel_w(kid, r, h, dim)
    f = kernel_f(kid, r, h, dim)
    assert math.isfinite(w) and math.isfinite(f)
    assert w >= 0.0
    assert f <= 0.0  # W never increases with r
    if r >= SUPPORT * h:
        assert w == 0.0 and f == 0.0
    elif q < 1.999:
        assert w > 0.0


@pytest.mark.parametrize("dim", DIMS)
@pytest.mark.parametrize("kid", KERNELS)
def test_continuous_at_the_support_edge_and_scales_with_h(kid, dim):
    h = 0.37
    # W and F vanish continuously at r = 2h (no jump in force as a neighbour leaves)
    assert kernel_w(kid, SUPPORT * h * (1 - 1e-9), h, dim) < 1e-20
    assert abs(kernel_f(kid, SUPPORT * h * (1 - 1e-9), h, dim)) < 1e-12
    # cubic spline joint at q = 1: W continuous
    assert kernel_w(kid, h * (1 - 1e-12), h, dim) == pytest.approx(kernel_w(kid, h, h, dim), rel=1e-10)
    # W(r, h) = W(r/h, 1) / h^dim and F(r, h) = F(r/h, 1) / h^(dim+2)
    for q in (0.0, 0.3, 1.0, 1.7):
        assert kernel_w(kid, q * h, h, dim) == pytest.approx(kernel_w(kid, q, 1.0, dim) / h**dim, rel=1e-13)
        assert kernel_f(kid, q * h, h, dim) == pytest.approx(kernel_f(kid, q, 1.0, dim) / h ** (dim + 2), rel=1e-13)


@settings(max_examples=300, deadline=None)
@given(kid=st.sampled_from([CUBIC_SPLINE, WENDLAND_C2]), dim=st.sampled_from(DIMS),
       q=st.floats(min_value=1e-2, max_value=2.5), h=lengths)
def test_f_is_derivative_over_r(kid, dim, q, h):
    """F(r) = (1/r) dW/dr against a central difference of W (step 1e-5 h)."""
    assume(abs(q - 1.0) > 1e-3 and abs(q - 2.0) > 1e-3)  # keep the stencil off the joints
    r, e = q * h, 1e-5 * h
    fd = (kernel_w(kid, r + e, h, dim) - kernel_w(kid, r - e, h, dim)) / (2.0 * e) / r
    scale = abs(kernel_f(kid, 0.0, h, dim))  # |F| is largest at r = 0
    assert kernel_f(kid, r, h, dim) == pytest.approx(fd, rel=1e-6, abs=1e-8 * scale)


vec = st.floats(min_value=-1.0, max_value=1.0, allow_nan=False)


@settings(max_examples=200, deadline=None)
@given(kid=st.sampled_from([CUBIC_SPLINE, WENDLAND_C2]), dim=st.sampled_from(DIMS),
       xi=st.tuples(vec, vec, vec), xj=st.tuples(vec, vec, vec), h=st.floats(0.2, 2.0))
def test_gradient_antisymmetric_and_matches_finite_difference(kid, dim, xi, xj, h):
    """grad_i W_ij = F x_ij = -grad_j W_ji exactly; and it is the gradient of W(|x_i - x_j|)."""
    xi, xj = np.array(xi[:dim]), np.array(xj[:dim])
    xij = xi - xj
    r = float(np.linalg.norm(xij))
    grad_i = kernel_f(kid, r, h, dim) * xij
    grad_j = kernel_f(kid, float(np.linalg.norm(xj - xi)), h, dim) * (xj - xi)
    assert np.array_equal(grad_i, -grad_j)
    assume(r > 1e-3 * h and abs(r / h - 1.0) > 1e-3 and abs(r / h - 2.0) > 1e-3)
    e = 1e-6 * h
    fd = np.empty(dim)
    for d in range(dim):
        step = np.zeros(dim)
        step[d] = e
        fd[d] = (kernel_w(kid, float(np.linalg.norm(xij + step)), h, dim)
                 - kernel_w(kid, float(np.linalg.norm(xij - step)), h, dim)) / (2.0 * e)
    scale = abs(kernel_f(kid, 0.0, h, dim)) * h
    np.testing.assert_allclose(grad_i, fd, rtol=1e-5, atol=1e-7 * scale)
