"""The thread count of a run: chosen from measured step times (sphcore.run.threads), and
changing it between steps leaves every bit of the result as it was."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from conftest import by_id, write_case

from sphcore.run import runner, threads
from sphcore.run.threads import ThreadTuner, candidates
from sphcore.testing import case_with

# a 2D dam break of 2,600 particles (above the pair loop's serial limit, PAIRS_PARALLEL_MIN
# = 1,000: its slabs run in parallel) with the wall model, density diffusion and artificial
# viscosity; DAM_2D_BIG has 21,000 (above PARALLEL_MIN = 20,000: the element-wise passes,
# the wall model's and the reflective walls' kernels run their parallel builds too)
DAM_2D = {
    "case": {"dim": 2},
    "domain": {"min": [0.0, 0.0], "max": [0.8, 0.5]},
    "blocks": [{"min": [0.0, 0.0], "count": [40, 65]}],
    "particles": {"dx": 0.005},
    "density_diffusion": {"delta": 0.1, "hydrostatic": True},
    "time": {"t_end": 0.004},
    "plugins": {"use": []},
}

DAM_3D = {
    "case": {"dim": 3},
    "domain": {"min": [0.0, 0.0, 0.0], "max": [0.3, 0.1, 0.2]},
    "blocks": [{"min": [0.0, 0.0, 0.0], "count": [10, 14, 16]}],
    "particles": {"dx": 0.007},
    "time": {"t_end": 0.003},
    "plugins": {"use": []},
}


DAM_2D_BIG = case_with(DAM_2D, {"domain.max": [1.5, 1.0], "blocks[0].count": [150, 140], "time.t_end": 0.0004})


class Alternate(ThreadTuner):
    """Switches between numba's full count and one thread after every step."""

    def __init__(self, most):
        super().__init__(most, adapt=False)
        self.counts = [most, 1]

    def after_step(self, seconds):
        self.steps[self.current] = self.steps.get(self.current, 0) + 1
        self.current = self.counts[1] if self.current == self.counts[0] else self.counts[0]
        return self.current


@pytest.mark.parametrize("case, plugins", [
    (DAM_2D, ["reflective", "wall_integral"]),
    (DAM_2D, ["ghost", "reflective"]),
    (DAM_3D, ["reflective", "wall_integral"]),
    (DAM_2D_BIG, ["reflective", "wall_integral"]),
])
def test_changing_the_thread_count_between_steps_keeps_the_bits(tmp_path, monkeypatch, case, plugins):
    most = numba.config.NUMBA_NUM_THREADS
    if most < 2:
        pytest.skip("numba is limited to one thread here (NUMBA_NUM_THREADS)")
    case_dir = write_case(tmp_path / "case", case_with(case, {"plugins.use": plugins}))
    one = runner.run(case_dir, output=tmp_path / "one", overrides=["parallel.threads=1"], quiet=True)
    monkeypatch.setattr(threads, "tuner_for", lambda config: Alternate(most))
    both = runner.run(case_dir, output=tmp_path / "both", quiet=True)
    assert one["status"] == both["status"] == "completed"
    assert one["steps"] == both["steps"] >= 6
    assert both["threads"]["steps_per_count"][str(most)] >= 3 and both["threads"]["steps_per_count"]["1"] >= 3
    sa, sb = by_id(one.simulation.state), by_id(both.simulation.state)
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
    used = drive(tuner, {2: 0.002, 1: 0.001}, 3000)  # one thread is faster (a loaded machine)
    assert tuner.counts == [2, 1]
    assert len(tuner.probes) >= 2 and all(min(p, key=p.get) == 1 for p in tuner.probes)
    assert used[-1] == 1 and used.count(1) / len(used) > 0.9
    # the load goes away: two threads are faster now; the tuner follows at its next probe,
    # at most MAX_USE_S of wall time later
    used = drive(tuner, {2: 0.0005, 1: 0.001}, 100_000)
    assert used[-1] == 2 and used[-50_000:].count(2) / 50_000 > 0.95


def test_windows_last_window_s_for_every_count_and_warm_up_is_not_timed():
    tuner = ThreadTuner(4, window_s=0.05, min_steps=4)
    assert tuner.counts == [4, 2, 1] == candidates(4)
    drive(tuner, {4: 10.0, 2: 10.0, 1: 10.0}, 3)  # slow first steps (compilation): ignored
    used = drive(tuner, {4: 0.001, 2: 0.002, 1: 0.004}, 200)
    assert tuner.probes[0] == pytest.approx({4: 0.001, 2: 0.002, 1: 0.004})
    first = used[:used.index(1) + 13]  # windows 4, 2, 1 (and on): 50, 25 and 13 steps of 0.05 s
    assert first.count(4) == 50 and first.count(2) == 25 and first.count(1) == 13


