"""Run a case directory end to end: load, build, prepare the output directory, step, summarise.

    run(case_dir) = load -> build (sphcore.run.build) -> first-step check -> output directory
                    -> steps, with the activities on their schedules -> summary.json -> RunResult

Used by the CLI (``sph run``) and by sweeps; returns a :class:`RunResult`.
"""

from __future__ import annotations

import json
import resource
import signal
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

import numba

from sphcore.case.model import apply_overrides, case_file, parse_override, read_toml, validate
from sphcore.case.overrides import key_text
from sphcore.errors import CaseError, Instability, OutputError
from sphcore.io import outdir
from sphcore.io.atomic import write_text_atomically
from sphcore.jit import prepare
from sphcore.plugin import pluginhost
from sphcore.run import budget, checkpoint, relax, resume, threads
from sphcore.run.activities import Activity, EveryStep, periodic
from sphcore.run.build import build
from sphcore.run.progress import Progress

MARKER = outdir.MARKER  # only directories whose marker proves it are overwritten (see outdir)


@dataclass
class RunResult:
    """What a run ended with: ``status`` ("completed", "unstable", "stopped", "output_error"
    or "failed"), ``message`` (empty when completed), ``summary`` (what summary.json holds),
    ``simulation`` (the Simulation as the run left it: its run state, plugins and context)
    and ``signum`` (the signal that stopped it, or None). ``result[key]`` and
    ``result.get(key)`` read the summary."""

    status: str
    message: str
    summary: dict
    simulation: object
    signum: int | None = None

    def __getitem__(self, key):
        return self.summary[key]

    def get(self, key, default=None):
        return self.summary.get(key, default)

    def __contains__(self, key) -> bool:
        return key in self.summary

    def keys(self):
        return self.summary.keys()

    def items(self):
        return self.summary.items()

    @property
    def t(self) -> float:
        return self.summary["t"]

    @property
    def steps(self) -> int:
        return self.summary["steps"]

    @property
    def output_dir(self) -> Path:
        return Path(self.summary["output_dir"])

    @property
    def state(self):
        """The run state (:class:`sphcore.run.state.RunState`) at the end."""
        return self.simulation.run


class Stopped(Exception):
    """SIGINT or SIGTERM arrived; a checkpoint was written."""

    def __init__(self, signum):
        self.signum = signum
        super().__init__(f"stopped by {signal.Signals(signum).name}")


def blame_option(err: CaseError, overrides, t_end) -> CaseError:
    """A CaseError about a key given on the command line names the option, not case.toml."""
    if t_end is not None and err.key == "time.t_end":
        return CaseError("--t-end", err.key, err.expected)
    for text in reversed(list(overrides or ())):
        path = parse_override(text)[0] if isinstance(text, str) else text[0]
        dotted = key_text(path)
        if err.key == dotted or err.key.startswith(dotted + ".") or err.key.startswith(dotted + "["):
            return CaseError("--set", err.key, err.expected)
    return err


def load(case_dir, overrides=(), t_end=None):
    """(case, plugin manager) for a case directory, with --set overrides applied."""
    prepare()  # before any kernel of the run: OpenMP settings, numba's cache checked
    file = case_file(case_dir)
    raw = apply_overrides(read_toml(file), overrides)
    if t_end is not None:
        raw = apply_overrides(raw, [(["time", "t_end"], t_end)])
    try:
        case = validate(raw, file, pluginhost.option_schemas(file, raw))
        budget.check_scales(case)
        budget.check_memory(case)  # particles and memory, before anything is allocated
        relax.check(case)
        pm = pluginhost.make_manager(case.config["plugins"]["use"], file)
        pluginhost.configure(pm, case)  # plugins check their own tables
    except CaseError as e:
        raise blame_option(e, overrides, t_end) from None
    return case, pm


def first_step(sim, overrides=(), t_end=None) -> float:
    """The first step's size (s), checked (:func:`sphcore.run.budget.check_first_step`);
    a refusal about a key given on the command line names the option."""
    try:
        return budget.check_first_step(sim)
    except CaseError as e:
        raise blame_option(e, overrides, t_end) from None


def output_path(case, output=None) -> Path:
    """--output as given, else output.dir inside the case directory (see outdir.resolve)."""
    return outdir.resolve(case, output)


