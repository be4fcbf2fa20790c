"""Probe sampling on fields with known answers, and the error figures on hand-computed series.

The numba functions take plain arrays: a lattice of particles stands in for the run.
"""

from __future__ import annotations

import math

import numpy as np
import pytest

from sphcore.physics.kernels import KERNEL_IDS
from sphcore.physics.particles import lattice
from sphcore_plugins.probes import figures
from sphcore_plugins.probes.sampling import depth_above, interpolate_pressure, line_points, select_near

G, RHO0, DX, H = 9.81, 1000.0, 0.01, 0.3
HS = 1.3 * DX  # smoothing length
GRAV = np.array([0.0, -G])
# the tank [0, 0.5] x [0, 1]: wall planes (normal into the fluid, offset = n.x on the plane)
NORMALS = np.array([[1.0, 0.0], [0.0, 1.0], [-1.0, 0.0], [0.0, -1.0]])
OFFSETS = np.array([0.0, 0.0, -0.5, -1.0])


def block(height=H, width=0.5):
    """A lattice block [0, width] x [0, height]: positions, densities, masses (V = dx^2 at rho0)."""
    pos = lattice(np.zeros(2), np.array([width, height]), DX)
    rho = np.full(len(pos), RHO0)
    return pos, rho, rho * DX * DX


def sample(points, pos, p, rho, m, wall, kernel="wendland_c2", face_n=(0.0, 0.0)):
    out_p, out_w = np.zeros(len(points)), np.zeros(len(points))
    interpolate_pressure(np.ascontiguousarray(points, float), pos, p, rho, m, KERNEL_IDS[kernel], HS, GRAV, wall,
                         np.asarray(face_n, float),
                         out_p, out_w)
    return out_p, out_w


# the right wall of the block (x = 0.5) at several heights, a floor point and a corner
WALL_POINTS = np.array([[0.5, 0.0], [0.5, 0.015], [0.5, 0.1], [0.5, 0.2], [0.5, 0.29], [0.25, 0.0], [0.0, 0.15]])


@pytest.mark.parametrize("kernel", ["wendland_c2", "cubic_spline"])
def test_wall_mode_of_a_hydrostatic_column_is_rho_g_depth(kernel):
    """Constant density: each particle's pressure carried hydrostatically to the sensor is
    rho g (H - y_s) exactly, so the Shepard average is too (to round-off), at the wall, at
    the floor, in a corner and next to the free surface."""
    pos, rho, m = block()
    p = RHO0 * G * (H - pos[:, 1])
    got, w = sample(WALL_POINTS, pos, p, rho, m, True, kernel)
    assert (w > 0).all()
    np.testing.assert_allclose(got, RHO0 * G * (H - WALL_POINTS[:, 1]), rtol=1e-12, atol=1e-9)


def test_wall_mode_with_tait_densities_is_within_the_stated_bound():
    """Tait densities of the column at rest (c0 = 20 m/s): the error is at most
    max |rho_j - rho0| g 2h (sampling module docstring), here a few mPa."""
    pos, rho, m = block()
    p = RHO0 * G * (H - pos[:, 1])
    b = 20.0**2 * RHO0 / 7.0
    rho = RHO0 * (p / b + 1.0) ** (1.0 / 7.0)
    got, _ = sample(WALL_POINTS, pos, p, rho, m, True)
    bound = np.abs(rho - RHO0).max() * G * 2 * HS
    assert np.abs(got - RHO0 * G * (H - WALL_POINTS[:, 1])).max() <= bound
    assert bound < 0.05 * RHO0 * G * DX  # 2 Pa: far below rho g dx = 98 Pa


def test_particle_mode_of_a_constant_field_is_exact_and_of_a_hydrostatic_one_is_not():
    """Shepard normalisation reproduces a constant field even where the wall truncates the
    kernel; the plain interpolation of a hydrostatic field at the floor misses the
    hydrostatic part below the wall (particles lie only above it), which wall mode restores."""
    pos, rho, m = block()
    got, _ = sample(WALL_POINTS, pos, np.full(len(pos), 1234.5), rho, m, False)
    np.testing.assert_allclose(got, 1234.5, rtol=1e-13)
    hydro = RHO0 * G * (H - pos[:, 1])
    floor, _ = sample(np.array([[0.25, 0.0]]), pos, hydro, rho, m, False)
    assert RHO0 * G * (H - 2 * HS) < floor[0] < RHO0 * G * H - 0.5 * RHO0 * G * DX


