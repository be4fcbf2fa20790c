"""Third-party plugins, installed the real way: a module plus a ``*.dist-info`` folder with an
``entry_points.txt`` in the group ``sphcore``, found on ``sys.path`` by importlib.metadata.

The throwaway plugin declares a table ``[throwaway]`` (one key, ``accel``), reads it in
``sph_configure``, adds that constant acceleration in ``sph_accelerations`` and counts
``sph_after_step`` calls.
"""

from __future__ import annotations

import json
import sys
import textwrap
from pathlib import Path

import numpy as np
import pytest
from conftest import by_id, make_sim, write_case

from sphcore import cli
from sphcore.errors import CaseError
from sphcore.plugin import pluginhost
from sphcore.plugin.pluginhost import PluginLoadError
from sphcore.run import runner
from sphcore.testing import case_with

GOOD_PLUGIN = '''
"""A throwaway sphcore plugin, written by the test suite."""
import numpy as np

from sphcore.api import Option, hookimpl


class Throwaway:
    def __init__(self):
        self.accel = None
        self.after_step_calls = 0

    @hookimpl
    def sph_options(self):
        return {"throwaway": {
            "accel": Option([0.0, 0.0, 0.0], "vector", "m/s^2", "constant extra acceleration"),
            "fail_at_step": Option(0, "int", doc="raise RuntimeError after this step (a plugin bug); 0 never", min=0),
        }}

    @hookimpl
    def sph_configure(self, case):
        self.accel = np.array(case.config["throwaway"]["accel"][: case.dim])
        self.fail_at_step = case.config["throwaway"]["fail_at_step"]

    @hookimpl
    def sph_accelerations(self, ctx, acc):
        acc += self.accel

    @hookimpl
    def sph_after_step(self, ctx):
        self.after_step_calls += 1
        ctx.stats(self)["after_step"] = self.after_step_calls
        if ctx.step == self.fail_at_step:
            raise RuntimeError("throwaway plugin failed on purpose")
'''

BAD_PLUGIN = '''
"""A throwaway sphcore plugin with a misspelt hook."""
from sphcore.api import hookimpl


class Misspelt:
    @hookimpl
    def sph_after_stepp(self, ctx):
        pass
'''

#: broken variants of a third-party plugin: (module source, what its error line must say)
BROKEN = {
    "bad_hook_name": (BAD_PLUGIN.replace("Misspelt", "Broken"), "sph_after_stepp"),
    "bad_argument": ('''
from sphcore.api import hookimpl


class Broken:
    @hookimpl
    def sph_after_step(self, simulation):
        pass
''', "simulation"),
    "import_error": ('''
import numpy_that_does_not_exist


class Broken:
    pass
''', "numpy_that_does_not_exist"),
    "option_error": ('''
from sphcore.api import hookimpl


class Broken:
    @hookimpl
    def sph_options(self):
        return {"broken": {"k": 1.0}}  # not an Option: a bug in the plugin
''', "sph_options"),
    "configure_crash": ('''
from sphcore.api import hookimpl


class Broken:
    @hookimpl
    def sph_configure(self, case):
        raise ZeroDivisionError("a bug in sph_configure")
''', "sph_configure"),
}

FREE_CASE = {
    "case": {"dim": 2},
    "domain": {"min": [-10.0, -10.0], "max": [10.0, 10.0]},
    "blocks": [{"min": [0.0, 0.0], "count": [3, 2], "kind": "sphere", "velocity": [0.25, -0.5]}],
    "particles": {"dx": 0.1},
    "physics": {"sph": False, "gravity": [0.0, 0.0]},
    "time": {"t_end": 0.5, "dt": 0.01},
    "plugins": {"use": ["throwaway"]},
    "throwaway": {"accel": [1.5, -2.0]},
}


def install(site: Path, module: str, source: str, dist: str, entry_points: str):
    """Write ``module.py`` and ``<dist>-0.1.dist-info`` (METADATA, entry_points.txt) into ``site``."""
    site.mkdir(parents=True, exist_ok=True)
    (site / f"{module}.py").write_text(textwrap.dedent(source))
    info = site / f"{dist.replace('-', '_')}-0.1.dist-info"
    info.mkdir()
    (info / "METADATA").write_text(f"Metadata-Version: 2.1\nName: {dist}\nVersion: 0.1\n")
    (info / "entry_points.txt").write_text(textwrap.dedent(entry_points))


