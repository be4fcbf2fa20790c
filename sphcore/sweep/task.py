"""One sweep variant as a Dask task: ``runner.run`` in a fresh Python process.

Why a process of its own rather than ``runner.run`` in the worker's thread:

- ``runner.run`` installs SIGINT/SIGTERM handlers (to checkpoint on a stop), and Python
  allows that only in a process's main thread; Dask runs tasks in worker threads;
- ``peak_memory_mb`` in the summary is the process's peak RSS: in a fresh process it is the
  variant's own, not the largest of every variant the worker ran before;
- a crash (a segfault in a kernel, the OOM killer) loses the variant, not the worker, and a
  per-variant time limit can stop a run cleanly (SIGTERM: checkpoint and summary).

The price is a Python start and the numba cache load, about 2 s per variant.
"""

from __future__ import annotations

import json
import math
import os
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

GRACE_S = 60.0  # after SIGTERM, how long a run may take to write its checkpoint and summary
LOG = "sweep.log"  # the variant process's stdout and stderr, kept when not empty
_CHILD = "from sphcore.sweep.task import child_main; child_main()"
_RUNNING: set = set()  # this worker's variant processes, for stop_running


def _jsonable(x):
    if hasattr(x, "item"):  # numpy scalars
        return x.item()
    if hasattr(x, "tolist"):
        return x.tolist()
    return str(x)


def run_variant(case_dir: str, output: str, overrides: list, t_end: float | None = None,
                timeout_s: float | None = None) -> dict:
    """Run one variant; returns its summary (as summary.json holds it) plus ``task_wall_s`` (s, the
    process's whole life). Never raises: a run that cannot start or crashes comes back
    with status 'failed', one that passes ``timeout_s`` with status 'timeout'."""
    start = time.perf_counter()
    fd, result_file = tempfile.mkstemp(prefix="sph-sweep-", suffix=".json")
    os.close(fd)
    payload = {"case_dir": str(case_dir), "output": str(output), "overrides": [list(o) for o in overrides],
               "t_end": t_end, "result": result_file}
    env = dict(os.environ)
    env.setdefault("NUMBA_NUM_THREADS", "1")  # variants share the cores; the worker's setting wins
    timed_out = False
    proc = subprocess.Popen([sys.executable, "-c", _CHILD], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
                            stderr=subprocess.STDOUT, env=env, text=True)
    _RUNNING.add(proc)
    try:
        log, _ = proc.communicate(json.dumps(payload, default=_jsonable), timeout=timeout_s)
    except subprocess.TimeoutExpired:
        timed_out = True
        proc.send_signal(signal.SIGTERM)  # the runner checkpoints and writes its summary
        try:
            log, _ = proc.communicate(timeout=GRACE_S)
        except subprocess.TimeoutExpired:
            proc.kill()
            log, _ = proc.communicate()
    finally:
        _RUNNING.discard(proc)
        if proc.poll() is None:  # the task itself was interrupted: leave no orphan behind
            proc.kill()
            proc.wait()
    try:
        text = Path(result_file).read_text()
        summary = json.loads(text) if text else None
    except (OSError, ValueError):
        summary = None
    finally:
        Path(result_file).unlink(missing_ok=True)
    if summary is None:
        tail = (log or "").strip().splitlines()[-1:] or ["no output"]
        summary = {"status": "failed",
                   "message": f"the run's process ended with status {proc.returncode} and no summary: {tail[0]}"}
    if timed_out:
        t = summary.get("t", math.nan)
        summary["status"] = "timeout"
        summary["message"] = (f"still running after --timeout {timeout_s:g} s, stopped at t = {t:.6g} s"
                              + ("; checkpoint written" if summary.get("message", "").startswith("stopped") else ""))
    summary["task_wall_s"] = time.perf_counter() - start
    if log and log.strip() and Path(output).is_dir():
        (Path(output) / LOG).write_text(log)
    return summary


def stop_running() -> int:
    """SIGTERM every variant process of this worker (each writes a checkpoint and its
    summary, status 'stopped'); the number signalled. Sent to every worker on Ctrl-C."""
    procs = [p for p in list(_RUNNING) if p.poll() is None]
    for p in procs:
        p.send_signal(signal.SIGTERM)
    return len(procs)


def child_main():
    """In the variant's process: read the payload on stdin, run, write the summary."""
    payload = json.loads(sys.stdin.read())
    from sphcore.errors import CaseError, OutputError
    from sphcore.plugin import pluginhost
    from sphcore.run import runner

    try:
        summary = runner.run(payload["case_dir"], payload["output"], [tuple(o) for o in payload["overrides"]],
                             payload["t_end"], overwrite=True, quiet=True).summary
    except (CaseError, OutputError, pluginhost.PluginLoadError) as e:
        summary = {"status": "failed", "message": str(e)}
    except Exception as e:  # a bug: the traceback goes to the variant's log
        import traceback

        traceback.print_exc()
        summary = {"status": "failed", "message": f"{type(e).__name__}: {e} (traceback in {LOG})"}
    Path(payload["result"]).write_text(json.dumps(summary, default=_jsonable))
