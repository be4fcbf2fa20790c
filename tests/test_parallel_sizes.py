"""One prange loop serves small and large calls (sphcore.jit.parallel.on_threads_by_size): the
kernel runs on one thread below the size, on the count set above it, and the count set is
restored; the wall model's plane terms, run that way, give the same bits on one thread and
two."""

from __future__ import annotations

import numba
import numpy as np
import pytest
from conftest import make_sim, write_case

from sphcore.jit.parallel import on_threads_by_size

TANK = {
    "case": {"dim": 2},
    "domain": {"min": [0.0, 0.0], "max": [1.3, 1.3]},
    "blocks": [{"min": [0.0, 0.0], "count": [64, 64]}],
    "particles": {"dx": 0.02},
    "time": {"t_end": 1.0},
    "plugins": {"use": ["reflective", "wall_integral"]},
}


def _threads_seen(seen):
    def kernel(x):
        seen.append(numba.get_num_threads())
        if x is None:
            raise RuntimeError("a failing kernel")
        return x + 10
    return kernel


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs two threads")
def test_small_calls_run_on_one_thread_and_the_count_is_restored():
    before = numba.get_num_threads()
    numba.set_num_threads(2)
    try:
        seen = []
        kernel = _threads_seen(seen)
        assert on_threads_by_size(10, 100, kernel, 1) == 11
        assert on_threads_by_size(100, 100, kernel, 1) == 11
        assert seen == [1, 2]
        assert numba.get_num_threads() == 2
        with pytest.raises(RuntimeError):
            on_threads_by_size(10, 100, kernel, None)
        assert numba.get_num_threads() == 2  # restored after an error too
        numba.set_num_threads(1)
        assert on_threads_by_size(10, 100, kernel, 1) == 11 and numba.get_num_threads() == 1
    finally:
        numba.set_num_threads(before)


@pytest.mark.skipif(numba.config.NUMBA_NUM_THREADS < 2, reason="needs two threads")
def test_the_plane_terms_give_the_same_bits_on_one_thread_and_two(tmp_path, monkeypatch):
    from sphcore_plugins.wall_integral import planes

    captured = []
    kernel = planes.add_plane_terms

    def spy(*args):
        captured.append([a.copy() if isinstance(a, np.ndarray) else a for a in args])
        return kernel(*args)

    monkeypatch.setattr(planes, "add_plane_terms", spy)
    sim = make_sim(write_case(tmp_path / "tank", TANK))
    sim.advance()
    args = list(captured[-1])
    n = sim.state.n
    assert args[1] > 100  # particles near the walls were listed
    # every particle, listed or not (a far one gets nothing added)
    args[0], args[1] = np.arange(n, dtype=np.int64), n
    results = []
    before = numba.get_num_threads()
    try:
        for threads in (1, 2):
            numba.set_num_threads(threads)
            out = [a.copy() if isinstance(a, np.ndarray) else a for a in args]
            kernel(*out)
            results.append(out[-5:])  # share, grad, hydro, fill, normals
    finally:
        numba.set_num_threads(before)
    for one, two in zip(*results):
        assert np.array_equal(one, two)
    share = results[0][0]
    near = captured[-1][0][:captured[-1][1]]  # the particles within 2h of a wall
    far = np.setdiff1d(np.arange(n), near)
    assert (share[near] > 0.0).all() and (share[far] == 0.0).all()