@pytest.fixture
def site(tmp_path, monkeypatch):
    """A fresh directory on sys.path; entry points are re-read before and after the test."""
    path = tmp_path / "site"
    path.mkdir()
    monkeypatch.syspath_prepend(str(path))
    pluginhost.refresh()
    modules_before = set(sys.modules)
    yield path
    for name in set(sys.modules) - modules_before:
        if name.startswith("throwaway"):
            del sys.modules[name]
    monkeypatch.undo()
    pluginhost.refresh()


@pytest.fixture
def throwaway(site):
    install(site, "throwaway_sph", GOOD_PLUGIN, "throwaway-sph", "[sphcore]\nthrowaway = throwaway_sph:Throwaway\n")
    pluginhost.refresh()
    return site


@pytest.fixture
def misspelt(site):
    install(site, "throwaway_bad_sph", BAD_PLUGIN, "throwaway-bad-sph",
            "[sphcore]\nthrowaway_bad = throwaway_bad_sph:Misspelt\n")
    pluginhost.refresh()
    return site


def test_installed_plugin_is_described(throwaway, capsys):
    rows = {row["name"]: row for row in pluginhost.describe()}
    assert rows["throwaway"] == {
        "name": "throwaway", "dist": "throwaway-sph", "version": "0.1", "tables": ["throwaway"], "broken": "",
        "hooks": ["sph_accelerations", "sph_after_step", "sph_configure", "sph_options"],
    }
    assert cli.main(["plugins"]) == 0
    line = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("throwaway ")]
    assert len(line) == 1
    assert "throwaway-sph 0.1" in line[0] and "sph_accelerations" in line[0]


def test_plugin_is_gone_after_the_fixture(tmp_path):
    """The fixtures leave no trace: a later test sees only the plugins really installed."""
    assert "throwaway" not in pluginhost.available()
    assert "throwaway" not in pluginhost.option_schemas()


def test_plugin_acceleration_moves_free_particles(throwaway, tmp_path):
    case_dir = write_case(tmp_path / "free", FREE_CASE)
    summary = runner.run(case_dir, output=tmp_path / "out", quiet=True)
    assert summary["status"] == "completed", summary["message"]
    sim = summary.simulation
    assert sim.t == 0.5 and summary["steps"] == 50
    # no SPH: no neighbour search, no density, only the plugin's acceleration
    assert sim.counters["neighbour_search"] == 0 and sim.counters["continuity"] == 0
    start = by_id(make_sim(case_dir).state)
    end = by_id(sim.state)
    a, v0, t = np.array([1.5, -2.0]), np.array([0.25, -0.5]), sim.t
    np.testing.assert_allclose(end["pos"], start["pos"] + v0 * t + 0.5 * a * t * t, rtol=1e-12, atol=1e-12)
    np.testing.assert_allclose(end["vel"], np.broadcast_to(v0 + a * t, end["vel"].shape), rtol=1e-12, atol=1e-12)
    # sph_after_step fired once per step; the plugin's stats are in the summary under its name
    assert summary["throwaway"]["after_step"] == summary["steps"] == 50
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["throwaway"] == {"after_step": 50}
    # its acceleration may do work: the energy check is off, and the summary says which plugin
    assert summary["core"]["energy_check"].startswith("off") and "throwaway" in summary["core"]["energy_check"]


def test_unselected_plugin_does_nothing(throwaway, tmp_path):
    """Installed but not in plugins.use: its table is still validated, its hooks never run."""
    case_dir = write_case(tmp_path / "free", case_with(FREE_CASE, {"plugins.use": []}))
    sim = make_sim(case_dir)
    while not sim.done():
        sim.advance()
    assert np.all(sim.state.vel == np.array([0.25, -0.5]))  # no acceleration at all
    assert "throwaway" not in sim.ctx.all_stats()


def test_unknown_key_in_plugin_table(throwaway, tmp_path, capsys):
    case_dir = write_case(tmp_path / "free", case_with(FREE_CASE, {"throwaway": {"acel": [1.5, -2.0]}}))
    with pytest.raises(CaseError) as info:
        runner.load(case_dir)
    assert Path(info.value.file) == case_dir / "case.toml"
    assert info.value.key == "throwaway.acel"
    status = cli.main(["run", str(case_dir)])
    err = capsys.readouterr().err.strip()
    assert status == 2
    assert len(err.splitlines()) == 1 and str(case_dir / "case.toml") in err and "throwaway.acel" in err
    assert not (case_dir / "output").exists()


