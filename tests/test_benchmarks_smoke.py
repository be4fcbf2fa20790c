"""Every script under benchmarks/ on a tiny input, as a person runs it: ``python
benchmarks/<group>/<script>.py ...`` from the repository root, in its own process.

Each test checks the exit status and that the output holds the figure the script exists to
print, parsed from its table (finite and positive) or its verdict (same bits, no escape).
Speed is never asserted: the figures are for a person to read (benchmarks/README.md).
A script whose peer is absent (PySPH) or that cannot mount its tmpfs says so in one line
and exits with status 77; its test then skips with that line.
"""

from __future__ import annotations

import math
import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

# the scripts run as a user runs them, each in a process of its own: the slow tier
pytestmark = pytest.mark.slow

ROOT = Path(__file__).resolve().parents[1]
BENCH = ROOT / "benchmarks"
UNAVAILABLE = 77  # exit status of a script that cannot run here (its one line says why)
NUM = r"[-+]?(?:\d[\d,]*\.?\d*(?:[eE][-+]?\d+)?|nan|inf)"  # a printed figure


def script(path: str, *args, timeout: float = 300) -> subprocess.CompletedProcess:
    """``python benchmarks/PATH ARGS`` from the repository root; its result."""
    return subprocess.run([sys.executable, str(BENCH / path), *map(str, args)], cwd=ROOT, capture_output=True,
                          text=True, timeout=timeout)


def output(proc: subprocess.CompletedProcess) -> str:
    """The standard output of a run that exited 0."""
    assert proc.returncode == 0, f"exit {proc.returncode}\n{proc.stdout[-4000:]}\n{proc.stderr[-4000:]}"
    return proc.stdout


def rows(pattern: str, text: str, count: int | None = None) -> list[tuple[str, ...]]:
    """The lines of ``text`` that match ``pattern`` from start to end (groups per line);
    at least one, or exactly ``count``."""
    found = [m.groups() for m in map(re.compile(pattern).fullmatch, map(str.strip, text.splitlines())) if m]
    assert found if count is None else len(found) == count, f"{count or 'some'} lines like {pattern!r} in:\n{text}"
    return found


def figure(*values: str) -> None:
    """Printed numbers (thousands separators allowed), each checked finite and positive."""
    for value in values:
        x = float(value.replace(",", ""))
        assert math.isfinite(x) and x > 0, value


# ---------------------------------------------------------------------------------------
# speed/
# ---------------------------------------------------------------------------------------


def test_bench_boundaries_prints_particle_steps_per_mode():
    out = output(script("speed/bench_boundaries.py", "--sizes", 400, "--steps", 2))
    for _, fluid, _, _, psps in rows(rf"(ghost|reflective|ghost\+reflective)\s+(\d+)\s+(\d+)\s+({NUM})"
                                                rf"\s+({NUM})\s+{NUM}\s+{NUM}\s+{NUM}\s+{NUM}", out, 3):
        assert int(fluid) == 400
        figure(psps)


def test_bench_boundaries_accuracy_prints_pressure_error_and_drift():
    out = output(script("speed/bench_boundaries.py", "--accuracy", "--relax-s", 0.02, "--free-s", 0.05))
    table = rows(rf"(ghost|reflective|ghost\+reflective)\s+(relaxed 0.02 s, then 0.05 s|hydrostatic start, 0.05 s)"
                 rf"\s+({NUM})%\s+({NUM})dx\s+({NUM})dx", out, 6)
    for _, _, p_err, drift, clearance in table:
        figure(p_err, clearance)
        assert math.isfinite(float(drift))


def test_bench_faces_prints_the_kernel_share_by_face_count():
    out = output(script("speed/bench_faces.py", "--dx", 0.05, "--faces", 0, 80, "--steps", 1, "--repeat", 1))
    table = rows(rf"(\d+)\s+(\d+)\s+({NUM})\s+({NUM})\s+({NUM})%", out, 2)
    assert int(table[0][0]) == 0 and int(table[1][0]) > 0  # no obstacle, then a sphere of faces
    for _, particles, step_ms, kernel_ms, share in table:
        figure(particles, step_ms)
        assert float(kernel_ms) >= 0 and math.isfinite(float(share))


