"""The ``ghost`` plugin in the host: options, configuration errors, the sources it hands
the core (current particle order, 3D), and the run summary."""

from __future__ import annotations

import numpy as np
import pytest
from conftest import by_id, make_sim, write_case

from sphcore.errors import CaseError
from sphcore.physics.kernels import SUPPORT
from sphcore.plugin import pluginhost
from sphcore.run import runner
from sphcore.testing import case_with
from sphcore_plugins.ghost import GhostPlugin


def box_case(tmp_path, dim=2, extra=None, n=6):
    """A box n dx wide and 2 n dx high, its lower half water; ``extra``: changes (case_with)."""
    lo = [0.0] * dim
    hi = [n * 0.02] * (dim - 1) + [2 * n * 0.02]
    case = {
        "case": {"dim": dim},
        "domain": {"min": lo, "max": hi},
        "blocks": [{"min": lo, "count": [n] * dim}],
        "particles": {"dx": 0.02},
        "time": {"t_end": 0.01},
        "plugins": {"use": ["ghost"]},
    }
    return write_case(tmp_path, case_with(case, extra or {}))


def test_entry_point_and_options_are_declared():
    info = pluginhost.available()["ghost"]
    assert info.cls is GhostPlugin and not info.error
    schema = GhostPlugin().sph_options()["ghost"]
    assert schema["wall"].default == "free_slip" and schema["wall"].choices == ("free_slip", "no_slip")
    assert schema["hydrostatic"].default is True and schema["hydrostatic"].kind == "bool"
    assert all(opt.doc for opt in schema.values())


@pytest.mark.parametrize("extra, key", [
    ({"ghost.wall": "sticky"}, "ghost.wall"),
    ({"ghost.hydrostatic": 1}, "ghost.hydrostatic"),
    ({"ghost.layers": 3}, "ghost.layers"),
    ({"physics.sph": False}, "plugins.use"),
])
def test_bad_options_name_the_key(tmp_path, extra, key):
    with pytest.raises(CaseError) as e:
        runner.load(box_case(tmp_path, extra=extra))
    assert e.value.key == key and str(e.value.file).endswith("case.toml")


def test_sources_follow_the_current_particle_order(tmp_path):
    sim = make_sim(box_case(tmp_path, extra={"ghost.wall": "no_slip"}))
    sim.state.vel[:] = np.random.default_rng(0).normal(size=sim.state.vel.shape)
    plugin = sim.pm.get_plugin("ghost")
    sim.state.permute(np.random.default_rng(1).permutation(sim.state.n))  # as a reorder does
    src = plugin.sph_extra_sources(sim.ctx)
    i = plugin.mirror.source_index
    st = sim.state
    d = sim.case.planes.distances(st.pos[i])
    # each ghost is the image of the particle now at row i, across a plane it is near
    dist_ghost = np.linalg.norm(src.pos - st.pos[i], axis=1)
    assert np.all(dist_ghost <= 2 * SUPPORT * sim.params.h * np.sqrt(2)) and np.all(dist_ghost > 0)
    np.testing.assert_array_equal(src.vel, -st.vel[i])  # no slip
    np.testing.assert_array_equal(src.m, st.m[i])
    assert (d.min(axis=1) > 0).all() and (sim.case.planes.distances(src.pos).min(axis=1) < 0).all()


def test_3d_box_runs_and_counts_face_edge_and_vertex_images(tmp_path):
    n = 6  # 6 x 6 x 6 particles, dx = 0.02 m, h = 1.3 dx: support 2.6 dx spans 3 layers
    summary = runner.run(box_case(tmp_path / "b3", dim=3, n=n), quiet=True)
    assert summary["status"] == "completed", summary["message"]
    # 5 walls touch the water (the lid is far): per wall face 3 layers x n x n images,
    # per wall-wall edge (4 floor edges + 4 vertical edges) 3 x 3 x n, per floor vertex 27
    expect = 5 * 3 * n * n + 8 * 9 * n + 4 * 27
    assert summary["ghost"]["ghosts_last"] == expect
    sim = summary.simulation
    assert sim.counters["extra_sources"] == sim.counters["rates"] > 0
    # a few steps of water at rest: nothing moved through a wall
    assert sim.case.planes.distances(sim.state.pos).min() > 0


def test_summary_reports_ghost_counts(tmp_path):
    summary = runner.run(box_case(tmp_path / "s"), quiet=True)
    assert summary["ghost"]["ghosts_max"] >= summary["ghost"]["ghosts_last"] > 0
    assert summary["ghost"]["ghost_reallocations"] >= 1


def test_switching_wall_treatment_is_one_line(tmp_path):
    # the same case with use = ["ghost"], ["reflective"] and both validates unchanged:
    # the [ghost] table is accepted (and ignored) when ghost is not selected
    case_dir = box_case(tmp_path / "sw", extra={"ghost.wall": "no_slip"})
    for use in (["ghost"], ["reflective"], ["ghost", "reflective"]):
        info = pluginhost.available().get("reflective")
        if "reflective" in use and (info is None or info.cls is None):
            continue
        case, pm = runner.load(case_dir, [f"plugins.use={use!r}".replace("'", '"')])
        assert case.config["plugins"]["use"] == use
        assert (pm.get_plugin("ghost") is not None) == ("ghost" in use)


def test_particle_ids_are_untouched(tmp_path):
    sim = make_sim(box_case(tmp_path))
    before = by_id(sim.state)
    sim.advance()
    after = by_id(sim.state)
    np.testing.assert_array_equal(before["id"], after["id"])
    assert sim.state.n == before["id"].size  # ghosts never join the state
