"""Run a case directory end to end: load, prepare the output directory, step, summarise.

Used by the CLI (``sph run``) and by sweeps; returns the summary as a dict.
"""

from __future__ import annotations

import json
import os
import resource
import shutil
import signal
import threading
import time
from pathlib import Path

from . import checkpoint, pluginhost
from .case import apply_overrides, case_file, read_toml, validate
from .errors import CaseError, Instability, OutputError
from .progress import Progress
from .simulation import Simulation

MARKER = ".sphcore-output"  # only directories holding it may be overwritten


class Stopped(Exception):
    """SIGINT or SIGTERM arrived; a checkpoint was written."""

    def __init__(self, signum):
        self.signum = signum
        super().__init__(f"stopped by {signal.Signals(signum).name}")


def load(case_dir, overrides=(), t_end=None):
    """(case, plugin manager) for a case directory, with --set overrides applied."""
    file = case_file(case_dir)
    raw = apply_overrides(read_toml(file), overrides)
    if t_end is not None:
        raw = apply_overrides(raw, [(["time", "t_end"], t_end)])
    case = validate(raw, file, pluginhost.option_schemas(file, raw))
    pm = pluginhost.make_manager(case.config["plugins"]["use"], file)
    pluginhost.configure(pm, case)
    return case, pm


def output_path(case, output=None) -> Path:
    return Path(output) if output is not None else case.dir / case.config["output"]["dir"]


def prepare_output(out: Path, overwrite=False, restart=False) -> Path:
    """Create the output directory; never clobber one silently."""
    if out.exists() and (not out.is_dir() or any(out.iterdir())) and not restart:  # a file is never a run's directory
        if not overwrite:
            raise OutputError(f"output directory {out} exists and is not empty: pass --overwrite, --restart or --output DIR")
        if not (out / MARKER).exists():
            raise OutputError(f"refusing to overwrite {out}: it was not written by sph (no {MARKER} file)")
        shutil.rmtree(out)
    if restart and not (out / checkpoint.NAME).exists():
        raise CaseError(out / checkpoint.NAME, "--restart", "no checkpoint to restart from")
    try:
        out.mkdir(parents=True, exist_ok=True)
        (out / MARKER).touch()
    except OSError as e:
        raise OutputError(f"cannot create output directory {out}: {e.strerror}") from e
    return out


def peak_memory_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: kB


def _jsonable(o):
    """numpy scalars and arrays in a summary, as JSON numbers and lists."""
    return o.tolist() if hasattr(o, "tolist") else float(o)


def _write_json(path: Path, data: dict):
    tmp = path.with_suffix(".tmp")
    tmp.write_text(json.dumps(data, indent=2, default=_jsonable) + "\n")
    os.replace(tmp, path)


def run(case_dir, output=None, overrides=(), t_end=None, overwrite=False, restart=False, progress=None,
        quiet=False) -> dict:
    case, pm = load(case_dir, overrides, t_end)
    out = output_path(case, output)
    if restart and not (out / checkpoint.NAME).exists():
        raise CaseError(out / checkpoint.NAME, "--restart", "no checkpoint to restart from")
    # particles and plugins are set up before anything touches the disk: a case that
    # fails there leaves the output directory as it was
    sim = Simulation(case, pm, out, restarting=restart)
    prepare_output(out, overwrite, restart)
    stop = {"signum": None}

    def on_signal(signum, frame):
        stop["signum"] = signum

    # signal handlers can only be installed from the main thread (a Dask worker runs tasks
    # in threads): elsewhere the run just has no checkpoint-on-signal
    old = ({s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
           if threading.current_thread() is threading.main_thread() else {})
    mode = "off" if quiet else (progress or case.config["output"]["progress"])
    bar = Progress(sim.t_end, sim.state.n, mode, case.config["output"]["log_interval_s"])
    start, step0, status, message = time.perf_counter(), sim.step, "failed", "an unexpected error (a bug: see the traceback)"
    try:
        if not restart:
            sim.output()
        while not sim.done():
            sim.advance()
            sim.output()
            bar.update(sim)
            if stop["signum"] is not None:
                checkpoint.save(sim, out)
                raise Stopped(stop["signum"])
        sim.output(final=True)
        checkpoint.save(sim, out)
        status, message = "completed", ""
    except Instability as e:
        status, message = "unstable", str(e)
    except OutputError as e:
        status, message = "output_error", str(e)
    except Stopped as e:
        status, message = "stopped", f"{e}; checkpoint written, continue with --restart"
        stop["stopped_by"] = e.signum
    finally:
        bar.close()
        for s, h in old.items():
            signal.signal(s, h)
        wall = time.perf_counter() - start
        steps = sim.step - step0
        summary = {
            "case": case.name, "status": status, "message": message, "output_dir": str(out),
            "t": sim.t, "wall_time_s": wall, "steps": steps, "n_particles": sim.state.n,
            "particle_steps_per_s": steps * sim.state.n / wall if wall > 0 else 0.0,
            "peak_memory_mb": peak_memory_mb(),
            "c0": sim.params.c0, "h": sim.params.h, "plugins": case.config["plugins"]["use"],
            "counters": dict(sim.counters),
            "config": case.config,  # the validated case after --set: what post-processing reads
        }
        summary.update(pluginhost.summaries(pm, sim.ctx))
        pm.hook.sph_finish(ctx=sim.ctx)
        _write_json(out / "summary.json", summary)
    summary["_sim"] = sim
    summary["_signum"] = stop.get("stopped_by")
    return summary
