"""The ``wall_integral`` plugin in the force loop: the wall completes the kernel sums.

Known answers: a uniform pressure pushes no particle anywhere (its own pressure is balanced
by the wall's); water at rest with plain Tait pressure stays hydrostatic to a few per cent
where the reflective walls alone leave it 40% off (measured figures are in docs/validation/hydrostatic_tank.md).
"""

from __future__ import annotations

import numpy as np
import pytest

from sphcore.run import runner
from sphcore.run.build import build
from sphcore.testing import case_with, run_case, write_case


def box(dim, lo, hi, use) -> dict:
    """The box from ``lo`` to ``hi`` filled with fluid at 5 kPa, no gravity, plugins ``use``."""
    return {
        "case": {"dim": dim},
        "domain": {"min": lo, "max": hi},
        "blocks": [{"min": lo, "max": hi}],
        "particles": {"dx": 0.02},
        "physics": {"gravity": [0.0, 0.0, 0.0], "hydrostatic_init": False},
        "eos": {"c0": 20.0, "p_background": 5000.0},
        "viscosity": {"alpha": 0.0},
        "time": {"t_end": 0.01},
        "plugins": {"use": use},
    }


def box_sim(tmp_path, dim, use, h_over_dx=1.3):
    lo = [0.0] * dim
    hi = [0.2] * dim
    case_dir = write_case(tmp_path / f"box{dim}", case_with(box(dim, lo, hi, use), {"kernel.h_over_dx": h_over_dx}))
    case, pm = runner.load(case_dir)
    sim = build(case, pm)
    sim.integrator.rates()
    return sim


@pytest.mark.parametrize("dim", [2, 3])
@pytest.mark.parametrize("h_over_dx", [1.3, 2.0])
def test_a_uniform_pressure_pushes_no_particle(tmp_path, dim, h_over_dx):
    """5 kPa everywhere in a box filled with fluid, no gravity: every acceleration is zero
    with the wall model (to round-off), including edges and corners; without it the
    particles along the walls are pushed into them."""
    with_walls = box_sim(tmp_path, dim, ["reflective", "wall_integral"], h_over_dx)
    a = np.linalg.norm(with_walls.integrator.acc, axis=1)
    p_scale = 5000.0 / 1000.0 / (h_over_dx * 0.02)  # p / (rho h): the size of one unbalanced term
    assert a.max() < 1e-9 * p_scale
    bare = box_sim(tmp_path / "bare", dim, ["reflective"], h_over_dx)
    assert np.linalg.norm(bare.integrator.acc, axis=1).max() > 0.1 * p_scale


TANK = {
    "case": {"dim": 2},
    "domain": {"min": [0.0, 0.0], "max": [0.4, 0.5]},
    "blocks": [{"min": [0.0, 0.0], "max": [0.4, 0.4]}],
    "particles": {"dx": 0.02},
    "kernel": {"h_over_dx": 2.0},
    "density_diffusion": {"delta": 0.1, "hydrostatic": True},
    "time": {"t_end": 0.5},
    "plugins": {"use": []},
    "reflective": {"cr": 0.0},
}


def layer_error(summary):
    return summary["pressure_gauge"]["pressure_max_layer_err"]


def test_wall_model_keeps_a_tank_at_rest_with_plain_tait(tmp_path):
    """A 0.4 m deep tank, plain Tait pressure, 0.5 s (about 20 sound crossings): the layer
    pressure errors below the top two layers stay within the 2% criterion with the wall model
    (measured 1.4%) and no particle moves by more than 0.1 dx (measured 0.06 dx, the
    free-surface corners included; the columns along the side walls do not slide); the
    reflective walls alone leave the layers 27% off with particles moved by 3 dx."""
    model = run_case(tmp_path / "model", TANK, plugins=["reflective", "wall_integral", "pressure_gauge"])
    bare = run_case(tmp_path / "bare", TANK, plugins=["reflective", "pressure_gauge"])
    assert model["status"] == bare["status"] == "completed"
    assert model["pressure_gauge"]["particles_lost"] == 0
    assert layer_error(model) < 0.02
    assert layer_error(bare) > 5 * layer_error(model)
    assert model["pressure_gauge"]["max_displacement_m"] < 0.1 * 0.02


