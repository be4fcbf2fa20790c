"""The thread count of a run: chosen from measured step times (sphcore.threads), and
changing it between steps leaves every bit of the result as it was."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from conftest import by_id, write_case

from sphcore import runner, threads
from sphcore.threads import ThreadTuner, candidates

# a 2D dam break of 2,600 particles (above the pair loop's serial limit, 2,048) with the
# wall model, density diffusion and artificial viscosity: every parallel kernel of a step
DAM_2D = """
[case]
dim = 2
[domain]
min = [0.0, 0.0]
max = [0.8, 0.5]
[[blocks]]
min = [0.0, 0.0]
count = [40, 65]
[particles]
dx = 0.005
[density_diffusion]
delta = 0.1
hydrostatic = true
[time]
t_end = 0.004
[plugins]
use = {plugins}
"""

DAM_3D = """
[case]
dim = 3
[domain]
min = [0.0, 0.0, 0.0]
max = [0.3, 0.1, 0.2]
[[blocks]]
min = [0.0, 0.0, 0.0]
count = [10, 14, 16]
[particles]
dx = 0.007
[time]
t_end = 0.003
[plugins]
use = {plugins}
"""


class Alternate(ThreadTuner):
    """Switches between numba's full count and one thread after every step."""

    def __init__(self, most):
        super().__init__(most, adapt=False)
        self.counts = [most, 1]

    def after_step(self, seconds):
        self.steps[self.current] = self.steps.get(self.current, 0) + 1
        self.current = self.counts[1] if self.current == self.counts[0] else self.counts[0]
        return self.current


@pytest.mark.parametrize("text, plugins", [
    (DAM_2D, ["reflective", "wall_integral"]),
    (DAM_2D, ["ghost", "reflective"]),
    (DAM_3D, ["reflective", "wall_integral"]),
])
def test_changing_the_thread_count_between_steps_keeps_the_bits(tmp_path, monkeypatch, text, plugins):
    most = numba.config.NUMBA_NUM_THREADS
    if most < 2:
        pytest.skip("numba is limited to one thread here (NUMBA_NUM_THREADS)")
    case_dir = write_case(tmp_path / "case", text.format(plugins=str(plugins).replace("'", '"')))
    one = runner.run(case_dir, output=tmp_path / "one", overrides=["parallel.threads=1"], quiet=True)
    monkeypatch.setattr(threads, "tuner_for", lambda config: Alternate(most))
    both = runner.run(case_dir, output=tmp_path / "both", quiet=True)
    assert one["status"] == both["status"] == "completed"
    assert one["steps"] == both["steps"] >= 10
    assert both["threads"]["steps_per_count"][str(most)] >= 5 and both["threads"]["steps_per_count"]["1"] >= 5
    sa, sb = by_id(one["_sim"].state), by_id(both["_sim"].state)
    assert not np.array_equal(sa["vel"], 0.0 * sa["vel"])  # the water moved
    for name in sa:
        assert np.array_equal(sa[name], sb[name]), name


def drive(tuner, cost, steps):
    """Step a tuner with a synthetic cost per step (s) for each thread count; returns the
    counts used, step by step."""
    used = []
    for _ in range(steps):
        used.append(tuner.current)
        tuner.after_step(cost[tuner.current])
    return used


def test_the_tuner_uses_the_faster_count_and_probes_again():
    tuner = ThreadTuner(2, window_s=0.01)
    used = drive(tuner, {2: 0.002, 1: 0.001}, 2000)  # one thread is faster (a loaded machine)
    assert tuner.counts == [2, 1]
    assert tuner.probes and all(min(p, key=p.get) == 1 for p in tuner.probes)
    assert len(tuner.probes) >= 3  # it probes again and again
    assert used[-1] == 1 and used.count(1) / len(used) > 0.9
    # the load goes away: two threads are faster now, and the tuner follows within one cycle
    used = drive(tuner, {2: 0.0005, 1: 0.001}, 2000)
    assert used[-1] == 2 and used[1000:].count(2) / 1000 > 0.9


def test_windows_last_about_window_s_and_warm_up_is_not_timed():
    tuner = ThreadTuner(4, window_s=0.05, min_steps=4)
    assert tuner.counts == [4, 2, 1] == candidates(4)
    drive(tuner, {4: 10.0, 2: 10.0, 1: 10.0}, 3)  # slow first steps (compilation): ignored
    assert tuner.probes == []
    drive(tuner, {4: 0.001, 2: 0.002, 1: 0.004}, 300)
    assert tuner._window == 50 and tuner.probes[0] == pytest.approx({4: 0.001, 2: 0.002, 1: 0.004})
    tiny = ThreadTuner(2, window_s=1e-6)
    drive(tiny, {2: 1.0, 1: 1.0}, 4)
    assert tiny._window == 4  # min_steps


def test_one_thread_or_no_adaptation_never_changes_the_count():
    for tuner in (ThreadTuner(1), ThreadTuner(2, adapt=False)):
        assert not tuner.active
        used = drive(tuner, {1: 0.001, 2: 0.1}, 500)
        assert set(used) == {tuner.counts[0]} and tuner.probes == []


def test_parallel_threads_is_a_case_option(tmp_path):
    case_dir = write_case(tmp_path / "case", DAM_2D.format(plugins='["reflective"]').replace("0.004", "0.0005"))
    summary = runner.run(case_dir, output=tmp_path / "out", overrides=["parallel.threads=1"], quiet=True)
    assert summary["threads"]["counts"] == [1] and not summary["threads"]["adaptive"]
    assert summary["threads"]["steps_per_count"] == {"1": summary["steps"]}
    assert numba.get_num_threads() == numba.config.NUMBA_NUM_THREADS  # restored after the run


def test_counts_within_the_margin_keep_the_last_choice():
    tuner = ThreadTuner(2, window_s=0.01)
    used = drive(tuner, {2: 0.00100, 1: 0.00099}, 3000)  # 1 % apart: timing noise
    assert len(tuner.probes) >= 2 and used[-1] == 2 and used.count(1) / len(used) < 0.1
    used = drive(tuner, {2: 0.00100, 1: 0.00090}, 3000)  # 10 % apart
    assert used[-1] == 1
