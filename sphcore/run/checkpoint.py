"""Checkpoints: everything a run needs to continue bit-for-bit, in one ``.npz``.

Saved: the run state (:meth:`sphcore.run.state.RunState.payload`: every particle array
(float64 as is), the rates of the current state, which the leapfrog reuses at the start of
the next step, the pair-list anchor, t, step, dt, the plugins' figures and kept state), the
validated case and the run's identity. The file is written to a temporary name and renamed,
so a crash mid-write keeps the previous one; a restart reads it back with :func:`read` and
:meth:`sphcore.run.state.RunState.load_payload`.
"""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path

import numpy as np

from sphcore.errors import CaseError, OutputError
from sphcore.run import resume

NAME = "checkpoint.npz"


def save(sim, directory: Path, extra: dict | None = None) -> Path:
    """Write the checkpoint; ``extra`` (the run's identity and history, see
    :mod:`sphcore.run.resume`) goes into its metadata."""
    path = Path(directory) / NAME
    tmp = path.with_suffix(".tmp.npz")
    meta, arrays = sim.run.payload()
    meta["config"] = resume.config_json(sim.case.config)
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