def test_lattice_moment_is_the_interior_sum_and_tends_to_the_continuum():
    """lambda = -(1/dim) sum_k dx^dim x_k . grad W(x_k) on the square/cubic lattice: an
    independent brute-force sum of the full tensor gives lambda I (cubic symmetry), 0.974
    for Wendland C2 at h = 1.3 dx in 2D, and lambda -> 1 as h/dx grows (the continuum)."""
    from sphcore.physics.kernels import WENDLAND_C2, kernel_f, lattice_moment

    for dim in (2, 3):
        dx, h = 0.02, 1.3 * 0.02
        k = np.arange(-3, 4) * dx
        x = np.stack(np.meshgrid(*([k] * dim), indexing="ij"), axis=-1).reshape(-1, dim)
        r = np.linalg.norm(x, axis=1)
        x, r = x[r > 0], r[r > 0]
        f = np.array([kernel_f(WENDLAND_C2, ri, h, dim) for ri in r])
        tensor = -(dx ** dim) * np.einsum("k,ka,kb->ab", f, x, x)  # sum V x_k (x) grad W
        lam = lattice_moment(WENDLAND_C2, h, dx, dim)
        assert np.allclose(tensor, lam * np.eye(dim), atol=1e-12)
        assert abs(lattice_moment(WENDLAND_C2, 4.0 * dx, dx, dim) - 1.0) < 1e-3
    assert abs(lattice_moment(WENDLAND_C2, 1.3 * 0.02, 0.02, 2) - 0.9739) < 1e-4


@pytest.mark.parametrize("h_over_dx", [1.3, 2.0])
def test_a_column_along_a_side_wall_is_held_up_as_the_interior(tmp_path, h_over_dx):
    """Plain Tait tank at t = 0: in every row away from the floor's and the surface's
    support, the particle next to the side wall has the vertical acceleration of the
    particle at the tank's centre within 0.06 m/s^2 (measured 0.029 and 0.044; 0.28 and
    0.11 before the wall completion took the interior's lattice normalisation lambda and
    the side wall's lattice error F into account). A mismatch there makes the columns
    along the walls slide against the bulk."""
    case = case_with(TANK, {"plugins.use": ["reflective", "wall_integral"], "kernel.h_over_dx": h_over_dx})
    case_dir = write_case(tmp_path / "tank", case)
    case, pm = runner.load(case_dir)
    sim = build(case, pm)
    sim.integrator.rates()
    st, a = sim.ctx.state, sim.integrator.acc
    x, y = st.pos[:, 0], st.pos[:, 1]
    support = 2.0 * h_over_dx * 0.02
    rows = [r for r in np.unique(np.round(y, 9)) if support < r < 0.4 - support]
    assert len(rows) >= 3
    for r in rows:
        side = np.isclose(y, r) & (x < 0.02)
        centre = np.isclose(y, r) & np.isclose(x, 0.19)
        assert side.sum() == centre.sum() == 1
        assert abs(a[side, 1][0] - a[centre, 1][0]) < 0.06


def test_a_lone_particle_near_a_wall_gets_no_wall_completion(tmp_path):
    """A splash particle 1.5 dx above the floor with no neighbours, moving away from the
    wall at 2 m/s under a 5 kPa pressure: the mirror image of its (empty) neighbourhood is
    empty, so the wall neither pushes it nor changes its density (acceleration g, zero in
    this box; drho/dt 0). With the lattice's wall gradient applied in full it lost density at about
    2 rho v |G| ~ 10^5 kg/m^3/s (a Lobovsky splash particle fell below 0.5 rho0)."""
    case = case_with(box(2, [0.0, 0.0], [0.2, 0.2], ["reflective", "wall_integral"]),
                     {"blocks[0].min": [0.09, 0.02], "blocks[0].max": [0.11, 0.04]})
    case_dir = write_case(tmp_path / "lone", case)
    case, pm = runner.load(case_dir)
    sim = build(case, pm)
    st = sim.ctx.state
    assert st.n == 1 and abs(st.pos[0, 1] - 0.03) < 1e-12
    st.vel[0] = (0.0, 2.0)
    sim.integrator.invalidate()
    sim.integrator.rates()
    assert np.abs(sim.integrator.acc[0]).max() < 1e-12
    assert abs(sim.integrator.drho[0]) < 1e-9