def test_a_sensor_with_no_particle_in_its_support_reads_zero_and_is_flagged():
    pos, rho, m = block()
    got, w = sample(np.array([[0.5, 0.3 + 2 * HS + 1e-6], [0.9, 0.1]]), pos, RHO0 * G * (H - pos[:, 1]), rho, m, True)
    assert (got == 0).all() and (w == 0).all()


def test_a_sensor_below_a_convex_edge_reads_only_the_water_in_front_of_its_face():
    """A step [0, 0.2] x [0, 0.1] in water (the particles around it): a sensor on its right
    face one spacing below the top edge has water above the step (x < 0.2) within 2h. With
    the face's normal it reads exactly the water in front of the face (here a constant
    field there and a different one above the step); without it the two are mixed. On a
    plane wall (the block's right side) the normal changes nothing, bit for bit."""
    pos, rho, m = block(height=0.3, width=0.4)
    keep = ~((pos[:, 0] < 0.2) & (pos[:, 1] < 0.1))
    pos, rho, m = np.ascontiguousarray(pos[keep]), rho[keep], m[keep]
    front = pos[:, 0] > 0.2
    p = np.where(front, 5000.0, -800.0)  # stagnation in front, suction over the edge
    sensor = np.array([[0.2, 0.1 - DX]])
    got, w = sample(sensor, pos, p, rho, m, False, face_n=(1.0, 0.0))
    assert w[0] > 0 and got[0] == pytest.approx(5000.0, rel=1e-13)
    mixed, _ = sample(sensor, pos, p, rho, m, False)
    assert mixed[0] < 5000.0 - 100.0  # the particles over the step pull it down
    pos, rho, m = block()
    hydro = RHO0 * G * (H - pos[:, 1])
    on_wall = WALL_POINTS[:5]  # the right wall x = 0.5
    a, _ = sample(on_wall, pos, hydro, rho, m, True, face_n=(-1.0, 0.0))
    b, _ = sample(on_wall, pos, hydro, rho, m, True)
    np.testing.assert_array_equal(a, b)


def test_line_points_are_centres_of_equal_pieces():
    pts = line_points([3.22, 0.1555], [3.22, 0.1645], 3)
    np.testing.assert_allclose(pts[:, 1], [0.157, 0.16, 0.163])
    assert (pts[:, 0] == 3.22).all()
    assert line_points([1.0, 2.0], [1.0, 2.0], 5).shape == (1, 2)


def test_select_near_keeps_exactly_the_fluid_within_reach_of_each_segment():
    rng = np.random.default_rng(1)
    pos = rng.uniform(0, 1, (5000, 2))
    kind = np.zeros(5000, np.int8)
    kind[::7] = 1  # spheres never count
    a = np.array([[1.0, 0.1], [0.3, 0.0]])
    b = np.array([[1.0, 0.2], [0.3, 1.0]])
    out = np.empty(5000, np.int64)
    got = set(out[: select_near(pos, kind, a, b, 0.05, out)].tolist())
    d1 = np.hypot(pos[:, 0] - 1.0, pos[:, 1] - np.clip(pos[:, 1], 0.1, 0.2))
    d2 = np.abs(pos[:, 0] - 0.3)
    want = set(np.flatnonzero(((d1 < 0.05) | (d2 < 0.05)) & (kind == 0)).tolist())
    assert got == want and len(got) > 100


@pytest.mark.parametrize("x", [0.25, 0.005, 0.01, 0.49])
@pytest.mark.parametrize("height", [0.3, 0.1, 0.03])
def test_depth_of_a_lattice_block_is_its_height_within_half_a_spacing(x, height):
    """The free surface (fluid fraction 0.5) of a block of known height H, found by the depth
    scan from the floor: within dx/2 of H in the middle, next to a wall (the wall images keep
    the fraction near 1) and for a layer three particles deep."""
    pos, rho, m = block(height)
    d = depth_above(np.array([x, 0.0]), np.array([0.0, 1.0]), DX / 4, pos, rho, m, KERNEL_IDS["wendland_c2"], HS,
                    NORMALS, OFFSETS)
    assert abs(d - height) < DX / 2


