"""The output schedule shared by the writers: every_dt, every_steps, step 0, final frame."""

from types import SimpleNamespace

import pytest

from sphcore.errors import CaseError
from sphcore.io.schedule import DEFAULT_EVERY_DT, Schedule, schedule_options


def fired(schedule, times, final_at_end=True):
    """Steps at which ``schedule`` fires for a run through ``times`` (t of step 0, 1, ...)."""
    out = []
    for step, t in enumerate(times):
        if schedule.due(t, step, final=False):
            out.append(step)
    if final_at_end and schedule.due(times[-1], len(times) - 1, final=True):
        out.append(len(times) - 1)
    return out


def accumulated(dt, n):
    """t after each of n steps of dt, summed the way an integrator does it (with round-off)."""
    t, out = 0.0, [0.0]
    for _ in range(n):
        t += dt
        out.append(t)
    return out


def test_every_dt_survives_float_accumulation():
    # 0.001 s steps summed 10 000 times: t drifts off the exact multiples of 0.01 by
    # round-off, yet every tenth step must fire, never the ninth or eleventh.
    times = accumulated(0.001, 10_000)
    steps = fired(Schedule(every_dt=0.01), times)
    assert steps == list(range(0, 10_001, 10))


def test_every_dt_over_a_long_run_of_small_steps():
    # 1e5 steps of 1e-5 s (a typical SPH step): still exactly every hundredth step
    times = accumulated(1e-5, 100_000)
    assert fired(Schedule(every_dt=1e-3), times) == list(range(0, 100_001, 100))


def test_every_dt_with_steps_that_do_not_divide_it():
    # dt = 0.003 s, every_dt = 0.01 s: the first step at or past each multiple fires
    times = accumulated(0.003, 40)
    expected = [0] + [next(i for i, t in enumerate(times) if t >= k * 0.01 - 1e-14) for k in range(1, 13)]
    steps = fired(Schedule(every_dt=0.01), times, final_at_end=False)
    assert steps == expected
    assert [round(times[s], 9) for s in steps[1:4]] == [0.012, 0.021, 0.030]


def test_a_long_step_writes_one_frame_and_skips_ahead():
    s = Schedule(every_dt=0.01)
    assert s.due(0.0, 0)
    assert s.due(0.035, 1)  # crossed 0.01, 0.02 and 0.03: one frame
    assert not s.due(0.039, 2)
    assert s.due(0.04, 3)


def test_every_steps_and_final_frame_not_duplicated():
    times = accumulated(0.001, 20)
    assert fired(Schedule(every_steps=5), times) == [0, 5, 10, 15, 20]  # step 20 not twice
    assert fired(Schedule(every_steps=6), times) == [0, 6, 12, 18, 20]  # final added


def test_final_call_repeated_at_the_same_step_fires_once():
    s = Schedule(every_dt=0.01)
    assert s.due(0.0, 0)
    assert s.due(0.005, 1, final=True)
    assert not s.due(0.005, 1, final=True)
    assert s.frames == 2


def test_final_frame_does_not_shift_the_next_multiple():
    # a final frame between multiples (e.g. written on an instability) must not move the count
    s = Schedule(every_dt=0.01)
    s.due(0.0, 0)
    s.due(0.005, 1, final=True)
    assert s.due(0.01, 2)


def test_resume_counts_frames_on_disk():
    s = Schedule(every_dt=0.01)
    s.resume(0.03, 30)
    assert not s.due(0.03, 30)  # restart at the step of the last frame: not again
    assert not s.due(0.035, 31)
    assert s.due(0.04, 32)


def test_defaults_and_options():
    assert Schedule().every_dt == DEFAULT_EVERY_DT
    opts = schedule_options("frame")
    assert set(opts) == {"every_dt", "every_steps"}
    assert opts["every_dt"].unit == "s"
    assert "0.01" in opts["every_dt"].doc


def test_both_set_is_a_case_error_naming_file_and_key():
    case = SimpleNamespace(file="/runs/dam/case.toml", config={"vtu": {"every_dt": 0.01, "every_steps": 5}})
    with pytest.raises(CaseError) as err:
        Schedule.from_config(case, "vtu")
    assert err.value.file == "/runs/dam/case.toml"
    assert err.value.key.startswith("vtu.every_")
    assert "only one" in str(err.value)


def test_from_config_reads_either_key():
    case = SimpleNamespace(file="case.toml", config={"netcdf": {"every_dt": None, "every_steps": 7}})
    s = Schedule.from_config(case, "netcdf")
    assert (s.every_dt, s.every_steps) == (None, 7)
    case.config["netcdf"] = {"every_dt": None, "every_steps": None}
    assert Schedule.from_config(case, "netcdf").every_dt == DEFAULT_EVERY_DT


@pytest.mark.parametrize("kwargs", [{"every_dt": 0.0}, {"every_dt": -1.0}, {"every_steps": 0}])
def test_nonpositive_intervals_are_rejected(kwargs):
    with pytest.raises(ValueError):
        Schedule(**kwargs)