def test_wrong_type_in_plugin_table(throwaway, tmp_path):
    case_dir = write_case(tmp_path / "free", case_with(FREE_CASE, {"throwaway.accel": "up"}))
    with pytest.raises(CaseError) as info:
        runner.load(case_dir)
    assert info.value.key == "throwaway.accel"


def test_plugin_table_without_the_plugin_installed(tmp_path):
    case_dir = write_case(tmp_path / "free", case_with(FREE_CASE, {"plugins.use": []}))
    with pytest.raises(CaseError) as info:
        runner.load(case_dir)
    assert info.value.key == "throwaway"  # an unknown section, named


def test_plugin_listed_twice(throwaway, tmp_path):
    case_dir = write_case(tmp_path / "free", case_with(FREE_CASE, {"plugins.use": ["throwaway", "throwaway"]}))
    with pytest.raises(CaseError) as info:
        runner.load(case_dir)
    assert info.value.key == "plugins.use" and "twice" in str(info.value)


def test_each_run_gets_fresh_plugin_instances(throwaway, tmp_path):
    case_dir = write_case(tmp_path / "free", FREE_CASE)
    first = runner.run(case_dir, output=tmp_path / "a", quiet=True)
    second = runner.run(case_dir, output=tmp_path / "b", quiet=True)
    assert first["throwaway"]["after_step"] == second["throwaway"]["after_step"] == 50


def test_misspelt_hook_fails_at_start_up(misspelt, tmp_path, capsys):
    case_dir = write_case(tmp_path / "bad", case_with(FREE_CASE, {"plugins.use": ["throwaway_bad"], "throwaway": None}))
    with pytest.raises(PluginLoadError) as info:
        runner.run(case_dir, output=tmp_path / "out", quiet=True)
    assert "sph_after_stepp" in str(info.value)
    assert "plugin 'throwaway_bad'" in str(info.value)  # names the plugin by its entry-point name
    assert "throwaway-bad-sph" in str(info.value)  # and its distribution
    assert not (tmp_path / "out").exists()
    status = cli.main(["run", str(case_dir)])
    err = capsys.readouterr().err.strip()
    assert status == 2
    assert len(err.splitlines()) == 1 and "sph_after_stepp" in err
    assert not (case_dir / "output").exists()



def test_misspelt_plugin_spoils_no_other_run(misspelt, tmp_path):
    case_dir = write_case(tmp_path / "free", case_with(FREE_CASE, {"plugins.use": [], "throwaway": None}))
    summary = runner.run(case_dir, output=tmp_path / "out", quiet=True)
    assert summary["status"] == "completed"


def test_misspelt_plugin_is_listed_as_broken(misspelt, capsys):
    rows = {row["name"]: row for row in pluginhost.describe()}
    assert "sph_after_stepp" in rows["throwaway_bad"]["broken"] and rows["throwaway_bad"]["hooks"] == []
    assert cli.main(["plugins"]) == 0
    line = [ln for ln in capsys.readouterr().out.splitlines() if ln.startswith("throwaway_bad ")]
    assert len(line) == 1 and "BROKEN" in line[0] and "throwaway-bad-sph" in line[0]