def test_depth_is_zero_on_a_dry_floor_and_ignores_water_above_an_air_gap():
    pos, rho, m = block(0.1, width=0.2)
    kid = KERNEL_IDS["wendland_c2"]
    up = np.array([0.0, 1.0])
    assert depth_above(np.array([0.4, 0.0]), up, DX / 4, pos, rho, m, kid, HS, NORMALS, OFFSETS) == 0.0
    # a sheet of water 0.1 m above the block (spray, an overturning jet) does not count
    sheet = pos[pos[:, 1] < 0.03] + np.array([0.0, 0.2])
    both = np.concatenate([pos, sheet])
    rb, mb = np.full(len(both), RHO0), np.full(len(both), RHO0 * DX * DX)
    d = depth_above(np.array([0.1, 0.0]), up, DX / 4, both, rb, mb, kid, HS, NORMALS, OFFSETS)
    assert abs(d - 0.1) < DX / 2


# ---------------------------------------------------------------------------- error figures


def test_first_rise_interpolates_the_first_crossing_of_0_1():
    assert figures.first_rise([0, 1, 2, 3], [0, 0.05, 0.15, 0.3]) == pytest.approx(1.5)
    assert figures.first_rise([0, 1, 2, 3], [0.2, 0.0, 0.3, 0.0]) == 0.0
    assert math.isnan(figures.first_rise([0, 1], [0.0, 0.09]))


def test_buchner_figures_on_a_synthetic_series():
    """Experiment: rises from 0 (tau 2.0) to 0.2 (tau 2.5), 0.6 at 3, then 0.5, 0.4, 0.3.
    Simulation: 0 up to tau 2.6, 0.5 from 2.7 on (samples every 0.1).
    MAE over tau in [2.6, 5.5] (experiment points 3, 4, 5): (0.1 + 0 + 0.1) / 3.
    Rise: experiment 2.0 + 0.5 (0.1/0.2) = 2.25; simulation 2.6 + 0.1 (0.1/0.5) = 2.62."""
    exp = np.array([[2.0, 0.0], [2.5, 0.2], [3.0, 0.6], [4.0, 0.5], [5.0, 0.4], [6.0, 0.3]])
    tau = np.round(np.arange(0, 70.5) * 0.1, 10)
    ps = np.where(tau >= 2.7, 0.5, 0.0)
    out = figures.buchner(tau, ps, exp)
    assert out["mae_points"] == 3
    assert out["mae_rhogH"] == pytest.approx(0.2 / 3, rel=1e-12)
    assert out["offset_rhogH"] == pytest.approx(0.0, abs=1e-12)  # median of -0.1, 0, +0.1
    assert out["rise_tau_exp"] == pytest.approx(2.25)
    assert out["rise_tau"] == pytest.approx(2.62)
    assert out["rise_dtau"] == pytest.approx(0.37)


def test_lobovsky_figures_on_a_synthetic_band():
    """Band 0.9..1.1 (median 1) everywhere; simulation samples at tau = 1, 2, 2.5, ..., 7, 8:
    the two outside [2, 7] do not count; of the 11 inside, one at 1.5 and one at 0.5 leave the
    band: fraction 9/11; the peak 1.5 (tau 3.5) is above the band's peak range [0.9, 1.1]."""
    band = np.array([[0.0, 0.9, 1.0, 1.1], [10.0, 0.9, 1.0, 1.1]])
    tau = np.concatenate([[1.0], np.arange(11) * 0.5 + 2.0, [8.0]])
    ps = np.ones_like(tau)
    ps[[0, -1]] = 5.0
    ps[4], ps[6] = 1.5, 0.5
    out = figures.lobovsky(tau, ps, band)
    assert out["band_samples"] == 11
    assert out["in_band_fraction"] == pytest.approx(9 / 11)
    assert out["offset_rhogH"] == 0.0  # nine of the eleven on the median
    assert out["peak_rhogH"] == 1.5 and out["peak_tau"] == 3.5 and out["peak_in_band"] is False
    assert (out["band_peak_lo_rhogH"], out["band_peak_hi_rhogH"]) == (0.9, 1.1)


