"""``sph sweep``: run a grid of case variants as Dask tasks and gather their summaries.

    sph sweep CASE_DIR --vary KEY=V1,V2,... [--vary ...] [--set KEY=VALUE ...] [--t-end T]
              [--scheduler ADDRESS | --workers N] [--output DIR] [--overwrite]
              [--timeout S] [--error KEY] [--progress auto|bar|log|off] [--dry-run]

1. :func:`plan` expands the grid (:mod:`sphcore.sweep.grid`) and validates every variant
   (case loaded with its overrides, particles built): a malformed one is a
   :class:`CaseError` naming the key and the variant before anything runs.
2. :func:`run` submits one task per variant (:func:`sphcore.sweep.task.run_variant`) to a
   ``distributed.LocalCluster`` sized to the machine (one process and one thread per
   worker, ``NUMBA_NUM_THREADS=1``), or to the scheduler at ``--scheduler``; it shows
   progress as tasks finish, then writes ``sweep.nc`` and ``pareto.png``
   (:mod:`sphcore.sweep.results`). A variant that fails or goes unstable is recorded with
   its status and reason; the others go on.

Dask is imported only here, and only when a sweep runs (the optional extra ``sweep``).
"""

from __future__ import annotations

import json
import logging
import math
import os
import shlex
import signal
import sys
import threading
import time
import uuid
from dataclasses import dataclass
from pathlib import Path

from sphcore import __version__
from sphcore.case.model import case_file, read_toml
from sphcore.errors import CaseError, OutputError

from .grid import Axis, Variant, expand, fold, parse_vary
from .results import default_error_key, grid, plot_pareto, table, to_dataset  # noqa: F401 (grid: API)
from .task import run_variant, stop_running

INSTALL_HINT = 'sph sweep needs Dask: pip install -e ".[sweep]" (dask[distributed])'
RESULTS, PLOT = "sweep.nc", "pareto.png"


class SweepError(Exception):
    """The sweep cannot start: Dask missing, scheduler unreachable, options that clash (exit 2)."""


@dataclass
class Plan:
    """A validated sweep: the variants and what they need to run."""

    case_dir: Path  # absolute: workers may start elsewhere (on a cluster: a shared file system)
    case_name: str
    axes: list[Axis]
    variants: list[Variant]
    sets: list[str]
    t_end: float | None = None


def plan(case_dir, vary=(), sets=(), t_end=None) -> Plan:
    """Expand and validate; raises :class:`CaseError` naming the key and the variant."""
    from sphcore.run import runner
    from sphcore.run.build import build_state

    case_dir = Path(case_dir).resolve()
    file = case_file(case_dir)
    raw = read_toml(file)
    axes = [parse_vary(v) for v in vary]
    variants = expand(axes, list(sets))
    name = ""
    for v in variants:
        try:
            v.overrides = fold(raw, v.overrides, file)
            case, _ = runner.load(case_dir, v.overrides, t_end)
            build_state(case)  # blocks inside the walls, not empty at this dx
        except CaseError as e:
            where = f" (variant {v.name})" if v.values else ""
            raise CaseError(e.file, e.key, e.expected + where) from None
        name = case.name
    return Plan(case_dir, name, axes, variants, list(sets), t_end)


def _distributed():
    try:
        import distributed
    except ImportError as e:
        raise SweepError(f"{INSTALL_HINT}; import failed: {e}") from None
    return distributed


def _client(distributed, scheduler, workers, processes, n_variants):
    """(client, description): a Client of the given scheduler, or of a new LocalCluster."""
    if scheduler:
        try:
            return distributed.Client(scheduler, timeout="20s"), f"scheduler {scheduler}"
        except (OSError, TimeoutError, ValueError, TypeError) as e:
            raise SweepError(f"--scheduler {scheduler}: cannot connect: {e} (expected an address such as "
                             "tcp://host:8786)") from None
    cores = len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count()
    n = max(1, min(workers or cores, n_variants))
    kwargs = {"env": {"NUMBA_NUM_THREADS": "1"}} if processes else {}
    # the worker processes inherit an ignored SIGINT: Ctrl-C is the sweep's to handle (it
    # stops the variants cleanly, see run); a variant's runner installs its own handler
    main = threading.current_thread() is threading.main_thread()
    old = signal.signal(signal.SIGINT, signal.SIG_IGN) if main else None
    try:
        cluster = distributed.LocalCluster(n_workers=n, threads_per_worker=1, processes=processes,
                                           dashboard_address=None, silence_logs=logging.ERROR, **kwargs)
    finally:
        if main:
            signal.signal(signal.SIGINT, old)
    kind = "processes" if processes else "threads"
    return distributed.Client(cluster), f"local cluster of {n} worker {kind}, 1 thread each"


