"""Small cases shared by the core physics and run tests, as data (nested dicts laid out as
case.toml is): each function returns a new dict, to use as it is or to vary with
:func:`sphcore.testing.case_with`."""

from __future__ import annotations

from sphcore.testing import write_case


def good() -> dict:
    """A small valid 2D case: a 10 x 10 block of fluid (dx = 0.02 m) resting in a 1 m box."""
    return {
        "case": {"dim": 2},
        "domain": {"min": [0.0, 0.0], "max": [1.0, 1.0]},
        "blocks": [{"min": [0.2, 0.2], "max": [0.4, 0.4]}],
        "particles": {"dx": 0.02},
        "time": {"t_end": 0.002},
        "plugins": {"use": []},
    }


def spheres_case(velocity=(0.0, 0.0), gravity=(0.0, 0.0), t_end=0.01, dt=0.001, scheme="leapfrog") -> dict:
    """A 4 x 3 block of rigid spheres (no SPH) far from the walls of a 20 m box; ``dt`` None
    leaves the time step to the case's rules."""
    return {
        "case": {"dim": 2},
        "domain": {"min": [-10.0, -10.0], "max": [10.0, 10.0]},
        "blocks": [{"min": [0.0, 0.0], "count": [4, 3], "kind": "sphere", "velocity": list(velocity)}],
        "particles": {"dx": 0.05},
        "physics": {"sph": False, "gravity": list(gravity)},
        "time": {"t_end": t_end} if dt is None else {"t_end": t_end, "dt": dt},
        "integrator": {"scheme": scheme},
        "plugins": {"use": []},
    }


def spheres(tmp_path, velocity=(0.0, 0.0), gravity=(0.0, 0.0), t_end=0.01, dt=0.001, scheme="leapfrog",
            name="spheres"):
    """The case directory ``tmp_path``/``name`` of :func:`spheres_case`."""
    return write_case(tmp_path / name, spheres_case(velocity, gravity, t_end, dt, scheme))


def colliding() -> dict:
    """Two 8 x 8 blocks of fluid, mirror images about x = 0.5 one spacing apart, moving towards
    each other at 0.5 m/s. The lattice spacing 1/64 m makes every initial position and its
    mirror exact binary numbers."""
    return {
        "case": {"dim": 2},
        "domain": {"min": [0.0, 0.0], "max": [1.0, 1.0]},
        "blocks": [{"min": [0.375, 0.25], "count": [8, 8], "velocity": [0.5, 0.0]},
                   {"min": [0.5, 0.25], "count": [8, 8], "velocity": [-0.5, 0.0]}],
        "particles": {"dx": 0.015625},
        "eos": {"c0": 20.0},
        "viscosity": {"alpha": 0.2, "beta": 0.2},
        "density_diffusion": {"delta": 0.1},
        "time": {"t_end": 0.01},
        "plugins": {"use": []},
    }


def blob() -> dict:
    """A 2D blob of fluid far from every wall, no gravity."""
    return {
        "case": {"dim": 2},
        "domain": {"min": [-5.0, -5.0], "max": [5.0, 5.0]},
        "blocks": [{"min": [-0.1, -0.1], "count": [10, 10]}],
        "particles": {"dx": 0.02},
        "physics": {"gravity": [0.0, 0.0]},
        "eos": {"c0": 10.0},
        "viscosity": {"alpha": 0.5, "beta": 0.5},
        "time": {"t_end": 1.0},
        "plugins": {"use": []},
    }


SPH_KERNELS = ("neighbour_search", "continuity", "momentum", "eos", "artificial_viscosity",
               "laminar_viscosity", "density_diffusion", "reorder", "extra_sources")
