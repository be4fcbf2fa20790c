"""What the validation pages share: running a case with ``sph run``, reusing a finished run,
reading its summary, formatting figures and Markdown tables, saving figures.

A page runs each of its cases through :func:`run_case`, which calls ``sph run`` as a
subprocess (the command a user would type) into ``<runs>/<label>/`` and reuses that run when
it is already there, finished, and was made from the same command and the same case files
(see :func:`stamp`). ``rerun=True`` runs it again whatever is there.
"""

from __future__ import annotations

import hashlib
import importlib.util
import json
import math
import shutil
import subprocess
import sys
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[2]  # the repository
CASES = ROOT / "cases"
POSTPROCESSING = ROOT / "postprocessing"
STAMP = ".stamp.json"  # <run folder>.stamp.json, beside the run folder: what the run is made from
FINISHED = ("completed", "unstable")  # a run that ended by itself; "failed" runs again
STOPPED = "stopped"  # stopped by a signal (Ctrl-C): continued from its checkpoint with --restart
DPI = 80  # figures' resolution: a 6 x 4 inch plot is ~50 KB

# the boundary treatments the pages compare: label -> the wall plugins (before the case's gauges)
REFLECTIVE = "reflective"
WALL_MODEL = "reflective + wall model"
GHOST = "ghost + reflective"
TREATMENTS = {
    REFLECTIVE: ["reflective"],
    WALL_MODEL: ["reflective", "wall_integral"],
    GHOST: ["ghost", "reflective"],
}


def plugins_set(plugins: list[str]) -> str:
    """The ``--set`` value that makes ``plugins`` the run's plugin list (TOML strings)."""
    return "plugins.use=[" + ", ".join(f'"{p}"' for p in plugins) + "]"


def case_digest(case_dir: Path) -> str:
    """SHA-256 of the case's files (case.toml and anything beside it the case may read;
    output folders and the README, the case's notes, left out): a run made from an edited
    case is not reused."""
    h = hashlib.sha256()
    for f in sorted(case_dir.rglob("*")):
        rel = f.relative_to(case_dir)
        if (not f.is_file() or rel.parts[0].startswith(("output", "sweep")) or "__pycache__" in rel.parts
                or rel.name == "README.md"):
            continue
        h.update(str(rel).encode() + b"\0" + f.read_bytes() + b"\0")
    return h.hexdigest()


def stamp(case_dir: Path, args: list[str]) -> dict:
    """What a run is made from: the ``sph run`` arguments after the output folder and the
    digest of the case's files. A run is reused only if its stamp is equal to this one."""
    return {"command": ["sph", "run", str(case_dir.relative_to(ROOT)), *args], "case_sha256": case_digest(case_dir)}


def read_summary(out: Path) -> dict | None:
    """The run's summary.json, or None when there is none (or it cannot be read)."""
    try:
        return json.loads((out / "summary.json").read_text())
    except (OSError, ValueError):
        return None


def stamp_file(out: Path) -> Path:
    """Where the stamp of the run in ``out`` is kept: beside the folder (sph writes only into
    an empty folder or one it wrote), written before the run starts."""
    return out.with_name(out.name + STAMP)


def reusable(out: Path, want: dict) -> dict | None:
    """The summary of the run in ``out`` if it was made from ``want`` (its stamp) and ended
    (completed, or stopped by an instability, which a rerun would repeat), or was stopped by
    a signal with a checkpoint to continue from; else None."""
    s = read_summary(out)
    try:
        have = json.loads(stamp_file(out).read_text())
    except (OSError, ValueError):
        return None
    if s is None or have != want:
        return None
    if s.get("status") in FINISHED or (s.get("status") == STOPPED and (out / "checkpoint.npz").exists()):
        return s
    return None


