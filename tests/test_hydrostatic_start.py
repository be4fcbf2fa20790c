"""The hydrostatic start: the exact hydrostatic state of the Tait fluid, the discrete
equilibrium of the SPH sums on the initial lattice.

Known answers: p(d) solves dp/dd = rho(p) g with p(0) = 0 and tends to rho0 g d for a
stiff fluid; in a tank at rest with plain Tait pressure and the wall model, every particle
below the free surface's reach starts with the same vertical acceleration, the lattice
normalisation's (lambda - 1) g, side walls and floor included (with equal masses it drifted
with depth and differed along the side walls).
"""

from __future__ import annotations

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from sphcore.physics import eos
from sphcore.run import runner
from sphcore.run.build import build
from sphcore.testing import case_with, write_case


@settings(max_examples=60, deadline=None)
@given(gamma=st.floats(1.0, 10.0), c0=st.floats(5.0, 200.0), depth=st.floats(1e-3, 5.0))
def test_hydrostatic_pressure_solves_dp_dd_equals_rho_g(gamma, c0, depth):
    """A centred difference of p(d) equals rho(p(d)) g (relative 1e-6); p(0) = 0."""
    rho0, g = 1000.0, 9.81
    hd = 1e-4 * depth
    p = eos.hydrostatic_pressure(np.array([depth - hd, depth, depth + hd]), rho0, c0, gamma, g)
    dpdd = (p[2] - p[0]) / (2 * hd)
    rho = eos.density_of(p[1:2], rho0, c0, gamma)[0]
    assert dpdd == pytest.approx(rho * g, rel=1e-6)
    assert eos.hydrostatic_pressure(np.zeros(1), rho0, c0, gamma, g)[0] == 0.0


def test_hydrostatic_pressure_limits():
    """gamma = 1 is the limit of gamma -> 1; a stiff fluid gives rho0 g d (1 + g d / (2 c0^2))
    to second order; an exponent below 1 whose density diverges within the depth gives NaN."""
    d = np.array([0.1, 1.0, 3.0])
    one = eos.hydrostatic_pressure(d, 1000.0, 20.0, 1.0, 9.81)
    near = eos.hydrostatic_pressure(d, 1000.0, 20.0, 1.0 + 1e-7, 9.81)
    assert one == pytest.approx(near, rel=1e-6)
    stiff = eos.hydrostatic_pressure(d, 1000.0, 300.0, 7.0, 9.81)
    assert stiff == pytest.approx(1000.0 * 9.81 * d * (1 + 9.81 * d / (2 * 300.0**2)), rel=1e-7)
    assert np.isnan(eos.hydrostatic_pressure(np.array([10.0]), 1000.0, 2.0, 0.5, 9.81)[0])


def tank(h_over_dx: float) -> dict:
    return {
        "case": {"dim": 2},
        "domain": {"min": [0.0, 0.0], "max": [0.6, 0.7]},
        "blocks": [{"min": [0.0, 0.0], "max": [0.6, 0.6]}],
        "particles": {"dx": 0.02},
        "kernel": {"h_over_dx": h_over_dx},
        "density_diffusion": {"delta": 0.1, "hydrostatic": True},
        "time": {"t_end": 0.01},
        "plugins": {"use": ["reflective", "wall_integral"]},
    }


@pytest.mark.parametrize("h_over_dx", [1.3, 1.5, 2.0])
def test_a_tank_at_rest_starts_in_the_discrete_equilibrium(tmp_path, h_over_dx):
    """One force evaluation at t = 0: below the free surface's reach (2h + dx), every
    particle's vertical acceleration is (lambda - 1) g, to 1e-5 g beyond the floor's reach
    (the columns along the side walls included) and 1e-4 g within it (the wall tables'
    interpolation in the wall distances), and none is pushed sideways by more than 5e-5 g. With a start
    of equal masses the deep rows drifted by up to 0.014 g and the wall columns
    differed by 0.004 g (docs/validation/hydrostatic_tank.md)."""
    case, pm = runner.load(write_case(tmp_path / "tank", tank(h_over_dx)))
    sim = build(case, pm)
    sim.integrator.rates()
    st_, prm = sim.ctx.state, sim.ctx.params
    acc = sim.integrator.acc[: st_.n] / prm.g_abs
    deep = st_.pos[:, 1] < 0.6 - prm.support - prm.dx
    floor = st_.pos[:, 1] < prm.support
    assert deep.sum() > 0.5 * st_.n
    assert acc[deep & ~floor, 1] == pytest.approx(prm.moment_norm - 1.0, abs=1e-5)
    assert acc[floor, 1] == pytest.approx(prm.moment_norm - 1.0, abs=1e-4)
    assert np.abs(acc[deep, 0]).max() < 5e-5
    # the masses carry the stratification: rho / m is the lattice's 1 / dx^2 everywhere
    assert st_.rho / st_.m == pytest.approx(1.0 / prm.dx**2, rel=1e-12)


def test_a_column_the_eos_cannot_hold_at_rest_is_refused_and_nothing_is_written(tmp_path, capsys):
    """gamma = 0.5, c0 = 2 m/s, a 1 m column: the Tait density diverges at 0.82 m depth
    (1 + (1 - 1/gamma) rho0 g d / B = 0), so the start has no hydrostatic state: exit 2,
    one line naming the file and eos.gamma, no output directory."""
    from sphcore import cli

    case = case_with(tank(1.3), {"blocks[0].max": [0.6, 1.0], "domain.max": [0.6, 1.2], "eos": {"c0": 2.0, "gamma": 0.5}})
    case_dir = write_case(tmp_path / "deep", case)
    assert cli.main(["run", str(case_dir), "--output", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "eos.gamma" in err and "case.toml" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()
