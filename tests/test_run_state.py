"""The run state as one object: a snapshot put back replays the same steps to the same bits,
and a checkpoint's payload read back is the same state."""

from __future__ import annotations

import numpy as np
from conftest import by_id, make_sim, write_case
from core_cases import good

from sphcore.run.state import RunState
from sphcore.testing import case_with

# a dam-break column with walls, kept pair lists, density diffusion and a plugin that
# keeps figures: every part of the state changes from step to step
CASE = case_with(good(), {"plugins.use": ["reflective", "wall_integral", "front_gauge"], "time.t_end": 0.05,
                          "density_diffusion.delta": 0.1, "neighbours": {"skin": 0.3, "sort_every": 5}})


def _steps(sim, n):
    for _ in range(n):
        sim.advance()
    return by_id(sim.state), sim.run.clock.t, dict(sim.counters), sim.ctx.all_stats()


def test_a_snapshot_put_back_replays_the_same_steps_bit_for_bit(tmp_path):
    """As a restart does, the restored run rebuilds its pair list from the snapshot's anchor
    and sorts the particles once more: the same bits, one build and one reorder more."""
    sim = make_sim(write_case(tmp_path / "case", CASE))
    _steps(sim, 7)  # mid-run: rates current, a pair list kept, particles reordered once
    snap = sim.snapshot()
    first = _steps(sim, 13)
    sim.restore(snap)
    second = _steps(sim, 13)
    for name in first[0]:
        assert np.array_equal(first[0][name], second[0][name]), name
    assert first[1] == second[1] and first[3] == second[3]  # the clock, every plugin's figures
    extra = {k: second[2][k] - first[2].get(k, 0) for k in second[2] if second[2][k] != first[2].get(k, 0)}
    assert extra == {"pair_list_builds": 1, "reorder": 1, "eos": 1}


def test_a_snapshot_shares_nothing_with_the_live_state(tmp_path):
    sim = make_sim(write_case(tmp_path / "case", CASE))
    _steps(sim, 3)
    snap = sim.snapshot()
    before = {k: v.copy() for k, v in snap.particles.items()}
    _steps(sim, 5)
    assert all(np.array_equal(before[k], snap.particles[k]) for k in before)
    assert snap.clock.step == 3 and sim.run.clock.step == 8


def test_a_checkpoint_payload_read_back_is_the_same_state(tmp_path):
    sim = make_sim(write_case(tmp_path / "case", CASE))
    _steps(sim, 9)
    meta, arrays = sim.run.payload()
    again = RunState(sim.state.__class__(**{n: a.copy() for n, a in sim.state.arrays()}), sim.run.clock.t_end)
    again.load_payload(meta, {k: np.array(v) for k, v in arrays.items()})
    assert again.clock == sim.run.clock
    assert np.array_equal(again.rates.acc, sim.run.rates.acc) and again.rates.fresh == sim.run.rates.fresh
    assert again.stats == sim.run.stats and again.counters == sim.run.counters
    assert np.array_equal(again.anchor(), sim.run.anchor())
    for (name, a), (_, b) in zip(again.particles.arrays(), sim.state.arrays()):
        assert np.array_equal(a, b), name