def test_bench_faces_wall_model_prints_its_share_of_a_step():
    out = output(script("speed/bench_faces.py", "--dx", 0.05, "--faces", 80, "--steps", 1, "--repeat", 1,
                        "--wall-model"))
    (_, alone_ms, exact_ms, exact_share, _, table_ms, table_share, _), = rows(
        rf"(\d+)\s+\d+\s+({NUM})" + rf"\s+({NUM})\s+({NUM})%\s+({NUM})" * 2, out, 1)
    figure(alone_ms, exact_ms, table_ms)
    assert math.isfinite(float(exact_share)) and math.isfinite(float(table_share))


def test_bench_loaded_prints_each_variants_time_and_ratio():
    out = output(script("speed/bench_loaded.py", "--pairs", 1, "--load", 0, "--set", 'plugins.use=["reflective"]',
                        "--set", "time.t_end=0.005"))
    for _, median_s, ratio in rows(rf"0\s+(1 thread|2 adaptive|2 fixed)\s+({NUM})\s+({NUM})(?:\s+.*)?", out, 3):
        figure(median_s, ratio)


def test_bench_moving_prints_the_moving_tanks_cost_against_the_fixed_one():
    out = output(script("speed/bench_moving.py", "--n", 600, "--steps", 2, "--pairs", 1))
    for name in ("fixed", "moving"):
        figure(*rows(rf"{name}\s+({NUM})\s+({NUM})", out, 1)[0])
    figure(*rows(rf"moving / fixed: ({NUM}) \(pairs ({NUM}) \.\. ({NUM})\)", out, 1)[0])


def test_bench_body_prints_a_floating_bodys_cost_against_its_moving_wall():
    out = output(script("speed/bench_body.py", "--n", 2000, "--steps", 2, "--pairs", 1))
    for name in ("moving", "body"):
        figure(*rows(rf"{name}\s+({NUM})\s+({NUM})", out, 1)[0])
    figure(*rows(rf"body / moving wall: ({NUM}) \(pairs ({NUM}) \.\. ({NUM})\)", out, 1)[0])


def test_bench_output_prints_what_the_writers_cost():
    out = output(script("speed/bench_output.py", "--t-end", 0.01, "--scales", 1))
    (particles, frames, mb, with_s, without_s, share, ms_frame), = rows(
        rf"1\s+(\d+)\s+\d+\s+(\d+)\s+({NUM})\s+({NUM})\s+({NUM})\s+({NUM})%\s+{NUM}\s+{NUM}%\s+({NUM})"
        rf"\s+{NUM}\s+{NUM}\s+{NUM}%", out, 1)
    figure(particles, frames, mb, with_s, without_s, ms_frame)
    assert math.isfinite(float(share))  # (with - without) / with: noise may make it negative


def test_bench_pairs_prints_the_pair_loop_and_a_step_by_stages():
    out = output(script("speed/bench_pairs.py", "cases/dam_break", "--at", 0.001, "--calls", 2, "--steps", 5))
    (ms_call, pairs, ns_pair), = rows(
        rf"pair loop, frozen state: ({NUM}) ms per call, (\d+) pairs, ({NUM}) ns per pair", out, 1)
    (us_step,), = rows(rf"5 steps: ({NUM}) us per step", out, 1)
    figure(ms_call, pairs, ns_pair, us_step)
    assert rows(rf"pair loop \(sph_rates\)\s+({NUM}) us\s+{NUM}%", out, 1)


def test_bench_pysph_alone_prints_sphcores_time():
    out = output(script("speed/bench_pysph.py", "--alone", "--pairs", 1, "--threads", 1, "--t-end", 0.01))
    (seconds, steps), = rows(rf"1\s+({NUM})\s+-\s+-\s+(\d+)\s+-", out, 1)
    figure(seconds, steps)


