"""The run around the physics, asserted: instability detection, the time step, bit-for-bit
restart.
"""

from __future__ import annotations

import json
import math
import re

import numpy as np
import pytest
from conftest import by_id, make_sim, run_to_end, write_case
from core_cases import blob as blob_case  # a test below names its cell grid blob
from core_cases import colliding, spheres_case

from sphcore import cli
from sphcore.run import runner
from sphcore.testing import case_with

# ----------------------------------------------------------------------------------------
# instability
# ----------------------------------------------------------------------------------------


def _message_parts(message):
    m = re.search(r"unstable at step (\d+), t = (\S+) s: (.*) \(worst particle id (-?\d+)\)", message)
    assert m, message
    return int(m.group(1)), float(m.group(2)), m.group(3), int(m.group(4))


def test_density_bound_stops_the_run(tmp_path, capsys):
    case_dir = write_case(tmp_path / "collide", case_with(colliding(), {"checks.rho_max": 1.0001}))
    summary = runner.run(case_dir, output=tmp_path / "out", quiet=True)
    assert summary["status"] == "unstable"
    sim = summary.simulation
    step, t, reason, pid = _message_parts(summary["message"])
    assert step == sim.step >= 1 and t == pytest.approx(sim.t, rel=1e-5) and sim.t < sim.t_end
    assert "density above the upper bound" in reason
    # the named particle is the densest one, and it is above the bound
    worst = int(np.argmax(sim.state.rho))
    assert pid == int(sim.state.id[worst])
    assert sim.state.rho[worst] > 1.0001 * 1000.0
    assert f"{sim.state.rho[worst]:.6g}" in reason
    assert json.loads((tmp_path / "out" / "summary.json").read_text())["status"] == "unstable"
    # through the CLI: exit status 1, one line on stderr
    status = cli.main(["run", str(case_dir), "--output", str(tmp_path / "cli"), "--progress", "off"])
    out, err = capsys.readouterr()
    assert status == 1
    lines = err.strip().splitlines()
    assert len(lines) == 1 and lines[0].startswith("sph: error: unstable at step ")
    assert f"step {step}," in lines[0] and f"id {pid})" in lines[0]
    assert ": unstable: " in out


def test_particle_leaving_the_domain_is_caught(tmp_path):
    case = case_with(spheres_case(t_end=1.0, dt=0.01), {"domain.min": [0.0, 0.0], "blocks[0].count": [1, 1]})
    case["blocks"].append({"min": [0.02, 0.5], "count": [1, 1], "kind": "sphere", "velocity": [-1.0, 0.0]})
    case_dir = write_case(tmp_path / "leak", case)
    summary = runner.run(case_dir, output=tmp_path / "out", quiet=True)
    assert summary["status"] == "unstable"
    step, t, reason, pid = _message_parts(summary["message"])
    # the centre starts at x = 0.045 m and moves at -1 m/s: it crosses x = 0 during step 5
    assert step == 5 and t == pytest.approx(0.05)
    assert pid == 1  # the moving particle (second block), not the one at rest
    assert "left the domain" in reason


def test_a_particle_far_from_the_rest_is_no_instability(tmp_path):
    """Water that spreads is not unstable: a particle 5 m from the rest (a dense grid over
    the box would hold ~9000 cells) costs one cell of the sorted-key grid, and the run goes on."""
    from sphcore.neighbours.cellgrid import CellGrid

    sim = make_sim(write_case(tmp_path / "blob", blob_case()))
    sim.state.pos[0] = [4.9, 4.9]
    assert sim.step % sim.case.config["neighbours"]["sort_every"] == 0  # the next step reorders
    sim.advance()
    assert np.all(np.isfinite(sim.state.pos))
    # the far particle costs exactly one cell more than the blob alone
    pos = sim.state.pos
    far = int(np.argmax(np.abs(pos - np.median(pos, axis=0)).sum(axis=1)))
    blob = CellGrid(np.delete(pos, far, axis=0), sim.params.support)
    assert CellGrid(pos, sim.params.support).ncells == blob.ncells + 1


def test_non_finite_positions_are_an_instability(tmp_path):
    from sphcore.errors import Instability

    sim = make_sim(write_case(tmp_path / "blob", blob_case()))
    sim.state.pos[0] = [np.nan, 4.9]
    with pytest.raises(Instability, match="non-finite"):
        sim.advance()


# ----------------------------------------------------------------------------------------
# time step
# ----------------------------------------------------------------------------------------


def test_adaptive_dt_is_acoustic_at_rest(good_case):
    sim = make_sim(good_case, ["time.t_end=0.01"])  # six full steps, none cut to land on t_end
    cfg = sim.case.config["time"]
    g = 9.81
    assert sim.params.c0 == pytest.approx(10.0 * math.sqrt(2.0 * g * 0.2), rel=1e-12)  # H = 10 dx
    for _ in range(6):
        vmax = float(np.sqrt(np.max(np.sum(sim.state.vel**2, axis=1))))
        amax = float(np.sqrt(np.max(np.sum(sim.integrator.acc**2, axis=1))))
        sim.advance()
        acoustic = cfg["cfl"] * sim.params.h / (sim.params.c0 + vmax)
        assert sim.dt == pytest.approx(acoustic, rel=1e-14)
        if amax > 0:
            assert cfg["force_factor"] * math.sqrt(sim.params.h / amax) > acoustic  # the acoustic limit binds
    assert sim.step == 6 and np.max(np.abs(sim.state.vel)) > 0  # the block is falling
    # the Courant number scales the step
    half = make_sim(good_case, ["time.cfl=0.15"])
    half.advance()
    first = make_sim(good_case, ["time.cfl=0.3"])
    first.advance()
    assert half.dt == pytest.approx(0.5 * first.dt, rel=1e-14)


