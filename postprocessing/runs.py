"""Open a run's output for a post-processing script, or stop with one clean line.

Each script says what kind of run it reads; a missing path, a directory sph did not write,
a run without frames or a run of another kind (a tank at rest given to the wavefront
script) is refused with ``<script>: error: ...`` on stderr and exit status 2, never a
traceback or a plot of nonsense. The run's validated case (``config`` in its
summary.json) gives the scripts their defaults (column width, water depth, density).
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from pathlib import Path


@dataclass
class Run:
    dir: Path  # the output directory (plots are written here, beside what sph wrote)
    frames: Path  # the .pvd or particles.nc to read
    config: dict  # the validated case, section -> key -> value

    def first_block(self) -> dict:
        fluid = [b for b in self.config.get("blocks", []) if b.get("kind", "fluid") == "fluid"]
        return fluid[0] if fluid else {}


def fail(script: str, message: str):
    print(f"{script}: error: {message}", file=sys.stderr)
    raise SystemExit(2)


def _block_extent(block, dx):
    lo = [float(v) for v in block["min"]]
    if block.get("max") is not None:
        hi = [float(v) for v in block["max"]]
    else:
        hi = [a + c * dx for a, c in zip(lo, block["count"])]
    return lo, hi


def open_run(path, script: str, kind: str) -> Run:
    """The run at ``path`` (an output directory, its .pvd or particles.nc); ``kind`` is
    "dam_break" (a 2D fluid column against the back wall with room to spread) or
    "tank_at_rest" (fluid covering the whole floor of a 2D tank, at rest)."""
    p = Path(path)
    if not p.exists():
        fail(script, f"no such run: {p}")
    d = p if p.is_dir() else p.parent
    if p.is_dir():
        pvd = sorted(p.glob("*.pvd"))
        frames = pvd[0] if pvd else p / "particles.nc"
    else:
        frames = p
    if frames.suffix not in (".pvd", ".nc") or not frames.exists():
        fail(script, f"{d} holds no frames of a run (a .pvd from the vtu plugin or particles.nc from netcdf)")
    summary = d / "summary.json"
    if not summary.exists():
        fail(script, f"{d} is not a run written by sph (no summary.json)")
    try:
        config = json.loads(summary.read_text()).get("config") or {}
    except (OSError, ValueError) as e:
        fail(script, f"cannot read {summary}: {e}")
    run = Run(d, frames, config)
    if config:
        _check_kind(run, script, kind)
    return run


def _check_kind(run: Run, script: str, kind: str):
    cfg = run.config
    dim = cfg["case"]["dim"]
    block, dom = run.first_block(), cfg["domain"]
    if dim != 2 or not block or dom.get("min") is None:
        fail(script, f"{run.dir} is not a {kind.replace('_', ' ')} run: it needs a 2D fluid block in a box domain")
    lo, hi = _block_extent(block, cfg["particles"]["dx"])
    dx = cfg["particles"]["dx"]
    moving = any(abs(v) > 0 for v in (block.get("velocity") or [0.0]))
    if kind == "dam_break":
        against_wall = abs(lo[0] - dom["min"][0]) < dx and abs(lo[1] - dom["min"][1]) < dx
        if not against_wall or hi[0] > dom["max"][0] - 2 * dx:
            fail(script, f"{run.dir} is not a dam break: its fluid block does not stand against the back wall "
                         f"with room to spread")
    elif kind == "tank_at_rest":
        if abs(lo[0] - dom["min"][0]) > dx or abs(hi[0] - dom["max"][0]) > dx or moving:
            fail(script, f"{run.dir} is not a tank at rest: its fluid does not cover the whole floor at rest")