def prepare_output(out: Path, overwrite=False, restart=False, case_file=None, lock=None) -> "outdir.Manifest":
    """Create the output directory; never clobber one silently (sweeps call this too).
    ``lock``: the directory's writer lock, when the caller holds it already."""
    if restart and not (Path(out) / checkpoint.NAME).exists():
        if lock is not None:
            lock.release()
        raise CaseError(Path(out) / checkpoint.NAME, "--restart", "no checkpoint to restart from")
    return outdir.prepare(out, case_file, overwrite, restart, lock)


def peak_memory_mb() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0  # Linux: kB


def _jsonable(o):
    """numpy scalars and arrays in a summary, as JSON numbers and lists."""
    return o.tolist() if hasattr(o, "tolist") else float(o)


def _write_json(path: Path, data: dict):
    write_text_atomically(path, json.dumps(data, indent=2, default=_jsonable) + "\n")


def run(case_dir, output=None, overrides=(), t_end=None, overwrite=False, restart=False, progress=None,
        quiet=False) -> RunResult:
    case, pm = load(case_dir, overrides, t_end)
    out = output_path(case, output)
    mode = "off" if quiet else (progress or case.config["output"]["progress"])
    saved, lock = None, None
    if restart and (out / checkpoint.NAME).is_file() and not out.is_symlink():
        # a live run may be writing the directory: refused before its checkpoint is read
        lock = outdir.WriterLock(out)
    try:
        if restart:  # continue the same run only: case, version and directory must match
            saved = checkpoint.read_meta(out)
            resume.verify(saved, case, out, out / checkpoint.NAME)
        # sizing the first step below evaluates the forces: that compiles the force kernels on a
        # fresh machine (said before it starts; checked after it, the cache would always hold them)
        if mode != "off" and not kernels_cached(case.config["case"]["dim"], case.config["scheme"]["name"]):
            print("[sph] compiling kernels, once (about 10 s; later runs load them from the cache)",
                  file=sys.stderr, flush=True)
        if mode != "off" and not restart and case.config["relax"]["time"] > 0:
            print(f"[sph] relaxing the start: {case.config['relax']['time']:g} s of damped motion before t = 0",
                  file=sys.stderr, flush=True)
        # particles and plugins are set up, and the first step sized, before anything touches
        # the disk: a case that fails there leaves the output directory as it was
        try:
            sim = build(case, pm, out, restarting=restart)
        except CaseError as e:  # the relaxation's errors name its key, which may have come from --set
            raise blame_option(e, overrides, t_end) from None
        relaxed = sim.ctx.stats("core").get("relax")
        if relaxed and mode != "off" and not restart:
            print(f"[sph] relaxed in {relaxed['wall_time_s']:.1f} s: particles moved up to {relaxed['max_move_dx']:.3g} dx, "
                  f"last speed {relaxed['last_speed_m_s']:.2g} m/s", file=sys.stderr, flush=True)
        first_step(sim, overrides, t_end)
        manifest = prepare_output(out, overwrite, restart, case.file, lock)
    except BaseException:
        if lock is not None:
            lock.release()
        raise
    past = resume.history(saved)
    stop = {"signum": None}

    def on_signal(signum, frame):
        stop["signum"] = signum

    # signal handlers can only be installed from the main thread (a Dask worker runs tasks
    # in threads): elsewhere the run just has no checkpoint-on-signal
    old = ({s: signal.signal(s, on_signal) for s in (signal.SIGINT, signal.SIGTERM)}
           if threading.current_thread() is threading.main_thread() else {})
    bar = Progress(sim.t_end, sim.state.n, mode, case.config["output"]["log_interval_s"])
    start, step0, status, message = time.perf_counter(), sim.step, "failed", "an unexpected error (a bug: see the traceback)"

    def segments(state, wall):
        return past["segments"] + [{"steps": sim.step - step0, "wall_time_s": wall,
                                    "t_start": saved["t"] if saved else 0.0, "t_end": sim.t, "status": state}]

    def save_checkpoint(state="running"):
        # the checkpoint carries the run's identity (checked by --restart) and its history,
        # so that the summary after a restart covers every segment
        wall = time.perf_counter() - start
        checkpoint.save(sim, out, {**resume.identity(case, out), "segments": segments(state, wall),
                                   "wall_time_total_s": past["wall_time_s"] + wall})
        manifest.update()

    tuner, threads_before = threads.tuner_for(case.config), numba.get_num_threads()
    numba.set_num_threads(tuner.current)
    step_wall = [0.0]  # wall time of the step just taken (s), for the thread tuner

    def tune(sim):
        count = tuner.after_step(step_wall[0])
        if count != numba.get_num_threads():
            numba.set_num_threads(count)

    def stop_if_asked(sim):
        if stop["signum"] is not None:
            save_checkpoint("stopped")
            raise Stopped(stop["signum"])

    # after each step, in this order (sphcore.run.activities)
    after_step = [Activity("threads", EveryStep(), tune),
                  Activity("writers", EveryStep(), lambda sim: sim.output()),
                  Activity("progress", EveryStep(), bar.update),
                  Activity("signal", EveryStep(), stop_if_asked),
                  Activity("checkpoint", periodic(case.config["output"]["checkpoint_every_s"],
                                                  case.config["output"]["checkpoint_every_dt"], sim.t),
                           lambda sim: save_checkpoint())]
    try:
        if not restart:
            save_checkpoint()  # a restart point exists before any frame, whatever stops the run
        if sim.step == 0:  # a fresh run, or a restart from that first checkpoint: frame 0
            sim.output()
        while not sim.done():
            t0 = time.perf_counter()
            sim.advance()
            step_wall[0] = time.perf_counter() - t0
            for activity in after_step:
                activity(sim)
        sim.output(final=True)
        save_checkpoint("completed")
        status, message = "completed", ""
    except Instability as e:
        status, message = "unstable", str(e)
    except CaseError as e:  # found only while stepping (no limit on dt any more): exit 1, output kept
        status, message = "unstable", f"at step {sim.step}, t = {sim.t:.6g} s: {e}"
    except OutputError as e:
        # no new checkpoint: the last one (periodic or at the start) matches the files on disk
        status, message = "output_error", (f"{e}; the last checkpoint and the files before it are kept (--restart)"
                                           if (out / checkpoint.NAME).exists() else
                                           f"{e}; no checkpoint could be written: run again with --overwrite")
    except Stopped as e:
        status, message = "stopped", f"{e}; checkpoint written, continue with --restart"
        stop["stopped_by"] = e.signum
    finally:
        bar.close()
        numba.set_num_threads(threads_before)
        for s, h in old.items():
            signal.signal(s, h)
        wall = time.perf_counter() - start
        total_wall = past["wall_time_s"] + wall
        steps = sim.step  # the whole run, every segment (a restart continues the count)
        summary = {
            "case": case.name, "status": status, "message": message, "output_dir": str(out),
            "t": sim.t, "wall_time_s": total_wall, "steps": steps, "n_particles": sim.state.n,
            "particle_steps_per_s": steps * sim.state.n / total_wall if total_wall > 0 else 0.0,
            "peak_memory_mb": peak_memory_mb(),
            "c0": sim.params.c0, "h": sim.params.h, "plugins": case.config["plugins"]["use"],
            "counters": dict(sim.counters),
            "threads": tuner.summary(),
            "segments": segments(status, wall),
            "config": case.config,  # the validated case after --set: what post-processing reads
        }
        # each of these may meet a full disk (front.csv, summary.json): what was written
        # before is kept, the writers are still closed, and the run reports the error
        try:
            for write in (lambda: summary.update(pluginhost.summaries(pm, sim.ctx)),
                          lambda: pm.hook.sph_finish(ctx=sim.ctx),
                          lambda: _write_json(out / "summary.json", summary),
                          manifest.update):
                try:
                    write()
                except OutputError as e:
                    if summary["status"] in ("completed", "stopped"):
                        summary["status"] = "output_error"
                        summary["message"] = f"{e}; the last checkpoint is kept (--restart)"
                    elif summary["status"] != "failed":
                        summary["message"] += f"; also {e}"
        finally:
            manifest.release()  # another run may write this directory now
    return RunResult(summary["status"], summary["message"], summary, sim, stop.get("stopped_by"))


def kernels_cached(dim: int = 2, scheme: str = "wcsph") -> bool:
    """Whether numba's cache holds the largest kernels of a ``dim``-dimensional run of
    ``scheme`` already (else the first step compiles them): the weakly compressible pair
    loop, or the divergence-free scheme's rates over its pair list and the list's fill
    (built per dimension; a dfsph run with the wall model never walks the cells)."""
    if scheme == "dfsph":
        from sphcore.physics import listedrates

        return listedrates.compiled_on_disk(dim)
    from sphcore.physics import equations

    return equations.compiled_on_disk(dim)