def test_water_does_not_cling_to_the_back_wall_with_the_wall_model(tmp_path):
    """The seed's dam break at half its resolution (dx = 0.114 m / 18, 648 particles, 0.3 s):
    the residual column height at the back wall against Martin & Moyce is 7.5% RMS with the
    wall model and 25.7% with the reflective walls alone (default CFL 0.3; 7.3% and 27.0% at
    CFL 0.2), whose truncated kernel lets the water cling to the wall (at the case's
    resolution: 4.8% and 23.2%)."""
    from pathlib import Path

    case = Path(__file__).resolve().parent.parent / "cases" / "dam_break"
    err = {}
    for name, use in (("bare", '["reflective","front_gauge"]'), ("model", '["reflective","wall_integral","front_gauge"]')):
        s = runner.run(case, output=tmp_path / name, quiet=True,
                       overrides=[f"plugins.use={use}", "front_gauge.wall_height=true",
                                  f"particles.dx={0.114 / 18!r}"])
        assert s["status"] == "completed"
        err[name] = s["front_gauge"]["rms_rel_err_martin_moyce_height"]
    assert err["model"] < 0.10
    assert err["bare"] > 2.5 * err["model"]


@pytest.mark.parametrize("dim", [2, 3])
def test_a_stagnation_flow_changes_the_density_only_where_the_kernel_is_truncated(tmp_path, dim):
    """The continuity sum of the divergence-free flow u = a x, w = -a z (z up from the
    floor) on the initial lattice, reflective walls alone, no gravity: drho/dt / (rho0 a)
    is -(M_tt - M_nn) at a layer whose support the floor truncates, M the layer's second
    moment sum_j V_j (x_j - x_i) (x) grad_i W_ij (an independent brute-force sum here), and
    0 to round-off where the support is whole. This is the floor layer's spurious
    compression or expansion next to the floor (docs/explanation/wall_model.md)."""
    from sphcore.physics.kernels import WENDLAND_C2, kernel_f

    dx, hdx, side = 0.02, 1.3, 0.3
    h = hdx * dx
    lo, hi = [0.0] * dim, [side] * dim
    case, pm = runner.load(write_case(tmp_path / "box", box(dim, lo, hi, ["reflective"])))
    sim = build(case, pm)
    st = sim.ctx.state
    x = st.pos
    st.vel[:] = 0.0
    st.vel[:, 0] = x[:, 0] - 0.5 * side
    st.vel[:, -1] = -x[:, -1]
    sim.integrator.invalidate()
    sim.integrator.rates()
    rate = sim.integrator.drho / 1000.0
    # the lattice's moments of a node at (k + 1/2) dx above a wall, brute force
    n = 4
    k = np.arange(-n, n + 1) * dx
    off = np.stack(np.meshgrid(*([k] * dim), indexing="ij"), axis=-1).reshape(-1, dim)
    r = np.linalg.norm(off, axis=1)
    keep = (r > 0) & (r < 2 * h)
    off, r = off[keep], r[keep]
    f = dx ** dim * np.array([kernel_f(WENDLAND_C2, ri, h, dim) for ri in r])
    far = np.all(np.abs(x[:, :-1] - 0.5 * side) < 0.5 * side - 2 * h - 1e-9, axis=1)
    for layer in range(4):
        inside = off[:, -1] + (layer + 0.5) * dx > 0.0
        m = -np.einsum("k,ka,kb->ab", f[inside], off[inside], off[inside])
        expected = -(m[0, 0] - m[-1, -1])
        sel = far & np.isclose(x[:, -1], (layer + 0.5) * dx)
        assert sel.sum() > 0
        assert np.allclose(rate[sel], expected, rtol=1e-9, atol=1e-12)
    if dim == 2:  # M_tt = 0.762, M_nn = 0.487 at the floor layer
        assert abs(np.mean(rate[far & np.isclose(x[:, -1], 0.5 * dx)]) + 0.275) < 0.001
