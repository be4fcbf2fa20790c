"""The hydrostatic pressure gauge measures layers one particle spacing thick, whatever the
contact radius a case sets (it once took the layer thickness and the floor from the radius)."""

from __future__ import annotations

import numpy as np
import pytest

from sphcore.physics import eos
from sphcore.testing import case_with, run_case

TANK = {
    "case": {"dim": 2},
    "domain": {"min": [0.0, 0.0], "max": [0.2, 0.3]},
    "blocks": [{"min": [0.0, 0.0], "max": [0.2, 0.2]}],
    "particles": {"dx": 0.01},
    "physics": {"modified_pressure": False},
    "time": {"t_end": 1e-9},
    "plugins": {"use": ["reflective", "pressure_gauge"]},
}


@pytest.mark.parametrize("radius", [None, 0.003, 0.005])
def test_gauge_reads_the_initial_hydrostatic_tank_as_exact(tmp_path, radius):
    """At t = 0 the particles carry the exact hydrostatic pressure of the Tait fluid
    (sphcore.physics.eos.hydrostatic_pressure): the gauge, which compares with the incompressible
    rho0 g (H - y), reads the compressibility's excess p(d) / (rho0 g d) - 1 at the deepest
    layer (d = H - dx/2; 0.24 % in this 0.2 m tank at c0 = 10 sqrt(2 g H)), to round-off,
    and nothing has moved, for any contact radius."""
    s = run_case(tmp_path, case_with(TANK, {"particles.radius": radius}))
    g = s["pressure_gauge"]
    assert s["status"] == "completed"
    d = 0.2 - 0.005
    excess = eos.hydrostatic_pressure(np.array([d]), 1000.0, s["c0"], 7.0, 9.81)[0] / (1000.0 * 9.81 * d) - 1
    assert 0.002 < excess < 0.003
    assert g["pressure_max_layer_err"] == pytest.approx(excess, rel=1e-9)
    assert abs(g["surface_drift_m"]) < 1e-9
    assert g["max_displacement_m"] < 1e-12