@pytest.mark.parametrize("variant", sorted(BROKEN))
def test_broken_third_party_plugin_is_one_line_and_its_own_fault(site, tmp_path, capsys, variant):
    """Each way a third-party plugin can be broken: the case that selects it gets one line
    naming the plugin and its distribution (exit 2, nothing written); other cases run."""
    source, says = BROKEN[variant]
    install(site, "throwaway_broken", source, "throwaway-broken", "[sphcore]\nbroken = throwaway_broken:Broken\n")
    pluginhost.refresh()
    free = case_with(FREE_CASE, {"throwaway": None})
    case_dir = write_case(tmp_path / "uses", case_with(free, {"plugins.use": ["broken"]}))
    assert cli.main(["run", str(case_dir)]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1, err
    assert "'broken'" in err and "throwaway-broken" in err and says in err, err
    assert not (case_dir / "output").exists()
    assert cli.main(["check", str(case_dir)]) == 2
    other = write_case(tmp_path / "other", case_with(free, {"plugins.use": []}))
    assert cli.main(["run", str(other), "--output", str(tmp_path / "other_out")]) == 0


def test_summary_of_a_crashed_run_does_not_say_completed(throwaway, tmp_path):
    case_dir = write_case(tmp_path / "free", case_with(FREE_CASE, {"throwaway.fail_at_step": 3}))
    with pytest.raises(RuntimeError, match="on purpose"):
        runner.run(case_dir, output=tmp_path / "out", quiet=True)
    summary = json.loads((tmp_path / "out" / "summary.json").read_text())
    assert summary["t"] == pytest.approx(0.03)
    assert summary["status"] != "completed"


def test_a_run_imports_only_the_plugins_its_case_may_need(tmp_path):
    """runner.load imports the case's plugins and those named like its tables, not every
    installed one (start-up time); run in a fresh process so that nothing is imported yet."""
    import subprocess

    case_dir = write_case(tmp_path / "c", plugins=["reflective"], tables={"vtu": {"every_dt": 0.1}})
    code = ("import sys; from sphcore.run import runner; runner.load(sys.argv[1]); "
            "print(' '.join(sorted(m for m in sys.modules if m.startswith('sphcore_plugins.') and m.count('.') == 1)))")
    out = subprocess.run([sys.executable, "-c", code, str(case_dir)], capture_output=True, text=True, check=True)
    assert out.stdout.split() == ["sphcore_plugins.reflective", "sphcore_plugins.vtu"]


def test_an_unselected_plugins_table_is_still_validated(tmp_path):
    """A table no loaded plugin owns loads every installed plugin to find its owner: a bad
    key in an unselected plugin's table is refused, an unknown table lists every known one."""
    case_dir = write_case(tmp_path / "c", plugins=["reflective"], tables={"probes": {"evry_dt": 0.1}})
    with pytest.raises(CaseError, match="evry_dt"):
        runner.load(case_dir)
    case_dir = write_case(tmp_path / "d", plugins=["reflective"], tables={"probez": {"every_dt": 0.1}})
    with pytest.raises(CaseError, match=r"unknown section \(known: .*probes.*vtu"):
        runner.load(case_dir)


WALL_PLUGIN = '''
"""A throwaway wall model: a share of 1 at every particle, completed by a push along x."""
from numba import njit

from sphcore.api import hookimpl


@njit(inline="always")
def push(wall, i, dim, vel, rho_i, p_i, rho_ref, lam, gravity, a0, a1, a2, dr, b0, b1, b2, gam):
    return a0 + 2.5 * wall.share[i], a1, a2, dr


class PushWall:
    @hookimpl
    def sph_wall_terms(self, ctx, terms):
        terms.share[:] = 1.0

    @hookimpl
    def sph_wall_completion(self, dim):
        return push if COMPLETES else None


COMPLETES = True
'''


@pytest.fixture
def wall_plugins(site):
    install(site, "throwaway_wall_sph", WALL_PLUGIN, "throwaway-wall-sph",
            "[sphcore]\nthrowaway_wall = throwaway_wall_sph:PushWall\n")
    install(site, "throwaway_halfwall_sph", WALL_PLUGIN.replace("COMPLETES = True", "COMPLETES = False"),
            "throwaway-halfwall-sph", "[sphcore]\nthrowaway_halfwall = throwaway_halfwall_sph:PushWall\n")
    pluginhost.refresh()
    return site


@pytest.mark.slow
def test_a_wall_model_plugin_completes_the_pair_sums_with_its_own_function(wall_plugins, tmp_path):
    """The core compiles a plugin's wall completion into its pair loop: a completion that
    adds 2.5 share_i to the x acceleration moves every particle's acceleration by exactly
    2.5 m/s^2 (the pair sums and gravity unchanged); a plugin with wall terms and no
    completion, or two different completions, is refused before the run starts."""
    from sphcore.testing import tiny_case

    acc = {}
    for use in (["reflective"], ["reflective", "throwaway_wall"]):
        case_dir = write_case(tmp_path / "_".join(use), case_with(tiny_case(), {"plugins.use": use}))
        sim = make_sim(case_dir)
        a, drho = np.zeros((sim.state.n, 2)), np.zeros(sim.state.n)
        sim.forces.evaluate(a, drho)  # the rates of the initial particles
        acc[len(use)] = a
    np.testing.assert_allclose(acc[2][:, 0] - acc[1][:, 0], 2.5, rtol=0, atol=1e-9)
    np.testing.assert_array_equal(acc[2][:, 1], acc[1][:, 1])
    for use, said in ((["throwaway_halfwall"], "supply none"), (["throwaway_wall", "wall_integral"], "push")):
        case_dir = write_case(tmp_path / "_".join(use), case_with(tiny_case(), {"plugins.use": use}))
        with pytest.raises(CaseError, match="sph_wall_completion") as err:
            make_sim(case_dir)
        assert said in str(err.value)