def test_bench_pysph_against_pysph():
    pysph = os.environ.get("PYSPH") or shutil.which("pysph")
    args = ("--pairs", 1, "--threads", 1, "--t-end", 0.01)
    if not pysph:
        proc = script("speed/bench_pysph.py", *args)
        lines = proc.stderr.strip().splitlines()
        assert proc.returncode == UNAVAILABLE and len(lines) == 1 and "PySPH not found" in lines[0], proc.stderr
        pytest.skip(lines[0])
    out = output(script("speed/bench_pysph.py", *args, "--pysph", pysph))
    figure(*rows(rf"1\s+({NUM})\s+({NUM})\s+({NUM})\s+(\d+)\s+(\d+)", out, 1)[0])  # times, ratio, steps



SPLISH_VENV = Path("/tmp/splishsplash-venv")  # where the SPlisHSPlasH scripts keep SPlisHSPlasH by default


def _splish_or_skip():
    """Skip unless SPlisHSPlasH is installed in its own environment already (the scripts
    would otherwise install it from PyPI, which a test does not do)."""
    py = SPLISH_VENV / "bin" / "python"
    if not py.exists() or subprocess.run([str(py), "-c", "import importlib.util as u, sys; "
                                          "sys.exit(u.find_spec('pysplishsplash') is None)"]).returncode != 0:
        pytest.skip(f"SPlisHSPlasH is not installed in {SPLISH_VENV} (the scripts install it there when run)")


def test_bench_splishsplash_against_splishsplash():
    _splish_or_skip()
    out = output(script("speed/bench_splishsplash.py", "--pairs", 1, "--threads", 1, "--t-end", 0.01))
    figure(*rows(rf"1\s+({NUM})\s+({NUM})\s+({NUM})\s+(\d+)\s+(\d+)\s+.*", out, 1)[0])  # times, ratio, steps


def test_tank_at_rest_against_splishsplash_prints_displacements():
    _splish_or_skip()
    out = output(script("accuracy/tank_at_rest_splishsplash.py", "--t-end", 0.1, "--dx", 0.05))
    assert rows(r"sphcore dfsph: (\d+) particles", out, 1) and rows(r"SPlisHSPlasH \S+ DFSPH: (\d+) particles", out, 1)
    # each code's first frame: the start, nothing moved yet
    for far, mean, speed in rows(rf"0\s+({NUM})\s+({NUM})\s+nan\s+nan\s+({NUM})", out, 2):
        assert float(far) == float(mean) == 0.0 and float(speed) >= 0.0


def test_tank_at_rest_alone_prints_displacements_by_region():
    out = output(script("accuracy/tank_at_rest_splishsplash.py", "--t-end", 0.1, "--dx", 0.05, "--sphcore-only",
                        "--set", "reflective.cr=0"))
    assert "SPlisHSPlasH" not in out and "sphcore's overrides: reflective.cr=0" in out
    (n,), = rows(r"sphcore dfsph: (\d+) particles", out, 1)
    found = {name: (int(k), float(mean), float(far)) for name, k, mean, far, _ in
             rows(rf"\s*(side|edge|floor|top|interior)\s+(\d+)\s+({NUM})\s+({NUM})\s+({NUM})", out, 5)}
    # the 8 x 8 x 8 lattice's rows: the top and floor layers, the vertical edges' and the side
    # walls' first rows between them, and the 6 x 6 x 6 interior
    assert int(n) == 512
    assert {name: k for name, (k, _, _) in found.items()} == {"side": 144, "edge": 24, "floor": 64, "top": 64,
                                                              "interior": 216}
    assert all(0.0 <= mean <= far for _, mean, far in found.values())


def test_bench_scale_prints_particle_steps_and_memory_per_particle():
    out = output(script("speed/bench_scale.py", "--sizes2d", 100, "--sizes3d", "--plugins", "reflective",
                        "--budget", 500))
    (n, steps, psps, us), = rows(rf"2\s+(\d+)\s+reflective\s+(\d+)\s+({NUM})\s+({NUM})\s+.*", out, 1)
    figure(n, steps, psps, us)


def test_bench_startup_prints_where_the_process_time_goes():
    out = output(script("speed/bench_startup.py", "--steps", 5))
    for label in ("import numba", "import sphcore", "load the case and its plugins", "set up the simulation"):
        (ms,), = rows(rf"{label}\s+({NUM}) ms\s+\(from the start\s+{NUM} ms\)", out, 1)
        assert float(ms) >= 0
    (us,), = rows(rf"mean step after the first five\s+({NUM}) us", out, 1)
    figure(us)