class _Progress:
    """A tqdm bar on a terminal, one line per finished variant in a log."""

    def __init__(self, n, mode="auto", stream=None):
        self.stream = stream or sys.stderr
        if mode == "auto":
            mode = "bar" if self.stream.isatty() else "log"
        self.mode, self.n, self.k, self.bar = mode, n, 0, None
        if mode == "bar":
            from tqdm import tqdm

            self.bar = tqdm(total=n, unit="variant", file=self.stream, dynamic_ncols=True)

    def say(self, text):
        if self.bar is not None:
            self.bar.write(text, file=self.stream)
        elif self.mode == "log":
            print(text, file=self.stream, flush=True)

    def done(self, variant, s):
        self.k += 1
        line = f"{variant.name}: {s.get('status')} ({s.get('task_wall_s', 0):.1f} s)"
        if s.get("status") != "completed":
            line += f": {s.get('message', '')}"
        if self.bar is not None:
            self.bar.set_postfix_str(f"last: {variant.name} {s.get('status')}", refresh=False)
            self.bar.update(1)
            if s.get("status") != "completed":
                self.bar.write(f"[sweep] {line}", file=self.stream)
        elif self.mode == "log":
            print(f"[sweep] {self.k}/{self.n} {line}", file=self.stream, flush=True)

    def close(self):
        if self.bar is not None:
            self.bar.close()


def _interrupt(client, futures, out, summaries, grace_s=60.0):
    """Cancel what has not started, SIGTERM the running variants, and record each stopped
    one from the summary.json its runner writes (status 'stopped')."""
    client.cancel(list(futures))
    try:
        signalled = sum(client.run(stop_running).values())
    except Exception:  # workers already gone
        signalled = 0
    todo = [v for v in futures.values() if v.index not in summaries]
    deadline = time.monotonic() + grace_s
    while True:
        found = {v.index: out / v.name / "summary.json" for v in todo if (out / v.name / "summary.json").exists()}
        if len(found) >= signalled or time.monotonic() > deadline:
            break
        time.sleep(0.2)
    for i, path in found.items():
        try:
            summaries[i] = json.loads(path.read_text())
        except ValueError:
            pass