def run_case(case: str, out: Path, sets: list[str] = (), t_end: float | None = None, rerun: bool = False) -> dict:
    """Run ``cases/<case>`` into ``out`` with ``sph run --set ...`` and return its summary, with
    ``"reused": True`` when nothing was run. A run made by the same command from the same
    case files is reused if it ended, continued with ``--restart`` if it was stopped (Ctrl-C
    on the build stops the run at a checkpoint), and run again otherwise or with ``rerun``."""
    case_dir = CASES / case
    args = [a for s in sets for a in ("--set", s)]
    if t_end is not None:
        args += ["--t-end", repr(float(t_end))]
    want = stamp(case_dir, args)
    s = None if rerun else reusable(out, want)
    if s is not None and s["status"] != STOPPED:
        print(f"  {out.name}: reused ({s['status']}, {s['wall_time_s']:.0f} s when run)", flush=True)
        return {**s, "reused": True}
    restart = s is not None
    if not restart:
        if out.exists():
            shutil.rmtree(out)  # the runs folder is the build's own: a stale or partial run goes
        out.parent.mkdir(parents=True, exist_ok=True)
        stamp_file(out).write_text(json.dumps(want, indent=1) + "\n")
    cmd = [sys.executable, "-m", "sphcore.cli", "run", str(case_dir), "--output", str(out),
           "--progress", "off", *args, *(["--restart"] if restart else [])]
    t0 = time.perf_counter()
    p = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True)
    s = read_summary(out)
    if s is None:
        raise RuntimeError(f"sph run {case} wrote no summary.json (exit {p.returncode}):\n{p.stderr[-2000:]}")
    print(f"  {out.name}: {s['status']}{' (continued)' if restart else ''} in {time.perf_counter() - t0:.0f} s",
          flush=True)
    return {**s, "reused": False}


def load(path: Path, name: str):
    """The Python file ``path`` loaded as the module ``name`` (kept in sys.modules)."""
    if name not in sys.modules:
        spec = importlib.util.spec_from_file_location(name, path)
        mod = importlib.util.module_from_spec(spec)
        sys.modules[name] = mod
        spec.loader.exec_module(mod)
    return sys.modules[name]


def toolkit(script: str):
    """``postprocessing/<script>.py`` as a module, for its definitions (the same figures the
    script prints). The toolkit's scripts import their siblings ``runs`` and the theory
    modules (``*_theory.py``, which read no run) by name, as Python finds them when a script
    runs from its folder: they are loaded first under those names."""
    runs = load(POSTPROCESSING / "runs.py", "runs")
    for theory in sorted(POSTPROCESSING.glob("*_theory.py")):
        load(theory, theory.stem)
    return runs if script == "runs" else load(POSTPROCESSING / f"{script}.py", f"postprocessing_{script}")


def postprocess(script: str, *args) -> subprocess.CompletedProcess:
    """Run ``postprocessing/<script>`` with ``args`` (its output kept from the console)."""
    return subprocess.run([sys.executable, str(POSTPROCESSING / script), *map(str, args)], cwd=ROOT, check=True,
                          capture_output=True, text=True)


def missing(v) -> bool:
    return v is None or (isinstance(v, float) and math.isnan(v))


def pct(v, signed: bool = True, digits: int = 1) -> str:
    """A fraction as a percentage (``+3.2 %``); ``-`` for a missing figure."""
    if missing(v):
        return "-"
    return f"{100 * v:{'+' if signed else ''}.{digits}f} %"


def num(v, digits: int = 3) -> str:
    """A figure to ``digits`` significant digits; ``-`` for a missing one."""
    if missing(v):
        return "-"
    return f"{v:.{digits}g}"


def status(s: dict) -> str:
    """``completed``, or what stopped the run and when."""
    return s["status"] if s["status"] == "completed" else f"{s['status']} at t = {s['t']:.3g} s"


def cost(s: dict) -> list[str]:
    """The wall time (s) and throughput (particle-steps/s) columns of a run."""
    return [f"{s['wall_time_s']:.0f}", f"{s['particle_steps_per_s']:.3g}"]


def table(header: list[str], rows: list[list[str]]) -> str:
    """A Markdown table."""
    lines = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    lines += ["| " + " | ".join(map(str, r)) + " |" for r in rows]
    return "\n".join(lines) + "\n"


def pyplot():
    """matplotlib's pyplot on the file-only Agg backend."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


def save(fig, figures: Path, name: str) -> Path:
    """Save ``fig`` as ``figures/<name>`` at the pages' resolution and close it."""
    figures.mkdir(parents=True, exist_ok=True)
    path = figures / name
    fig.savefig(path, dpi=DPI, bbox_inches="tight")
    pyplot().close(fig)
    return path