def test_bench_step_prints_particle_steps_per_second():
    out = output(script("speed/bench_step.py", "--sizes", 400, "--steps", 2, "--plugins", "reflective"))
    (n, psps, us, share), = rows(rf"(\d+)\s+2\s+{NUM}\s+({NUM})\s+({NUM})\s+({NUM})\s+{NUM}", out, 1)
    assert int(n) == 400
    figure(psps, us)
    assert 0 <= float(share) <= 100


def test_bench_wakeup_prints_the_loop_time_per_thread_count():
    out = output(script("speed/bench_wakeup.py", "--n", 1000, "--gaps", 0, 50, "--calls", 20))
    (one, most), = rows(rf"0\s+({NUM})\s+({NUM})", out, 1)  # back to back: nothing subtracted
    figure(one, most)
    assert len(rows(rf"{NUM}\s+({NUM})\s+({NUM})", out)) == 2


def test_bench_wall_model_prints_each_variants_share():
    out = output(script("speed/bench_wall_model.py", "--n", 400, "--steps", 2, "--pairs", 1))
    table = rows(rf"(reflective|\+ wall model|\+ density diffusion|\+ both)\s+({NUM})\s+({NUM})\s+(-|{NUM}%)", out, 4)
    for _, ms, psps, _ in table:
        figure(ms, psps)


def test_bench_wall_share_prints_the_cost_per_particle():
    out = output(script("speed/bench_wall_share.py", "--sides", 20, 8, "--repeat", 1))
    for dim, n, share, us, _ in rows(rf"([23])D box  whole box\s+(\d+)\s+({NUM})%\s+({NUM})\s+({NUM})", out, 2):
        assert int(n) == {"2": 400, "3": 512}[dim] and float(share) == 100.0
        figure(us)
    for ms, _ in rows(rf"[23]D box  whole box per step: ({NUM}) ms for (\d+) particles", out, 2):
        figure(ms)


def test_bench_wedge_prints_reflections_per_particle_and_step():
    # 0.4 s: long enough for the particles to fall into the apex and touch both walls
    out = output(script("speed/bench_wedge.py", "--steps", 400))
    table = rows(rf"([23])\s+({NUM})\s+({NUM})\s+(\d+)\s+(\d+)\s+({NUM})\s+({NUM})\s+({NUM})x", out, 6)
    for _, _, per_step, most, guards, clearance, kernel_s, _ in table:
        figure(per_step, most, kernel_s)
        assert int(guards) >= 0 and math.isfinite(float(clearance))


# ---------------------------------------------------------------------------------------
# faults/
# ---------------------------------------------------------------------------------------


def test_kill_restart_ends_bit_for_bit():
    out = output(script("faults/kill_restart.py", "--kills", 2, "--seed", 1))
    (sent, landed), = rows(r"kills sent (\d+), landed on a running process (\d+), seed 1", out, 1)
    assert int(sent) == 2 and 0 <= int(landed) <= 2
    (steps, _), = rows(r"summary: completed, (\d+) steps over (\d+) recorded segments .*", out, 1)
    figure(steps)
    assert "final particles and every netCDF frame: bit for bit equal to the uninterrupted run" in out


def test_full_disk_fails_cleanly_and_restarts_bit_for_bit():
    if not sys.platform.startswith("linux") or os.geteuid() != 0 or shutil.which("mount") is None:
        pytest.skip("full_disk.py mounts a tmpfs: needs root and mount on Linux")
    proc = script("faults/full_disk.py", "--free", "64")  # the disk fills at the first frame
    if proc.returncode == UNAVAILABLE:  # root, and still no mount (a container without the capability)
        lines = proc.stderr.strip().splitlines()
        assert len(lines) == 1, proc.stderr
        pytest.skip(lines[0])
    out = output(proc)
    assert rows(r"free\s+64 KiB: exit ([012]), ok: .*", out, 1)
    assert "1 fill levels, 0 failed" in out


# ---------------------------------------------------------------------------------------
# fuzz/
# ---------------------------------------------------------------------------------------