def run(p: Plan, output=None, scheduler=None, workers=None, processes=True, timeout_s=None, error_key=None,
        overwrite=False, progress="auto", attrs=None):
    """Run every variant of ``p``; writes ``sweep.nc`` and ``pareto.png`` in the sweep
    directory (default ``<case>/sweep``; each variant's own output in a subdirectory named
    after it) and returns the Dataset. ``ds.attrs["interrupted"]`` is 1 after Ctrl-C (the
    variants not done are recorded as 'cancelled')."""
    from sphcore.run import runner

    distributed = _distributed()
    out = Path(output or p.case_dir / "sweep").resolve()
    if out.exists() and not out.is_dir() or any(q.exists() and not q.is_dir() for q in out.parents):
        raise OutputError(f"sweep directory {out}: a file is in the way (expected a directory, or none)")
    if out.exists() and any(out.iterdir()) and not overwrite:
        raise OutputError(f"sweep directory {out} exists and is not empty: pass --overwrite or --output DIR")
    client, where = _client(distributed, scheduler, workers, processes, len(p.variants))
    bar = None
    summaries: dict[int, dict] = {}
    interrupted = False
    token = uuid.uuid4().hex[:8]  # task keys unique on a shared scheduler
    manifest = None
    start = time.time()
    try:
        manifest = runner.prepare_output(out, overwrite)  # refuses a directory sph did not write
        bar = _Progress(len(p.variants), progress)
        bar.say(f"[sweep] {len(p.variants)} variants of {p.case_dir} on a {where}; results in {out}")
        futures = {client.submit(run_variant, str(p.case_dir), str(out / v.name), v.overrides, p.t_end, timeout_s,
                                 key=f"sph-{v.name}-{token}", pure=False): v for v in p.variants}
        try:
            for fut in distributed.as_completed(futures):
                v = futures[fut]
                try:
                    summaries[v.index] = fut.result()
                except Exception as e:  # the task itself died (worker lost, killed)
                    summaries[v.index] = {"status": "failed", "message": f"task lost: {type(e).__name__}: {e}"}
                bar.done(v, summaries[v.index])
        except KeyboardInterrupt:
            interrupted = True
            bar.say("[sweep] interrupted: stopping the running variants (each writes a checkpoint)")
            _interrupt(client, futures, out, summaries)
    finally:
        if manifest is not None:  # the variants have ended: another sweep may use the directory
            manifest.release()
        if bar is not None:
            bar.close()
        cluster = getattr(client, "cluster", None)
        client.close()
        if cluster is not None and not scheduler:
            cluster.close()
    results = [summaries.get(v.index, {"status": "cancelled", "message": "the sweep was interrupted"})
               for v in p.variants]
    meta = {"case": p.case_name, "case_dir": str(p.case_dir), "sphcore_version": __version__,
            "created": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "sweep_wall_s": time.time() - start,
            "cluster": where, "set": json.dumps(p.sets), "interrupted": int(interrupted)}
    if p.t_end is not None:
        meta["t_end"] = p.t_end
    meta.update(attrs or {})
    ds = to_dataset(p.variants, p.axes, results, meta)
    key = error_key or default_error_key(ds)
    if key:
        ds.attrs["error_key"] = key
    ds.to_netcdf(out / RESULTS)
    if key in ds:
        plot_pareto(ds, key, out / PLOT)
    elif error_key:
        numeric = [k for k in ds.data_vars if k not in ("status", "message")]
        print(f"sph: warning: no summary key {error_key!r}, no {PLOT} drawn; keys: {', '.join(numeric)}",
              file=sys.stderr)
    return ds


def _command(args) -> str:
    """The command line, rebuilt from the parsed arguments (stored in sweep.nc)."""
    words = ["sph", "sweep", str(args.case_dir)]
    words += [w for v in args.vary for w in ("--vary", v)] + [w for s in args.overrides for w in ("--set", s)]
    for opt in ("t_end", "output", "scheduler", "workers", "timeout", "error"):
        if getattr(args, opt) is not None:
            words += ["--" + opt.replace("_", "-"), str(getattr(args, opt))]
    return shlex.join(words)


def main(args) -> int:
    """``sph sweep`` (arguments parsed by :mod:`sphcore.cli`). Exit status: 0 every variant
    completed, went unstable or timed out (the sweep's results are what was asked for);
    1 some variant failed (an exception or a lost task: see its message); 2 bad input or
    no Dask, nothing run; 130 interrupted (what finished is written)."""
    from sphcore.plugin.pluginhost import PluginLoadError

    try:
        if args.scheduler and args.workers:
            raise SweepError("--workers sizes the local cluster; a --scheduler cluster has its own workers")
        if args.workers is not None and args.workers < 1:
            raise SweepError(f"--workers {args.workers}: expected a positive number")
        if args.timeout is not None and not (math.isfinite(args.timeout) and args.timeout > 0):
            raise SweepError(f"--timeout {args.timeout}: expected a positive number of seconds")
        p = plan(args.case_dir, args.vary, args.overrides, args.t_end)
        if args.dry_run:
            for v in p.variants:
                print(f"{v.name}: " + " ".join(f"--set {k}={json.dumps(x)}" for k, x in v.values.items()))
            print(f"{len(p.variants)} variants of {p.case_dir}: all valid")
            return 0
        ds = run(p, args.output, args.scheduler, args.workers, True, args.timeout, args.error, args.overwrite,
                 args.progress or "auto", {"command": _command(args)})
    except (CaseError, OutputError, SweepError, PluginLoadError) as e:
        print(f"sph: error: {e}", file=sys.stderr)
        return 2
    out = Path(args.output or p.case_dir / "sweep").resolve()
    print(table(ds, ds.attrs.get("error_key")))
    drawn = f" and {out / PLOT}" if (out / PLOT).exists() else ""
    print(f"wrote {out / RESULTS}{drawn}")
    if ds.attrs["interrupted"]:
        return 130
    return 1 if any(s in ("failed", "output_error") for s in ds["status"].values) else 0
