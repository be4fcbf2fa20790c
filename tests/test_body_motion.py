"""postprocessing/body_motion.py on loads files whose motion is known: a damped cosine gives
back its period, decrement and equilibrium; what it cannot read it refuses."""

from __future__ import annotations

import math
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "postprocessing" / "body_motion.py"
AXES = ("x", "y", "z", "rx", "ry", "rz", "vx", "vy", "vz", "wx", "wy", "wz")


def _write(directory: Path, t, y, vy, name="bodies[0]"):
    cols = {f"{name}.{a}": np.zeros_like(t) for a in AXES}
    cols[f"{name}.y"], cols[f"{name}.vy"] = y, vy
    header = ["t"] + [f"{name}.F{a}" for a in "xyz"] + [f"{name}.M{a}" for a in "xyz"] + list(cols)
    rows = [[tk] + [0.0] * 6 + [c[k] for c in cols.values()] for k, tk in enumerate(t)]
    directory.mkdir(parents=True, exist_ok=True)
    (directory / "wall_loads.csv").write_text("# loads\n" + ",".join(header) + "\n"
                                              + "".join(",".join(repr(float(v)) for v in r) + "\n" for r in rows))


def _run(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True, text=True, check=False)


@pytest.mark.parametrize("period, delta, eq", [(0.7, 0.9, 0.3), (1.3, 0.2, -0.05)])
def test_a_damped_cosine_gives_back_its_period_decrement_and_equilibrium(tmp_path, period, delta, eq):
    """y = eq + z0 exp(-delta t / T) cos(2 pi t / T) from rest at t = 0 (sampled at 5 ms, as
    the loads file is written): the period within 1 %, the decrement within 2 %, the given
    equilibrium's amplitudes, and the release counted as the first extremum."""
    t = np.arange(0.0, 4.0 * period, 0.005)
    omega, sigma = 2 * math.pi / period, delta / period
    y = eq + 0.005 * np.exp(-sigma * t) * (np.cos(omega * t) + sigma / omega * np.sin(omega * t))
    vy = np.gradient(y, t)
    vy[0] = 0.0
    _write(tmp_path, t, y, vy)
    res = _run(tmp_path, "--axis", "y", "--after", 0.0, "--equilibrium", eq)
    assert res.returncode == 0, res.stderr
    figures = {line.split()[0]: line.split() for line in res.stdout.splitlines() if line}
    assert float(figures["period"][1]) == pytest.approx(period, rel=0.01)
    assert float(figures["log"][2]) == pytest.approx(delta, rel=0.02)
    assert "0.0000  " in res.stdout  # the release, at rest, is the first extremum
    assert (tmp_path / "body_bodies0_y.png").stat().st_size > 1000


def test_what_it_cannot_read_is_refused(tmp_path):
    t = np.arange(0.0, 1.0, 0.005)
    _write(tmp_path / "flat", t, np.full_like(t, 0.3), np.zeros_like(t))
    for args, words in (((tmp_path / "none",), "no such file"),
                        ((tmp_path / "flat", "--body", "bodies[3]"), "no group 'bodies[3]'"),
                        ((tmp_path / "flat",), "extrema")):
        res = _run(*args)
        assert res.returncode == 2 and res.stderr.startswith("body_motion.py: error: ") and words in res.stderr, \
            res.stderr
        assert len(res.stderr.strip().splitlines()) == 1
