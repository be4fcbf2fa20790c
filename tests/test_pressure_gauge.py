"""The hydrostatic pressure gauge measures layers one particle spacing thick, whatever the
contact radius a case sets (it once took the layer thickness and the floor from the radius)."""

from __future__ import annotations

import pytest

from sphcore.testing import run_case

TANK = """
[case]
dim = 2
[domain]
min = [0.0, 0.0]
max = [0.2, 0.3]
[[blocks]]
min = [0.0, 0.0]
max = [0.2, 0.2]
[particles]
dx = 0.01
{radius}
[physics]
modified_pressure = false
[time]
t_end = 1e-9
[plugins]
use = ["reflective", "pressure_gauge"]
"""


@pytest.mark.parametrize("radius", ["", "radius = 0.003", "radius = 0.005"])
def test_gauge_reads_the_initial_hydrostatic_tank_as_exact(tmp_path, radius):
    """At t = 0 the particles carry the exact hydrostatic pressure rho0 g (H - y): every
    layer's error is round-off and nothing has moved, for any contact radius."""
    s = run_case(tmp_path, TANK.format(radius=radius))
    g = s["pressure_gauge"]
    assert s["status"] == "completed"
    assert g["pressure_max_layer_err"] < 1e-9  # round-off: 1e-12 measured
    assert abs(g["surface_drift_m"]) < 1e-9
    assert g["max_displacement_m"] < 1e-12
