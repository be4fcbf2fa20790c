"""Write the reference pages from the code at every build, so that they cannot go stale.

- ``reference/case_keys.md``: every case key with its default, kind, unit and meaning, from
  the same declarations ``sph options`` prints (:func:`sphcore.plugin.pluginhost.option_tables`:
  the core's and every installed plugin's).
- ``reference/cli.md``: ``sph --help`` and each command's help, as the parser prints them.
- ``reference/cases.md``: the shipped cases, from each ``cases/*/case.toml`` (its
  ``[case]`` description, dimension, plugins and simulated time).
- ``reference/output_files.md``: the files a run writes, with each netCDF variable's
  dimensions, units and meaning, read from the files of two small runs made at build time
  (a dam break with every writer, a swaying tank with wall loads). A file that a run writes
  and :data:`FILES` does not describe fails the build.

The hook reference (``reference/hooks.md``) is written by hand around ``automodule``; the
docstrings it shows are the hook specifications themselves.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys
import tempfile
from fnmatch import fnmatch
from pathlib import Path

from sphinx.errors import ExtensionError

#: one line per file a run may write; the build fails on a file missing here
FILES = {
    "summary.json": "the run's figures: status, time, steps, wall time, particle-steps/s, peak memory, "
                    "kernel counters, threads, the validated case (`config`) and each plugin's figures "
                    "under its name",
    "checkpoint.npz": "the state a `--restart` continues from (particles, clock, every plugin's kept "
                      "state, the writers' records); replaced whole at each checkpoint",
    ".sphcore-output": "the output directory's marker: the files sph wrote there (`--overwrite` removes "
                       "these and only these)",
    ".sphcore-lock": "held by the run writing the directory: a second writer is refused",
    "particles.nc": "particle frames (`netcdf` plugin): netCDF CDF-5, one record per frame, readable "
                    "while the run writes",
    "*.pvd": "the collection of the particle frames (`vtu` plugin): open it in ParaView",
    "*_walls.pvd": "the collection of the wall frames (`vtu` plugin, runs whose walls move)",
    "vtu/*.vtu": "one particle frame (`vtu` plugin), point data as below",
    "vtu/*_walls_*.vtu": "the walls at one frame (`vtu` plugin, runs whose walls move)",
    "probes.nc": "pressure and depth probes (`probes` plugin), one row per sample",
    "probes.csv": "the same probes as columns, written when the run ends",
    "front.csv": "the surge front and the residual height at the back wall per sample (`front_gauge`)",
    "wall_loads.nc": "force and moment of the fluid on each moving wall group (`wall_loads` plugin)",
    "wall_loads.csv": "the same loads as columns, written when the run ends",
}

DAM_BREAK = [
    "--t-end", "0.02", "--set", "particles.dx=0.0095",
    "--set", 'plugins.use=["reflective","vtu","netcdf","front_gauge","pressure_gauge","probes"]',
    "--set", "vtu.every_dt=0.01", "--set", "netcdf.every_dt=0.01",
    "--set", 'probes.pressure=[{name="P1", point=[0.42, 0.01]}]',
    "--set", 'probes.depth=[{name="H1", point=[0.2, 0.0]}]',
]
SWAYING_TANK = [
    "--t-end", "0.02", "--set", "particles.dx=0.05",
    "--set", 'plugins.use=["reflective","wall_integral","vtu","netcdf","wall_loads","probes"]',
    "--set", "vtu.every_dt=0.01", "--set", "netcdf.every_dt=0.01",
]


def _run(root: Path, case: str, args: list, out: Path) -> Path:
    cmd = [sys.executable, "-m", "sphcore.cli", "run", str(root / "cases" / case), "--output", str(out),
           "--progress", "off", *args]
    env = dict(os.environ, NUMBA_NUM_THREADS="1")
    done = subprocess.run(cmd, capture_output=True, text=True, env=env)
    if done.returncode:
        raise ExtensionError(f"the reference run of cases/{case} failed:\n{done.stderr}")
    return out


def _pattern(rel: str) -> str:
    """The most specific entry of FILES that names ``rel``."""
    for pattern in sorted(FILES, key=len, reverse=True):
        if rel == pattern or fnmatch(rel, pattern):
            return pattern
    raise ExtensionError(f"a run wrote {rel}, which docs/_ext/reference.py FILES does not describe")


def _netcdf_table(path: Path) -> list[str]:
    import netCDF4

    lines = ["| variable | dimensions | units | meaning |", "|---|---|---|---|"]
    with netCDF4.Dataset(path) as ds:
        for name, var in ds.variables.items():
            attrs = var.__dict__
            meaning = attrs.get("long_name", "")
            if "flag_meanings" in attrs:
                meaning += f" ({attrs['flag_meanings']})"
            lines.append(f"| `{name}` | {', '.join(var.dimensions)} | {attrs.get('units', '')} | {meaning} |")
    return lines


def _vtu_table(path: Path) -> list[str]:
    import meshio

    mesh = meshio.read(path)
    lines = ["| point array | components |", "|---|---|"]
    for name, data in mesh.point_data.items():
        lines.append(f"| `{name}` | {1 if data.ndim == 1 else data.shape[1]} |")
    return lines


def output_files(root: Path) -> str:
    with tempfile.TemporaryDirectory() as tmp:
        runs = [("cases/dam_break", _run(root, "dam_break", DAM_BREAK, Path(tmp) / "dam_break")),
                ("cases/sloshing_free", _run(root, "sloshing_free", SWAYING_TANK, Path(tmp) / "sloshing"))]
        seen, body = set(), []
        for case, out in runs:
            for path in sorted(p for p in out.rglob("*") if p.is_file()):
                rel = path.relative_to(out).as_posix()
                pattern = _pattern(rel)
                if pattern in seen:
                    continue
                seen.add(pattern)
                body += [f"## `{pattern}`", "", FILES[pattern][0].upper() + FILES[pattern][1:] + f" (here from a run of `{case}`).", ""]
                if path.suffix == ".nc":
                    body += _netcdf_table(path) + [""]
                elif path.suffix == ".vtu":
                    body += _vtu_table(path) + [""]
                elif path.suffix == ".csv":
                    header = path.read_text().splitlines()[0]
                    body += ["Columns: " + ", ".join(f"`{c}`" for c in header.split(",")), ""]
                elif rel == "summary.json":
                    keys = json.loads(path.read_text())
                    body += ["Top-level keys: " + ", ".join(f"`{k}`" for k in keys), ""]
    head = [
        "# Output files",
        "",
        "What a run writes into its output directory (`output/` beside `case.toml`, or",
        "`--output DIR`). Which files appear depends on the plugins a case uses. The tables",
        "below are read from the files of two small runs made when this page was built, so",
        "they list exactly what the code writes. SI units throughout; in 2D, forces are per",
        "metre of span (N/m) and moments N m/m.",
        "",
    ]
    return "\n".join(head + body)


def case_keys() -> str:
    from sphcore.case.options import Option
    from sphcore.plugin import pluginhost

    lines = [
        "# Case keys",
        "",
        "Every key a `case.toml` may set, with its default. A case holds only the keys it",
        "changes; everything else takes the default below. `sph options` prints the same",
        "list (`sph options wall_integral` for one plugin's tables); `--set table.key=value`",
        "overrides any key from the command line. *derived* means the default is computed",
        "from other keys (its meaning says how). Tables marked `[]` are arrays of tables",
        "(`[[blocks]]`).",
        "",
    ]
    owner_seen = None
    for (owner, table), schema in pluginhost.option_tables().items():
        if owner != owner_seen:
            lines += ["## Core" if owner == "core" else f"## Plugin `{owner}`", ""]
            if owner != "core":
                lines += [f"Used when `plugins.use` names `\"{owner}\"`.", ""]
            owner_seen = owner
        rows = schema.items() if isinstance(schema, dict) else [("", schema)]
        lines += [f"### `[{table}]`", "", "| key | default | kind | unit | meaning |", "|---|---|---|---|---|"]
        for key, opt in rows:
            if not isinstance(opt, Option):
                continue
            default = "*derived*" if opt.default is None else f"`{opt.default!r}`"
            doc = opt.doc.replace("|", "\\|")
            if opt.choices:
                doc += " One of " + ", ".join(f"`{c}`" for c in opt.choices) + "."
            if opt.restart:
                doc += " May change on `--restart`."
            lines.append(f"| `{key or table}` | {default} | {opt.kind} | {opt.unit} | {doc} |")
        lines.append("")
    return "\n".join(lines)


def cli() -> str:
    env = dict(os.environ, COLUMNS="100")
    lines = [
        "# Command line",
        "",
        "`sph` is installed with the package. Exit status: 0 done; 1 the run went unstable or",
        "could not write its output (the last good output is kept); 2 bad input (one line",
        "naming the file or option, the key and what was expected; nothing written); 130/143",
        "stopped by SIGINT/SIGTERM (a checkpoint is written first, `--restart` continues).",
        "",
    ]
    for command in ["", "run", "check", "options", "plugins", "sweep"]:
        args = [sys.executable, "-m", "sphcore.cli", *([command] if command else []), "--help"]
        text = subprocess.run(args, capture_output=True, text=True, env=env, check=True).stdout
        title = "`sph`" if not command else f"`sph {command}`"
        lines += [f"## {title}", "", "```text", text.rstrip(), "```", ""]
    return "\n".join(lines)


def cases(root: Path) -> str:
    try:
        import tomllib
    except ModuleNotFoundError:  # Python 3.10
        import tomli as tomllib

    lines = [
        "# Cases",
        "",
        "The case directories shipped in `cases/`, each run with `sph run cases/<name>`; each",
        "directory's README says what the case reproduces, how long it takes and how to read",
        "its output. Copy one to start a case of your own.",
        "",
        "| case | dim | description | plugins | simulated time |",
        "|---|---|---|---|---|",
    ]
    for toml in sorted((root / "cases").glob("*/case.toml")):
        case = tomllib.loads(toml.read_text())
        info, plugins = case.get("case", {}), case.get("plugins", {}).get("use", [])
        t_end = case.get("time", {}).get("t_end")
        lines.append(f"| `{toml.parent.name}` | {info.get('dim', '')} | {info.get('description', '')} | "
                     f"{', '.join(f'`{p}`' for p in plugins)} | {'' if t_end is None else f'{t_end:g} s'} |")
    return "\n".join(lines + [""])


def _write(path: Path, text: str) -> None:
    if not path.exists() or path.read_text() != text:  # an unchanged page keeps its time: no rebuild
        path.write_text(text)


def generate(app) -> None:
    docs = Path(app.srcdir)
    out = docs / "reference"
    _write(out / "case_keys.md", case_keys())
    _write(out / "cli.md", cli())
    _write(out / "cases.md", cases(docs.parent))
    _write(out / "output_files.md", output_files(docs.parent))


def setup(app):
    app.connect("builder-inited", generate)
    return {"parallel_read_safe": True}
