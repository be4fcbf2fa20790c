"""Regenerate the validation pages' tables and figures from the runs: one command.

    python validation/build.py [--only NAME ...] [--rerun] [--runs DIR]

Each validation page of the documentation, ``docs/validation/<NAME>.md``, has a module
``validation/pages/<NAME>.py`` (modules whose name starts with ``_`` are helpers, not
pages, importable by the pages under their own names: ``from _common import run_case``).
A page module defines:

- ``NAME`` (str): the page's name; its page is ``docs/validation/<NAME>.md``;
- ``TITLE`` (str): what the page validates, one line (printed by the build);
- ``build(runs: Path, figures: Path, rerun: bool) -> str``: runs the page's cases under
  ``runs`` (``<runs dir>/<NAME>/``, one folder per run), writes its PNG figures into
  ``figures`` (``docs/validation/figures/``, each file named ``<NAME>_...png``) and
  returns the Markdown of its tables.

The build writes what ``build`` returns to ``docs/validation/tables/<NAME>.md`` (left out
of the Sphinx sources); the page includes it with

    ```{include} tables/<NAME>.md
    ```

so that the page's prose stays hand-written while every figure in its tables and plots
comes from the runs. A page runs its cases through ``validation/pages/_common.py``
(``run_case``: ``sph run`` as a subprocess), which reuses a run when its folder holds a
finished run (``summary.json`` says completed, or unstable, which a rerun would repeat)
made by the same ``sph run`` command from the same case files (a stamp of the command line
and of the SHA-256 of the case folder, ``<run folder>.stamp.json``, written before the run
starts); a run stopped by a signal (Ctrl-C on the build) continues from its checkpoint with
``sph run --restart``; ``--rerun`` runs everything again. With the runs in place, a build
only redraws the figures and tables.

``--only NAME ...`` builds those pages alone; ``--runs DIR`` keeps the runs in
``DIR`` instead of ``validation/runs/`` (ignored by git). The build prints each page's wall
time and the total. Run it with one Numba thread per run and one run at a time (the pages
run their cases one after the other) to get the wall times quoted on the pages:

    NUMBA_NUM_THREADS=1 python validation/build.py

These are not tests: they run the shipped cases at their resolution and take minutes to
tens of minutes. The tests check the figures they rest on with small cases.
"""

from __future__ import annotations

import argparse
import importlib.util
import sys
import time
from pathlib import Path

HERE = Path(__file__).resolve().parent
ROOT = HERE.parent
PAGES = HERE / "pages"
DOCS = ROOT / "docs" / "validation"


def discover() -> dict:
    """The page modules of ``validation/pages/``, by their NAME (file order)."""
    # the helpers (_common.py first, then the others in name order), importable by their
    # names as the pages import them: ``from _common import run_case``
    helpers = sorted(PAGES.glob("_*.py"), key=lambda p: (p.stem != "_common", p.name))
    for path in helpers:
        if path.stem != "__init__":
            spec = importlib.util.spec_from_file_location(path.stem, path)
            sys.modules[path.stem] = importlib.util.module_from_spec(spec)
            spec.loader.exec_module(sys.modules[path.stem])
    pages = {}
    for path in sorted(PAGES.glob("*.py")):
        if path.name.startswith("_"):
            continue
        spec = importlib.util.spec_from_file_location(f"validation_page_{path.stem}", path)
        mod = importlib.util.module_from_spec(spec)
        spec.loader.exec_module(mod)
        for attr in ("NAME", "TITLE", "build"):
            if not hasattr(mod, attr):
                raise SystemExit(f"build.py: error: {path} defines no {attr}")
        pages[mod.NAME] = mod
    return pages


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--only", nargs="+", action="extend", metavar="NAME", help="build these pages only")
    ap.add_argument("--rerun", action="store_true", help="run every case again, even where a finished run is there")
    ap.add_argument("--runs", type=Path, default=HERE / "runs", help="where the runs are kept (default validation/runs)")
    args = ap.parse_args(argv)
    pages = discover()
    names = args.only or list(pages)
    unknown = [n for n in names if n not in pages]
    if unknown:
        ap.error(f"no page {', '.join(unknown)} (pages: {', '.join(pages)})")
    figures, tables = DOCS / "figures", DOCS / "tables"
    figures.mkdir(parents=True, exist_ok=True)
    tables.mkdir(parents=True, exist_ok=True)
    times = {}
    t_all = time.perf_counter()
    for name in names:
        page = pages[name]
        print(f"{name}: {page.TITLE}", flush=True)
        t0 = time.perf_counter()
        md = page.build(args.runs.resolve() / name, figures, args.rerun)
        (tables / f"{name}.md").write_text(md if md.endswith("\n") else md + "\n")
        times[name] = time.perf_counter() - t0
        print(f"{name}: {times[name] / 60:.1f} min", flush=True)
    total = time.perf_counter() - t_all
    print("\n".join(f"{n:24s} {t / 60:6.1f} min" for n, t in times.items()))
    print(f"{'total':24s} {total / 60:6.1f} min")
    return 0


if __name__ == "__main__":
    sys.exit(main())
