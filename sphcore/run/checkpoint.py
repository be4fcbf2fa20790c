"""Checkpoints: everything a run needs to continue bit-for-bit, in one ``.npz``.

Saved: the run state (:meth:`sphcore.run.state.RunState.payload`: every particle array
(float64 as is), the rates of the current state, which the leapfrog reuses at the start of
the next step, the pair-list anchor, t, step, dt, the plugins' figures and kept state), the
validated case and the run's identity. The file is written to a temporary name and renamed,
so a crash mid-write keeps the previous one (:mod:`sphcore.io.atomic`); a restart reads it back with :func:`read` and
:meth:`sphcore.run.state.RunState.load_payload`.
"""

from __future__ import annotations

import json
import zipfile
from pathlib import Path

import numpy as np

from sphcore.errors import CaseError
from sphcore.io.atomic import write_atomically
from sphcore.run import resume

NAME = "checkpoint.npz"
#: what numpy raises on a file that is not a whole checkpoint (empty, cut, another format)
UNREADABLE = (OSError, EOFError, ValueError, KeyError, zipfile.BadZipFile)


def save(sim, directory: Path, extra: dict | None = None) -> Path:
    """Write the checkpoint; ``extra`` (the run's identity and history, see
    :mod:`sphcore.run.resume`) goes into its metadata."""
    path = Path(directory) / NAME
    meta, arrays = sim.run.payload()
    meta["config"] = resume.config_json(sim.case.config)
    meta.update(extra or {})

    def write(tmp):
        with open(tmp, "wb") as f:  # a file object: np.savez would add ".npz" to a name
            np.savez(f, meta=np.array(json.dumps(meta, default=float)), **arrays)

    write_atomically(path, write, what="the checkpoint")
    return path


def read(directory: Path) -> tuple[dict, dict]:
    """(metadata, arrays) of ``directory``/checkpoint.npz."""
    path = Path(directory) / NAME
    if not path.exists():
        raise CaseError(path, "--restart", "no checkpoint to restart from in this output directory")
    try:
        with np.load(path) as z:
            meta = json.loads(str(z["meta"]))
            arrays = {k: z[k].copy() for k in z.files if k != "meta"}
    except UNREADABLE as e:
        raise CaseError(path, "--restart", f"not a readable checkpoint ({type(e).__name__}: {e})") from None
    return meta, arrays


def read_meta(directory: Path) -> dict:
    """Only the metadata of ``directory``/checkpoint.npz (the arrays stay on disk)."""
    path = Path(directory) / NAME
    if not path.exists():
        raise CaseError(path, "--restart", "no checkpoint to restart from in this output directory")
    try:
        with np.load(path) as z:
            return json.loads(str(z["meta"]))
    except UNREADABLE as e:
        raise CaseError(path, "--restart", f"not a readable checkpoint ({type(e).__name__}: {e})") from None
