"""The plugin template (examples/plugin_template), installed from its folder with pip the way a
third party would, selected by a case, and run: the public API is all it needs."""

from __future__ import annotations

import ast
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

from sphcore.plugin import pluginhost
from sphcore.testing import case_with, run_case, tiny_case

TEMPLATE = Path(__file__).resolve().parents[1] / "examples" / "plugin_template"
MODULE = TEMPLATE / "sph_energy_log" / "__init__.py"

# a 0.1 m x 0.2 m column released in a 0.5 m tank: kinetic energy rises from zero
COLUMN = case_with(tiny_case(), {"domain.max": [0.5, 0.3], "blocks[0].max": [0.1, 0.2], "particles.dx": 0.01,
                                  "time.t_end": 0.05})


@pytest.fixture(scope="module")
def installed(tmp_path_factory):
    """pip install the template into a fresh target directory put on sys.path."""
    site = tmp_path_factory.mktemp("site")
    subprocess.run([sys.executable, "-m", "pip", "install", "--quiet", "--no-deps",
                    "--target", str(site), str(TEMPLATE)], check=True, capture_output=True)
    sys.path.insert(0, str(site))
    pluginhost.refresh()
    yield site
    sys.path.remove(str(site))
    sys.modules.pop("sph_energy_log", None)
    pluginhost.refresh()


def test_template_is_small_and_uses_only_the_public_module():
    source = MODULE.read_text()
    assert len(source.splitlines()) < 50
    imports = [n for n in ast.walk(ast.parse(source)) if isinstance(n, (ast.Import, ast.ImportFrom))]
    sph = {n.module for n in imports if isinstance(n, ast.ImportFrom) and (n.module or "").startswith("sphcore")}
    assert sph == {"sphcore.api"}


def test_template_installs_and_runs_in_a_case(installed, tmp_path):
    info = pluginhost.available()["energy_log"]
    assert info.error == "" and info.dist == "sph-energy-log"
    summary = run_case(tmp_path, COLUMN, plugins=["reflective", "energy_log"], tables={"energy_log": {"every_steps": 5}})
    assert summary["status"] == "completed", summary["message"]
    figures = summary["energy_log"]
    series = np.loadtxt(tmp_path / "output" / "energy.csv", delimiter=",", skiprows=1)
    # the column falls: kinetic energy grows from zero, and the peak is the series' largest value
    assert series[0, 1] < series[-1, 1] and figures["kinetic_peak_J"] == pytest.approx(series[:, 1].max())
    assert figures["kinetic_peak_t_s"] == pytest.approx(series[np.argmax(series[:, 1]), 0])
    # energy cannot exceed the potential energy released: M g (the centre of mass' drop)
    m = 1000.0 * 0.01 ** 2 * 200
    assert figures["kinetic_peak_J"] < m * 9.81 * 0.1


def test_template_option_error_names_the_key(installed, tmp_path):
    from sphcore import cli

    case_dir = tmp_path / "bad"
    from sphcore.testing import write_case

    write_case(case_dir, COLUMN, plugins=["reflective", "energy_log"], tables={"energy_log": {"file": "../escape.csv"}})
    assert cli.main(["run", str(case_dir)]) == 2
    assert not (case_dir / "output").exists()