def test_the_offset_measures_a_shift_and_ignores_spikes():
    """The experiment itself shifted by +0.25 (Lobovsky: its median; Buchner: its points),
    with every 20th sample a spike of +-10: the offset is the shift, while the MAE and the
    band fraction are ruined by the spikes."""
    from sphcore_plugins.gauges import reference

    band = reference.series("lobovsky_2014_sensor2")
    ps = band[:, 2] + 0.25
    ps[::20] += np.where(np.arange(ps[::20].size) % 2 == 0, 10.0, -10.0)
    out = figures.lobovsky(band[:, 0], ps, band)
    assert out["offset_rhogH"] == pytest.approx(0.25, abs=1e-12)
    assert out["in_band_fraction"] < 0.5
    exp = reference.series("buchner_2002_P1")
    tau = np.linspace(0.0, 7.5, 7501)
    ps = np.interp(tau, exp[:, 0], exp[:, 1]) - 0.25
    ps[::20] += 10.0
    out = figures.buchner(tau, ps, exp)
    assert out["offset_rhogH"] == pytest.approx(-0.25, abs=0.02)  # interpolation of the digitised points
    assert out["mae_rhogH"] > 0.25


def test_noise_is_the_ringing_around_the_moving_average():
    """A straight line has no noise (its centred moving average is itself, up to one sample
    more on one side of a window whose ends fall between samples: slope x dtau / 2); a ringing of
    amplitude A and a period 1/20 of the averaging window on top of it has noise A/sqrt(2)
    (within 2 %: the window holds 20 whole periods up to one sample); NaN without samples."""
    tau = np.linspace(0.0, 8.0, 80001)  # 1e-4 in tau, as a probe at every_dt = 1e-4 s and H ~ 0.1 m
    line = 0.3 + 0.05 * tau
    assert figures.noise(tau, line, 2.6, 5.5) <= 0.05 * 1e-4 / 2
    ring = line + 0.4 * np.sin(2 * np.pi * tau / (figures.NOISE_WINDOW / 20))
    assert figures.noise(tau, ring, 2.6, 5.5) == pytest.approx(0.4 / math.sqrt(2), rel=0.02)
    assert math.isnan(figures.noise(tau, ring, 9.0, 10.0))


def test_window_means_show_where_a_shift_lies():
    """The Lobovsky median shifted by +0.3 after tau = 4: the windows before 4 show no
    difference, those after show 0.3 (up to the band's sampling within a window)."""
    from sphcore_plugins.gauges import reference

    band = reference.series("lobovsky_2014_sensor2")
    ps = band[:, 2] + np.where(band[:, 0] >= 4.0, 0.3, 0.0)
    rows = figures.window_means(band[:, 0], ps, band, "lobovsky", 0.5)
    assert len(rows) == 10 and rows[0][0] == 2.0
    for a, sim, exp in rows:
        assert sim - exp == pytest.approx(0.3 if a >= 4.0 else 0.0, abs=1e-12)


def test_the_experiment_itself_scores_perfectly_in_si_units():
    """The Lobovsky median, turned into seconds and pascals with H = 0.3 m, rho = 997 kg/m^3,
    lies inside its own band and peaks at the band's median peak; Buchner P1 against itself
    has MAE 0 and no rise difference."""
    from sphcore_plugins.gauges import reference

    rho, g, height = 997.0, 9.81, 0.3
    band = reference.series("lobovsky_2014_sensor2")
    t = band[:, 0] * math.sqrt(height / g)
    out = figures.errors("lobovsky_2014_sensor2", t, band[:, 2] * rho * g * height, rho, g, height)
    assert out["in_band_fraction"] == 1.0
    assert out["peak_rhogH"] == pytest.approx(out["band_peak_median_rhogH"], rel=1e-12)
    assert out["peak_in_band"] is True
    p1 = reference.series("buchner_2002_P1")
    out = figures.errors("buchner_2002_P1", p1[:, 0] * math.sqrt(0.6 / g), p1[:, 1] * 1000 * g * 0.6, 1000.0, g, 0.6)
    assert out["mae_rhogH"] < 1e-12 and out["rise_dtau"] == pytest.approx(0.0, abs=1e-12)
    assert 2.4 < out["rise_tau_exp"] < 2.55  # the first impact (header: near 2.4)