def test_viscous_limit_and_dt_max(good_case):
    nu = 1.0  # m^2/s: the viscous limit 0.125 h^2 / nu binds
    sim = make_sim(good_case, [f"fluid.nu={nu}"])
    sim.advance()
    assert sim.dt == pytest.approx(0.125 * sim.params.h**2 / nu, rel=1e-14)
    capped = make_sim(good_case, ["time.dt_max=1e-5"])
    capped.advance()
    assert capped.dt == 1e-5


@pytest.mark.parametrize("t_end, n_steps, last", [(0.001, 5, 0.0002), (0.0011, 6, 0.0001)])
def test_fixed_dt_is_honoured_and_ends_on_t_end(good_case, t_end, n_steps, last):
    sim = make_sim(good_case, ["time.dt=0.0002", f"time.t_end={t_end}"])
    dts = run_to_end(sim)
    assert sim.t == t_end  # exactly, no sliver step
    assert len(dts) == n_steps
    assert all(dt == 0.0002 for dt in dts[:-1])
    assert dts[-1] == pytest.approx(last, rel=1e-9)


# ----------------------------------------------------------------------------------------
# restart
# ----------------------------------------------------------------------------------------


def test_restart_is_bit_for_bit(tmp_path):
    dt = 2.0**-13  # t = k dt is exact: the interrupted run lands on t1 with full steps
    t_end, t1 = 40 * dt, 15 * dt
    case = case_with(colliding(), {"time.t_end": t_end, "time.dt": dt, "fluid.nu": 1e-6})
    case_dir = write_case(tmp_path / "case", case)
    full = runner.run(case_dir, output=tmp_path / "full", quiet=True)
    part = runner.run(case_dir, output=tmp_path / "part", t_end=t1, quiet=True)
    assert part["status"] == "completed" and part.simulation.step == 15 and part.simulation.t == t1
    rest = runner.run(case_dir, output=tmp_path / "part", t_end=t_end, restart=True, quiet=True)
    assert full["status"] == rest["status"] == "completed"
    a, b = full.simulation, rest.simulation
    assert a.step == b.step == 40 and a.t == b.t == t_end
    assert rest["steps"] == 40 and [s["steps"] for s in rest["segments"]] == [15, 25]  # the whole run
    sa, sb = by_id(a.state), by_id(b.state)
    for name in sa:
        assert np.array_equal(sa[name], sb[name]), name
    ia, ib = np.argsort(a.state.id), np.argsort(b.state.id)
    assert np.array_equal(a.integrator.acc[ia], b.integrator.acc[ib]) and np.array_equal(a.integrator.drho[ia], b.integrator.drho[ib])
    # the state did evolve: the comparison is not between two copies of the initial state
    assert not np.array_equal(sa["pos"], by_id(make_sim(case_dir).state)["pos"])


def test_restart_without_checkpoint_is_a_case_error(good_case, tmp_path, capsys):
    status = cli.main(["run", str(good_case), "--output", str(tmp_path / "none"), "--restart"])
    err = capsys.readouterr().err.strip()
    assert status == 2
    assert len(err.splitlines()) == 1 and "--restart" in err and "checkpoint" in err


@pytest.mark.parametrize("plugins, overrides", [
    (["reflective"], []),
    (["reflective"], ["physics.modified_pressure=true"]),
    (["reflective", "wall_integral"], ["density_diffusion.delta=0.1"]),
])
@pytest.mark.slow
def test_a_time_step_allocates_no_array_per_particle(tmp_path, plugins, overrides):
    """numpy allocations during a step (tracemalloc; numba's own are not traced) stay far
    below one float per particle (400 kB at 50,000 particles), over twelve steps that
    include a reorder; the measured peak is ~80 kB, mostly tracemalloc's own records."""
    import tracemalloc

    case = case_with(blob_case(), {"blocks[0].count": [224, 224], "plugins.use": plugins,
                              "domain.min": [-0.2, -0.2], "domain.max": [4.6, 4.6]})
    sim = make_sim(write_case(tmp_path / "big", case), overrides)
    assert sim.state.n == 224 * 224
    for _ in range(3):
        sim.advance()  # first-use buffers
    tracemalloc.start()
    try:
        peaks = []
        for _ in range(12):
            tracemalloc.reset_peak()
            sim.advance()
            peaks.append(tracemalloc.get_traced_memory()[1])
    finally:
        tracemalloc.stop()
    assert sim.step % sim.case.config["neighbours"]["sort_every"] < 12  # a reorder was among them
    assert max(peaks) < 0.5 * 8 * sim.state.n, peaks
