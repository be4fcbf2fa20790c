"""Small cases shared by the core physics and run tests (TOML text, formatted per test)."""

from __future__ import annotations

from conftest import write_case

SPHERES = """
[case]
dim = 2

[domain]
min = [-10.0, -10.0]
max = [10.0, 10.0]

[[blocks]]
min = [0.0, 0.0]
count = [4, 3]
kind = "sphere"
velocity = {velocity}

[particles]
dx = 0.05

[physics]
sph = false
gravity = {gravity}

[time]
t_end = {t_end}
{dt}

[integrator]
scheme = "{scheme}"

[plugins]
use = []
"""


def spheres(tmp_path, velocity=(0.0, 0.0), gravity=(0.0, 0.0), t_end=0.01, dt=0.001, scheme="leapfrog",
            name="spheres"):
    text = SPHERES.format(velocity=list(velocity), gravity=list(gravity), t_end=t_end, scheme=scheme,
                          dt="" if dt is None else f"dt = {dt}")
    return write_case(tmp_path / name, text)


# Two 8 x 8 blocks of fluid, mirror images about x = 0.5 one spacing apart, moving towards
# each other at 0.5 m/s. The lattice spacing 1/64 m makes every initial position and its
# mirror exact binary numbers.
COLLIDING = """
[case]
dim = 2

[domain]
min = [0.0, 0.0]
max = [1.0, 1.0]

[[blocks]]
min = [0.375, 0.25]
count = [8, 8]
velocity = [0.5, 0.0]

[[blocks]]
min = [0.5, 0.25]
count = [8, 8]
velocity = [-0.5, 0.0]

[particles]
dx = 0.015625

[eos]
c0 = 20.0

[viscosity]
alpha = 0.2
beta = 0.2

[density_diffusion]
delta = 0.1

[time]
t_end = 0.01

[plugins]
use = []
"""

# A 2D blob of fluid far from every wall, no gravity.
BLOB = """
[case]
dim = 2

[domain]
min = [-5.0, -5.0]
max = [5.0, 5.0]

[[blocks]]
min = [-0.1, -0.1]
count = [10, 10]

[particles]
dx = 0.02

[physics]
gravity = [0.0, 0.0]

[eos]
c0 = 10.0

[viscosity]
alpha = 0.5
beta = 0.5

[time]
t_end = 1.0

[plugins]
use = []
"""

SPH_KERNELS = ("neighbour_search", "continuity", "momentum", "eos", "artificial_viscosity",
               "laminar_viscosity", "density_diffusion", "reorder", "extra_sources")
