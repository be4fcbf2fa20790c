"""The ``reflective`` plugin through pluggy: options, configuration, the step hook, summary."""

from importlib.metadata import entry_points
from types import SimpleNamespace

import numpy as np
import pluggy
import pytest

from sphcore.case.options import validate_table
from sphcore.errors import CaseError
from sphcore.geometry.planes import Planes
from sphcore.physics.particles import FLUID, lattice, make_block
from sphcore.plugin import hookspecs
from sphcore.plugin.context import RunContext
from sphcore.run.state import RunState
from sphcore_plugins.reflective import ReflectivePlugin
from sphcore_plugins.reflective.entry import outside


def manager():
    pm = pluggy.PluginManager(hookspecs.PROJECT)
    pm.add_hookspecs(hookspecs)
    plugin = ReflectivePlugin()
    pm.register(plugin, name="reflective")
    pm.check_pending()  # every hookimpl matches a hookspec
    return pm, plugin


def schema(pm):
    (tables,) = pm.hook.sph_options()
    return tables["reflective"]


def make_case(pm, table, planes):
    """The part of a validated case the plugin reads (its table, the planes, the file);
    planes alone may bound no region here, which a full case would refuse."""
    cfg = {"reflective": validate_table(schema(pm), table, "case.toml", "reflective"), "time": {"t_end": 1.0}}
    return SimpleNamespace(config=cfg, planes=planes, file="case.toml")


def make_sim(case, pos, radius):
    """A real run context of those particles (no Simulation: the hooks are called directly)."""
    state = make_block(pos, np.zeros(pos.shape[1]), 1000.0, 2 * radius, radius, FLUID)
    return RunContext(case, None, RunState(state, 1.0), plugin_name=lambda plugin: "reflective")


def test_entry_point_loads_the_plugin():
    (ep,) = [e for e in entry_points(group="sphcore") if e.name == "reflective"]
    assert ep.load() is ReflectivePlugin


def test_options_defaults_and_bounds():
    pm, _ = manager()
    opts = schema(pm)
    assert validate_table(opts, {}, "c.toml", "reflective") == {
        "cr": 1.0, "max_reflections": 1000, "velocity": "contact"}
    ok = validate_table(opts, {"cr": 0, "velocity": "end"}, "c.toml", "reflective")
    assert ok["cr"] == 0.0 and isinstance(ok["cr"], float)
    for bad in ({"cr": 1.5}, {"cr": -0.1}, {"max_reflections": 0}, {"max_reflections": 2.5},
                {"velocity": "middle"}, {"restitution": 0.5}):
        with pytest.raises(CaseError):
            validate_table(opts, bad, "c.toml", "reflective")
    assert all(o.doc for o in opts.values())


def test_configure_needs_walls():
    pm, _ = manager()
    with pytest.raises(CaseError, match="needs walls"):
        pm.hook.sph_configure(case=make_case(pm, {}, None))


def test_setup_rejects_a_particle_outside():
    pm, _ = manager()
    case = make_case(pm, {}, Planes.box([0, 0], [1, 1]))
    pm.hook.sph_configure(case=case)
    pm.hook.sph_setup(ctx=make_sim(case, lattice([0, 0], [1, 1], 0.1), 0.05))  # touching: fine
    with pytest.raises(CaseError, match="overlaps a wall"):
        pm.hook.sph_setup(ctx=make_sim(case, np.array([[0.5, 0.5], [0.5, 0.04]]), 0.05))


def test_step_hook_reflects_counts_and_survives_reordering():
    pm, plugin = manager()
    planes = Planes.box([0, 0, 0], [1, 1, 1])
    case = make_case(pm, {"cr": 0.5, "max_reflections": 3}, planes)
    pm.hook.sph_configure(case=case)
    r = 0.025
    pos0 = lattice([0, 0, 0], [1, 1, 1], 2 * r)
    sim = make_sim(case, pos0, r)
    pm.hook.sph_setup(ctx=sim)
    rng = np.random.default_rng(0)
    total_hit = total_guard = 0
    for step in range(5):
        n = len(pos0)
        vel = rng.standard_normal((n, 3)) * 10.0 ** rng.uniform(-2, 2, (n, 1))
        acc = np.tile([0.0, -9.81, 0.0], (n, 1))
        dt = 0.05
        pos = pos0 + dt * (vel + dt / 2 * acc)
        out = outside(pos, r, planes)
        pos_before, acc_before, pos0_before = pos.copy(), acc.copy(), pos0.copy()
        pm.hook.sph_after_integrate(ctx=sim, pos0=pos0, pos=pos, vel=vel, acc=acc, dt=dt)
        assert np.array_equal(pos0, pos0_before) and np.array_equal(acc, acc_before)
        assert not outside(pos, r, planes).any()
        assert np.array_equal(pos[~out], pos_before[~out])
        total_hit += int(out.sum())
        total_guard += int(np.count_nonzero(plugin._guarded))
        stats = sim.stats("reflective")
        assert stats["reflected_particle_steps"] == total_hit and stats["guard_returns"] == total_guard
        # between steps the core may reorder the particles and change their number
        keep = rng.permutation(n)[: n - 7 * (step % 2)]
        pos0 = np.ascontiguousarray(pos[keep])
        sim.state.radius = np.ascontiguousarray(sim.state.radius[keep])
    assert total_hit > 0 and total_guard > 0  # max_reflections = 3 needs the guard
    summary = sim.all_stats()["reflective"]  # what the run summary gets under "reflective"
    assert summary["guard_returns"] == total_guard and summary["reflected_particle_steps"] == total_hit
    assert summary["reflection_events"] >= total_hit


def test_end_point_velocity_option():
    pm, plugin = manager()
    floor = Planes.from_lists([[0.0, 1.0]], [[0.0, 0.0]])
    res = {}
    for mode in ("contact", "end"):
        plugin.__init__()
        case = make_case(pm, {"cr": 1.0, "velocity": mode}, floor)
        pm.hook.sph_configure(case=case)
        sim = make_sim(case, np.array([[0.0, 0.1]]), 0.05)
        pos0, vel, acc = np.array([[0.0, 0.06]]), np.array([[0.0, -2.0]]), np.array([[0.0, -9.81]])
        pos = pos0 + 0.01 * (vel + 0.005 * acc)
        v_end = vel + 0.01 * acc
        pm.hook.sph_after_integrate(ctx=sim, pos0=pos0, pos=pos, vel=v_end, acc=acc, dt=0.01)
        res[mode] = v_end[0, 1]
    assert res["end"] == pytest.approx(2.0981)  # Eq. 2 at the end point: -(-2.0981)
    assert res["contact"] < res["end"]  # gravity's work between contact and mirror point