@pytest.mark.parametrize("most, speedup", [(2, 1.6), (16, 10.0)])
def test_probing_costs_at_most_its_budget_on_any_number_of_threads(most, speedup):
    """Quiet machine: the most threads are fastest; what the run loses to probing the
    slower counts stays within BUDGET (2 %) plus the first probes."""
    t_most = 1e-3
    cost = {most: t_most, max(most // 2, 1): t_most * speedup / (1 + speedup / 2), 1: t_most * speedup}
    tuner = ThreadTuner(most)
    steps = 300_000  # 300 s of wall time at the best count
    spent = sum(cost[c] for c in drive(tuner, cost, steps))
    assert spent / (steps * t_most) - 1.0 < threads.BUDGET + 0.005
    assert tuner.chosen == most


def test_one_thread_or_no_adaptation_never_changes_the_count():
    for tuner in (ThreadTuner(1), ThreadTuner(2, adapt=False)):
        assert not tuner.active
        used = drive(tuner, {1: 0.001, 2: 0.1}, 500)
        assert set(used) == {tuner.counts[0]} and tuner.probes == []


def test_parallel_threads_is_a_case_option(tmp_path):
    case_dir = write_case(tmp_path / "case", case_with(DAM_2D, {"plugins.use": ["reflective"], "time.t_end": 0.0005}))
    summary = runner.run(case_dir, output=tmp_path / "out", overrides=["parallel.threads=1"], quiet=True)
    assert summary["threads"]["counts"] == [1] and not summary["threads"]["adaptive"]
    assert summary["threads"]["steps_per_count"] == {"1": summary["steps"]}
    assert numba.get_num_threads() == numba.config.NUMBA_NUM_THREADS  # restored after the run


def test_counts_within_the_margin_keep_the_last_choice():
    tuner = ThreadTuner(2, window_s=0.01)
    used = drive(tuner, {2: 0.00100, 1: 0.00099}, 20_000)  # 1 % apart: timing noise
    assert len(tuner.probes) >= 2 and used[-1] == 2 and used.count(1) / len(used) < 0.1
    used = drive(tuner, {2: 0.00100, 1: 0.00090}, 100_000)  # 10 % apart
    assert used[-1] == 1


def test_a_restart_may_change_the_thread_settings_and_keeps_the_bits(tmp_path):
    """parallel.threads and parallel.adapt may differ on --restart (resume.MAY_DIFFER): the
    result is the same bits for any thread count."""
    dt = 2.0**-15
    case = case_with(DAM_2D, {"plugins.use": ["reflective", "wall_integral"], "time.t_end": 40 * dt, "time.dt": dt})
    case_dir = write_case(tmp_path / "case", case)
    full = runner.run(case_dir, output=tmp_path / "full", quiet=True)
    part = runner.run(case_dir, output=tmp_path / "part", t_end=15 * dt, quiet=True)
    rest = runner.run(case_dir, output=tmp_path / "part", restart=True, quiet=True,
                      overrides=["parallel.threads=1", "parallel.adapt=false"])
    assert full["status"] == part["status"] == rest["status"] == "completed"
    assert rest["threads"]["counts"] == [1] and rest["steps"] == full["steps"] == 40
    sa, sb = by_id(full.simulation.state), by_id(rest.simulation.state)
    for name in sa:
        assert np.array_equal(sa[name], sb[name]), name


@pytest.mark.parametrize("given", [None, "0", "passive"])
def test_openmp_wait_defaults_are_set_before_the_first_kernel_and_a_users_setting_wins(given):
    """sphcore.jit.prepare sets a passive wait with a short spin before numba starts its
    threads, unless the user set them; importing sphcore (or its run package) sets nothing."""
    import os
    import subprocess
    import sys

    env = {k: v for k, v in os.environ.items() if k not in ("GOMP_SPINCOUNT", "OMP_WAIT_POLICY")}
    if given is not None:
        env["GOMP_SPINCOUNT"] = env["OMP_WAIT_POLICY"] = given
    code = ("import os, sphcore, sphcore.run.runner, sphcore.api; from sphcore.jit import prepare; "
            "print(os.environ.get('GOMP_SPINCOUNT'), os.environ.get('OMP_WAIT_POLICY')); prepare(); "
            "print(os.environ['GOMP_SPINCOUNT'], os.environ['OMP_WAIT_POLICY'])")
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True)
    before, after = out.stdout.splitlines()
    assert before.split() == [str(given), str(given)]
    assert after.split() == ([given, given] if given else ["1000", "passive"])