def test_fuzz_reflective_finds_no_escape():
    out = output(script("fuzz/fuzz_reflective.py", "--n", 2000, "--batch", 500, "--quiet"))
    (tried,), = rows(r"tried (\d+) trajectories in \d+ domains .*", out, 1)
    assert int(tried) == 2000
    (escaped, nonfinite), = rows(r"escaped (\d+)\s+non-finite (\d+)\s+needed the guard .*", out, 1)
    assert (escaped, nonfinite) == ("0", "0")
    (rate,), = rows(rf"kernel time {NUM} s \(({NUM}) trajectories/s\), .*", out, 1)
    figure(rate)


def test_fuzz_moving_finds_no_escape():
    out = output(script("fuzz/fuzz_moving.py", "--n", 8000, "--batch", 2000, "--quiet"))
    (escapes,) = rows(rf"8,000 trajectories in 4 scenes: (\d+) escapes, {NUM} reflected, \d+ guard returns, "
                      rf"{NUM} trajectories/s", out, 1)[0]
    assert escapes == "0"


def test_fuzz_faces_finds_no_escape_or_crossing():
    out = output(script("fuzz/fuzz_faces.py", "--n", 800, "--batch", 800, "--per-domain", 100, "--quiet"))
    (n, domains, escaped, crossed, nonfinite, rate), = rows(
        rf"total\s+({NUM})\s+(\d+)\s+(\d+)\s+(\d+)\s+(\d+)\s+{NUM}%\s+{NUM}\s+\d+\s+{NUM}\s+({NUM})", out, 1)
    assert n == "800" and int(domains) == 8 and (escaped, crossed, nonfinite) == ("0", "0", "0")
    figure(rate)
    assert "OK: no escape, crossing or non-finite value" in out


# ---------------------------------------------------------------------------------------
# tools/
# ---------------------------------------------------------------------------------------


def test_final_state_compares_two_runs_bit_for_bit(tmp_path):
    a, b, c = tmp_path / "a.npz", tmp_path / "b.npz", tmp_path / "c.npz"
    for out in (a, b):
        text = output(script("tools/final_state.py", "run", "cases/dam_break", out, "--t-end", 0.004,
                             "--set", 'plugins.use=["reflective"]'))
        (steps,), = rows(rf"cases/dam_break: completed, (\d+) steps, t = {NUM} s, saved .*", text, 1)
        figure(steps)
    same = output(script("tools/final_state.py", "compare", a, b))
    assert rows(r"(\w+)\s+bit for bit", same, 6)  # pos, vel, rho, p, t, steps
    with np.load(a) as z:
        arrays = dict(z)
    arrays["pos"][0, 0] = np.nextafter(arrays["pos"][0, 0], np.inf)  # one bit of one particle
    np.savez(c, **arrays)
    differ = script("tools/final_state.py", "compare", a, c)
    assert differ.returncode == 1 and rows(rf"pos\s+DIFFERENT: ({NUM})", differ.stdout, 1), differ.stdout


@pytest.fixture
def other_equations(request, tmp_path) -> Path:
    """A copy of this checkout's pair loop, as another checkout's (an A/A run). It stays in
    pytest's cache between runs and is rewritten only when the source changes, so that
    numba's cache beside it stays valid (compiling it takes about 10 s)."""
    import sphcore.physics.equations

    source = Path(sphcore.physics.equations.__file__)
    cache = getattr(request.config, "cache", None)
    copy = (cache.mkdir("bench_pair_ab") if cache is not None else tmp_path) / "equations.py"
    if not copy.exists() or copy.read_bytes() != source.read_bytes():
        shutil.copyfile(source, copy)
    return copy


def test_bench_pair_ab_prints_same_bits_and_the_ratio(other_equations):
    out = output(script("tools/bench_pair_ab.py", other_equations, "--at", 0.001, "--rounds", 1))
    assert rows(r"pysph_dam_break: \d+ particles at t = .*; same bits: (True)", out, 1)
    for ab in ("A", "B"):
        figure(*rows(rf"{ab}: fastest ({NUM}) ms, median ({NUM}) ms per call", out, 1)[0])
    figure(*rows(rf"B / A: ({NUM}) \(fastest calls\), ({NUM}) \(median of 1 rounds\)", out, 1)[0])
