"""Checkpoints: everything a run needs to continue bit-for-bit, in one ``.npz``.

Saved: every particle array (float64 as is), the rates of the current state (the leapfrog
reuses them at the start of the next step), t, step, dt and the run's statistics. The file
is written to a temporary name and renamed, so a crash mid-write keeps the previous one.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from sphcore.errors import CaseError, OutputError
from sphcore.physics.particles import ParticleState
from sphcore.run import resume

NAME = "checkpoint.npz"


def save(sim, directory: Path, extra: dict | None = None) -> Path:
    """Write the checkpoint; ``extra`` (the run's identity and history, see
    :mod:`sphcore.run.resume`) goes into its metadata."""
    path = Path(directory) / NAME
    tmp = path.with_suffix(".tmp.npz")
    ctx = sim.ctx
    arrays = {f"state_{name}": a for name, a in ctx.state.arrays()}
    rates = sim.integrator.checkpoint()
    arrays["acc"] = rates["acc"]
    arrays["drho"] = rates["drho"]
    pairs = sim.forces.pairs
    if pairs is not None and pairs.checkpoint() is not None:
        arrays["pair_list_positions"] = pairs.checkpoint()  # the lists are rebuilt from these
    kept = {}
    for plugin, values in ctx._kept.items():
        kept[plugin] = {}
        for key, value in values.items():
            if isinstance(value, np.ndarray):
                arrays[f"kept_{plugin}_{key}"] = value
                kept[plugin][key] = {"__array__": f"kept_{plugin}_{key}"}
            else:
                kept[plugin][key] = value
    meta = {"t": ctx.t, "step": ctx.step, "dt": ctx.dt, "stats": ctx._stats, "kept": kept,
            "counters": dict(ctx.counters), "fresh": bool(rates["fresh"]),
            "config": resume.config_json(sim.case.config)}
    meta.update(extra or {})
    try:
        with open(tmp, "wb") as f:
            np.savez(f, meta=np.array(json.dumps(meta, default=float)), **arrays)
            f.flush()
            os.fsync(f.fileno())
        os.replace(tmp, path)
    except OSError as e:
        try:  # a full disk: drop the partial file, the previous checkpoint stays
            tmp.unlink(missing_ok=True)
        except OSError:
            pass
        raise OutputError(f"cannot write checkpoint {path}: {e.strerror or e}") from e
    return path


def read(directory: Path) -> tuple[dict, dict]:
    """(metadata, arrays) of ``directory``/checkpoint.npz."""
    path = Path(directory) / NAME
    if not path.exists():
        raise CaseError(path, "--restart", "no checkpoint to restart from in this output directory")
    with np.load(path) as z:
        meta = json.loads(str(z["meta"]))
        arrays = {k: z[k].copy() for k in z.files if k != "meta"}
    return meta, arrays


def read_meta(directory: Path) -> dict:
    """Only the metadata of ``directory``/checkpoint.npz (the arrays stay on disk)."""
    path = Path(directory) / NAME
    if not path.exists():
        raise CaseError(path, "--restart", "no checkpoint to restart from in this output directory")
    try:
        with np.load(path) as z:
            return json.loads(str(z["meta"]))
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as e:
        raise CaseError(path, "--restart", f"not a readable checkpoint ({e})") from None


def restore_state(ctx, meta: dict, arrays: dict) -> None:
    """Put the checkpoint's particles, clock, statistics and the plugins' kept state into
    the run context ``ctx`` (before set-up)."""
    names = [name for name, _ in ctx.state.arrays()]
    ctx.state = ParticleState(**{name: arrays[f"state_{name}"] for name in names})
    ctx.t, ctx.step, ctx.dt = meta["t"], meta["step"], meta["dt"]
    for plugin, values in meta["stats"].items():
        ctx.stats(plugin).update(values)
    for plugin, values in meta.get("kept", {}).items():
        ctx.kept(plugin).update({k: arrays[v["__array__"]] if isinstance(v, dict) and "__array__" in v else v
                                 for k, v in values.items()})
    ctx.counters.update(meta["counters"])


def restore_rates(sim, meta: dict, arrays: dict) -> None:
    """Put the checkpoint's rates into the integrator (after allocation), so the leapfrog
    continues exactly as the uninterrupted run would."""
    sim.integrator.restore({"acc": arrays["acc"], "drho": arrays.get("drho", np.zeros(0)), "fresh": meta["fresh"]})
    if sim.forces.pairs is not None and "pair_list_positions" in arrays:
        sim.forces.pairs.restore(arrays["pair_list_positions"])
