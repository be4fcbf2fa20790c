"""Continuing runs: what a checkpoint must match for ``--restart`` to continue it, and the
run's history across segments (for the summary).

A restart continues the same run only: the case after ``--set`` (except the keys in
:data:`MAY_DIFFER` and plugin options declared with ``Option(restart=True)``), the sphcore
version, the case file and the output directory must be those recorded in the checkpoint.
Otherwise frames of another run would be appended to the same files; the restart is refused
(exit status 2) with what differs.
"""

from __future__ import annotations

import json
from pathlib import Path

from sphcore import __version__
from sphcore.errors import CaseError

#: core keys a restart may change: how far to run, and how the run reports and checkpoints
#: (a plugin marks its own with ``Option(restart=True)``)
MAY_DIFFER = {"time.t_end", "output.progress", "output.log_interval_s", "output.checkpoint_every_s",
              "output.checkpoint_every_dt", "output.dir", "particles.memory_limit_gib", "time.max_steps",
              "parallel.threads", "parallel.adapt"}  # the same bits for any thread count


def _flat(config: dict, prefix="") -> dict:
    out = {}
    for k, v in config.items():
        key = f"{prefix}{k}"
        if isinstance(v, dict):
            out.update(_flat(v, key + "."))
        else:
            out[key] = v
    return out


def config_json(config: dict) -> str:
    """The canonical text of a validated config, as the checkpoint stores it."""
    return json.dumps(config, default=str, sort_keys=True)


def identity(case, out: Path) -> dict:
    """What a checkpoint records about the run it belongs to."""
    return {"version": __version__, "case_file": str(Path(case.file).resolve()),
            "output_dir": str(Path(out).resolve())}


def verify(meta: dict, case, out: Path, file) -> None:
    """Refuse (CaseError naming the checkpoint ``file`` and what differs) to restart a
    checkpoint of another run."""
    saved_version = meta.get("version", "unknown (written before restarts were checked)")
    if saved_version != __version__:
        raise CaseError(file, "version", f"written by sphcore {saved_version}, this is {__version__}: "
                        "a restart continues only with the same code (run without --restart, or with --overwrite)")
    mine = identity(case, out)
    for key, what in (("case_file", "case file"), ("output_dir", "output directory")):
        if meta.get(key) is not None and meta[key] != mine[key]:
            raise CaseError(file, key, f"the checkpoint belongs to {what} {meta[key]}, not {mine[key]}")
    old = _flat(json.loads(meta["config"])) if "config" in meta else {}
    new = _flat(json.loads(config_json(case.config)))
    # a table only one side has, of a plugin the run does not use (installed or removed in
    # between), does not change the run
    used = set(case.config["plugins"]["use"])
    one_sided = ({k.split(".")[0] for k in old} ^ {k.split(".")[0] for k in new}) - used
    may_differ = MAY_DIFFER | getattr(case, "restart_keys", frozenset())
    diff = [k for k in sorted(set(old) | set(new))
            if k not in may_differ and k.split(".")[0] not in one_sided and old.get(k) != new.get(k)]
    if diff:
        shown = "; ".join(f"{k} = {old.get(k, '(unset)')!r} in the checkpoint, {new.get(k, '(unset)')!r} now"
                          for k in diff[:3])
        more = f" (and {len(diff) - 3} more)" if len(diff) > 3 else ""
        raise CaseError(file, diff[0], f"the case differs from the run being continued: {shown}{more}; "
                        "a restart continues the same case (only time.t_end and output settings may change)")


def history(meta: dict | None) -> dict:
    """The run's totals before this segment: wall time (s) and the segments so far."""
    if not meta:
        return {"wall_time_s": 0.0, "segments": []}
    return {"wall_time_s": float(meta.get("wall_time_total_s", 0.0)), "segments": list(meta.get("segments", []))}
