"""The wheel holds every module and data file of the source tree: a normal (not editable)
install must run everything an editable one runs (``sph sweep`` included)."""

from __future__ import annotations

import shutil
import subprocess
import sys
import zipfile
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
SOURCES = {"sphcore": "sphcore", "plugins": "sphcore_plugins"}  # folder -> installed package


def _tracked(folder: str) -> list[Path]:
    """Files of ``folder`` as git tracks them (the tree a clone has), else as on disk."""
    try:
        out = subprocess.run(["git", "ls-files", folder], cwd=ROOT, capture_output=True, text=True, check=True)
        files = [ROOT / line for line in out.stdout.splitlines() if line]
    except (OSError, subprocess.CalledProcessError):
        files = [p for p in (ROOT / folder).rglob("*") if p.is_file()]
    return [p for p in files if "__pycache__" not in p.parts and p.suffix not in (".pyc", ".nbi", ".nbc")]


def test_the_wheel_holds_every_module_and_data_file(tmp_path):
    # built from a copy of the tracked files, so that the build leaves nothing in the checkout
    src = tmp_path / "src"
    for folder in ("sphcore", "plugins"):
        for p in _tracked(folder):
            (src / p.relative_to(ROOT)).parent.mkdir(parents=True, exist_ok=True)
            shutil.copy2(p, src / p.relative_to(ROOT))
    for name in ("pyproject.toml", "setup.py", "README.md"):
        shutil.copy2(ROOT / name, src / name)
    built = subprocess.run([sys.executable, "-m", "pip", "wheel", str(src), "--no-deps", "-q", "-w", str(tmp_path)],
                           capture_output=True, text=True)
    assert built.returncode == 0, built.stderr[-2000:]
    (wheel,) = tmp_path.glob("sphcore-*.whl")
    names = set(zipfile.ZipFile(wheel).namelist())
    expected = {f"{SOURCES[folder]}/{p.relative_to(ROOT / folder).as_posix()}"
                for folder in SOURCES for p in _tracked(folder)}
    assert "sphcore/sweep/__init__.py" in expected  # the subpackage a hand-written list once missed
    assert expected - names == set()
