"""Checkpoints: everything a run needs to continue bit-for-bit, in one ``.npz``.

Saved: every particle array (float64 as is), the rates of the current state (the leapfrog
reuses them at the start of the next step), t, step, dt and the run's statistics. The file
is written to a temporary name and renamed, so a crash mid-write keeps the previous one.
"""

from __future__ import annotations

import json
import os
from pathlib import Path

import numpy as np

from .errors import CaseError, OutputError
from .particles import ParticleState

NAME = "checkpoint.npz"


def save(sim, directory: Path) -> Path:
    path = Path(directory) / NAME
    tmp = path.with_suffix(".tmp.npz")
    arrays = {f"state_{name}": a for name, a in sim.state.arrays()}
    arrays["acc"] = sim.acc
    if sim.drho is not None:
        arrays["drho"] = sim.drho
    meta = {"t": sim.t, "step": sim.step, "dt": sim.dt, "stats": sim.stats,
            "counters": dict(sim.counters), "fresh": bool(getattr(sim.integrator, "fresh", False)),
            "config": json.dumps(sim.case.config, default=str, sort_keys=True)}
    try:
        with open(tmp, "wb") as f:
            np.savez(f, meta=np.array(json.dumps(meta, default=float)), **arrays)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as e:
        raise OutputError(f"cannot write checkpoint {path}: {e.strerror or e}") from e
    return path


def load(sim, directory: Path) -> dict:
    """Restore ``sim`` from ``directory``/checkpoint.npz; returns the checkpoint's metadata."""
    path = Path(directory) / NAME
    if not path.exists():
        raise CaseError(path, "--restart", "no checkpoint to restart from in this output directory")
    with np.load(path) as z:
        meta = json.loads(str(z["meta"]))
        names = [name for name, _ in sim.state.arrays()]
        sim.state = ParticleState(**{name: z[f"state_{name}"].copy() for name in names})
        sim._allocate()
        sim.acc[:] = z["acc"]
        if sim.drho is not None and "drho" in z:
            sim.drho[:] = z["drho"]
    sim.t, sim.step, sim.dt = meta["t"], meta["step"], meta["dt"]
    sim.stats.update(meta["stats"])
    sim.counters.update(meta["counters"])
    if hasattr(sim.integrator, "fresh"):
        sim.integrator.fresh = meta["fresh"]
    return meta
