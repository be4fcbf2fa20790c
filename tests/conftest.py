"""Shared helpers for the core tests: write a case directory, build a Simulation, step it.

Cases (dicts: core_cases.py, sphcore.testing.case_with) are written into pytest's
``tmp_path``; nothing is written under the repository. Plugins are never selected unless a
test says so (``[plugins] use = []``).
"""

from __future__ import annotations

import importlib.util
import os
import sys
from pathlib import Path

import numpy as np
import pytest
from core_cases import good
from hypothesis import HealthCheck, settings

from sphcore.jit import prepare
from sphcore.run import runner
from sphcore.run.build import build
from sphcore.run.simulation import Simulation
from sphcore.testing import case_toml, write_case  # the tests import write_case from here

# Hypothesis: CI draws the same examples on every run (derandomised, no example database),
# and with no timing-based check (deadline, too_slow), so a submission is never failed by a
# draw or a timing no earlier run made; a developer's run keeps
# exploring new examples and remembers its failures. HYPOTHESIS_PROFILE picks either.
settings.register_profile("ci", derandomize=True, database=None, print_blob=True, deadline=None,
                          suppress_health_check=[HealthCheck.too_slow])
settings.register_profile("dev", print_blob=True)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci" if os.environ.get("CI") else "dev"))

prepare()  # tests call kernels directly too: the process settings a run makes first


# Tiers: a plain `pytest` runs the fast tier (a few minutes on two cores); the long physics
# regressions are marked `slow` and run with --all, which is what the README's test command
# and CI run. `-m slow` runs only them.
def pytest_addoption(parser):
    parser.addoption("--all", action="store_true", help="run every tier: the slow physics regressions too")


def pytest_collection_modifyitems(config, items):
    if config.getoption("--all") or config.getoption("-m"):
        return
    slow = [item for item in items if item.get_closest_marker("slow")]
    if slow:
        config.hook.pytest_deselected(items=slow)
        items[:] = [item for item in items if not item.get_closest_marker("slow")]

# The good case (core_cases.good) as case.toml text, for tests that malform the text (test_malformed_inputs).
GOOD_CASE = case_toml(good())


def make_sim(case_dir, overrides=()) -> Simulation:
    """A Simulation of the case (plugins from ``[plugins] use``), with no output directory."""
    case, pm = runner.load(case_dir, overrides)
    return build(case, pm, None)


def run_to_end(sim: Simulation, max_steps: int = 100_000) -> list[float]:
    """Step until t_end; returns the time steps taken (s)."""
    dts = []
    while not sim.done():
        sim.advance()
        dts.append(sim.dt)
        assert len(dts) < max_steps, "the run does not end"
    return dts


def write_cut_netcdf(path: Path, cut: str, build=None) -> None:
    """A netCDF file as a run killed inside its header leaves it: ``cut`` "empty" (no byte),
    else global attributes only, plus what ``build(ds)`` defines (some of the header)."""
    import netCDF4

    if cut == "empty":
        path.write_bytes(b"")
        return
    with netCDF4.Dataset(path, "w", format="NETCDF3_64BIT_DATA") as ds:
        ds.title = "cut"
        if build is not None:
            build(ds)


def by_id(state) -> dict[str, np.ndarray]:
    """Every particle array of a state, ordered by particle id."""
    order = np.argsort(state.id, kind="stable")
    return {name: a[order] for name, a in state.arrays()}


@pytest.fixture
def good_case(tmp_path) -> Path:
    """A valid case directory (core_cases.good)."""
    return write_case(tmp_path / "good", good())


def script(name: str):
    """A script as a module: postprocessing/<name>.py (the user's toolkit), else the study
    validation/<case>/<name>.py. The scripts are not a package: run as ``python DIR/X.py``
    they find their siblings (postprocessing/runs.py) because Python puts DIR first on
    sys.path; the script's folder is put there here the same way while it loads."""
    root = Path(__file__).resolve().parents[1]
    found = [root / "postprocessing" / f"{name}.py", *sorted(root.glob(f"validation/*/{name}.py"))]
    path = next((p for p in found if p.is_file()), None)
    if path is None:
        raise FileNotFoundError(f"no script {name}.py in postprocessing/ or validation/*/")
    folder = str(path.parent)
    sys.path.insert(0, folder)
    try:
        spec = importlib.util.spec_from_file_location(f"pp_{name}", path)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
    finally:
        sys.path.remove(folder)
    return mod
