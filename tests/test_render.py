"""postprocessing/render.py: a run's frames as pictures, rendered off-screen with pyvista.

A tiny dam break (cases/dam_break at dx = 0.114 m / 8, 0.04 s, a frame every 0.02 s) is
rendered as a user runs the script (a subprocess); the pictures must hold the colour map's
colours where the fluid is (not only grey walls on white), the GIF every frame, and a
directory that is not a run is refused with one line and exit status 2."""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

import numpy as np
import PIL.Image as PIL  # Pillow: in the test extra (it also comes with matplotlib and pyvista)
import pytest

from sphcore import cli

ROOT = Path(__file__).resolve().parents[1]
SCRIPT = ROOT / "postprocessing" / "render.py"


def render(*args):
    return subprocess.run([sys.executable, str(SCRIPT), *map(str, args)], capture_output=True, text=True,
                          check=False, timeout=300)


@pytest.fixture(scope="module")
def run(tmp_path_factory):
    out = tmp_path_factory.mktemp("render") / "dam_break"
    status = cli.main(["run", str(ROOT / "cases" / "dam_break"), "--output", str(out), "--progress", "off",
                       "--t-end", "0.04", "--set", "particles.dx=0.01425", "--set", "vtu.every_dt=0.02",
                       "--set", 'plugins.use=["reflective", "vtu"]'])
    assert status == 0
    return out


def coloured(path: Path, left: float = 0.8) -> int:
    """Pixels of the image's left part (the scalar bar stands at the right) whose channels
    differ by more than 40 of 255: the colour map's, not grey, black or white."""
    rgb = np.asarray(PIL.open(path).convert("RGB"), dtype=int)
    rgb = rgb[:, : int(left * rgb.shape[1])]
    return int(((rgb.max(axis=2) - rgb.min(axis=2)) > 40).sum())


def test_frames_are_coloured_pictures_and_the_gif_animates_them(run, tmp_path):
    res = render(run, "--gif", "--size", "320x240", "--out", tmp_path)
    assert res.returncode == 0 and "Traceback" not in res.stderr, res.stderr
    pngs = sorted(tmp_path.glob("pressure_*.png"))
    assert [p.name for p in pngs] == ["pressure_000000.png", "pressure_000001.png", "pressure_000002.png"]
    for png in pngs:
        assert png.read_bytes()[:4] == b"\x89PNG" and PIL.open(png).size == (320, 240)
        assert coloured(png) > 1000, png  # the column, 8 x 16 particles, is ~50 x 100 pixels here
        colours = {tuple(c) for c in np.asarray(PIL.open(png).convert("RGB")).reshape(-1, 3)}
        assert len(colours) > 20, png  # a colour map: many colours, not one flat tint
    with PIL.open(tmp_path / "pressure.gif") as gif:
        assert gif.n_frames == 3
    assert "bad X server" not in res.stderr and res.stderr.strip() == "", res.stderr


def test_velocity_of_the_last_frame_by_default_beside_the_run(run):
    res = render(run, "--field", "velocity", "--frames", "last", "--size", "320x240")
    assert res.returncode == 0, res.stderr
    png = run / "render" / "velocity_000002.png"
    assert res.stdout.split()[0] == str(png) and coloured(png) > 1000
    assert not (run / "render" / "velocity.gif").exists()


@pytest.mark.parametrize("what", ["empty", "missing", "netcdf only", "bad frames", "bad size"])
def test_what_is_not_a_run_or_a_bad_option_is_refused_with_one_line(run, tmp_path, what):
    path = {"empty": tmp_path, "missing": tmp_path / "missing"}.get(what, run)
    extra = {"bad frames": ["--frames", "7"], "bad size": ["--size", "0x100"]}.get(what, [])
    if what == "netcdf only":
        path = tmp_path / "nc"
        path.mkdir()
        (path / "particles.nc").write_bytes(b"not frames")
    res = render(path, *extra, "--out", tmp_path / "pictures")
    assert res.returncode == 2, (res.stdout, res.stderr)
    assert len(res.stderr.strip().splitlines()) == 1 and res.stderr.startswith("render.py: error: "), res.stderr
    assert "Traceback" not in res.stderr and not (tmp_path / "pictures").exists()
