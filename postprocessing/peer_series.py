"""Score another code's wall-pressure series against a shipped experiment, with sphcore's figures.

Reads   FILE, the peer's series: a CSV with two columns, time (s) and pressure (Pa), header
        lines starting with "#" or a non-numeric first row allowed; or a JSON file holding
        {KEY: {"time": [...], "values": [...]}} in s and Pa (the layout of
        TrixiParticles.jl's validation reference files; --key names the series, e.g.
        pressure_P4_fluid_1). Nothing of the peer is shipped with sphcore: the file is the
        user's (a run's own probes.csv is such a file too: --column P1_pa).
Writes  nothing; prints the figures as ``name = value`` lines.

``--column NAME``: a CSV whose first non-comment row names its columns (time first),
several series side by side; the one named is scored. ``--scaled``: the file holds
t sqrt(g/H) and p/(rho g H) (published curves digitised in the experiment's dimensionless
form) instead of s and Pa. The figures are those of the probes plugin
(sphcore_plugins.probes.figures): for a Buchner reference the mean absolute error of
p/(rho g H) over t sqrt(g/H) in [2.6, 5.5] and the first rise; for the Lobovsky band the
share of samples inside it and the peak. A missing or unreadable file, or a series it does
not hold: one line on stderr, exit status 2.

    python postprocessing/peer_series.py FILE --reference buchner_2002_P1 --H 0.6
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np
from runs import RunError, refuse

from sphcore_plugins.gauges import reference
from sphcore_plugins.probes import figures

PROG = Path(__file__).name


def load(path: Path, key: str | None, column: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(t, p) of the peer's series, in the file's units."""
    if path.suffix.lower() == ".json":
        data = json.loads(path.read_text())
        series = {k: v for k, v in data.items() if isinstance(v, dict) and {"time", "values"} <= v.keys()} \
            if isinstance(data, dict) else {}
        if not series:
            raise ValueError(f'{path}: no series (expected {{KEY: {{"time": [...], "values": [...]}}}})')
        if key not in series:
            raise ValueError(f"{path}: --key must name one of: {', '.join(series)}")
        return np.asarray(series[key]["time"], float), np.asarray(series[key]["values"], float)
    rows, col, named = [], 1, column is None
    for line in path.read_text().splitlines():
        parts = [x.strip() for x in line.replace(";", ",").split(",")]
        if not named and not rows and not line.startswith("#") and column in parts:
            col, named = parts.index(column), True  # the header row
            continue
        try:
            rows.append((float(parts[0]), float(parts[col])))
        except (ValueError, IndexError):
            continue  # header or comment
    if not named:
        raise ValueError(f"{path}: --column {column}: no header row naming that column")
    if not rows:
        raise ValueError(f"{path}: no rows of two numbers (time, pressure)")
    a = np.array(rows)
    return a[:, 0], a[:, 1]


def checked(path: Path, t: np.ndarray, p: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """The series if it is one: two 1-D arrays of the same length, at least two finite rows,
    times increasing; else a ValueError naming ``path``."""
    if t.ndim != 1 or p.shape != t.shape:
        raise ValueError(f"{path}: time and values of different shapes {t.shape} and {p.shape}: expected two "
                         "columns of numbers")
    if len(t) < 2 or not (np.all(np.isfinite(t)) and np.all(np.isfinite(p))) or not np.all(np.diff(t) > 0):
        raise ValueError(f"{path}: {len(t)} rows: expected at least two rows of finite numbers, times increasing")
    return t, p


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("file", type=Path, help="the peer's series: CSV or JSON (see above)")
    ap.add_argument("--reference", required=True, choices=sorted(reference.SERIES))
    ap.add_argument("--H", type=float, required=True, help="initial column height (m)")
    ap.add_argument("--key", help="series name inside a JSON file")
    ap.add_argument("--column", help="CSV: the column to score, named in the file's header row")
    ap.add_argument("--scaled", action="store_true", help="the file holds t sqrt(g/H) and p/(rho g H), not s and Pa")
    ap.add_argument("--rho", type=float, default=1000.0, help="density (kg/m^3) of the scaling")
    ap.add_argument("--g", type=float, default=9.81, help="gravity (m/s^2) of the scaling")
    args = ap.parse_args(argv)
    try:
        if not args.file.is_file():
            raise RunError(f"{args.file}: no such file (expected the peer's series, CSV or JSON)")
        try:
            for name in ("H", "rho", "g"):
                value = getattr(args, name)
                if not (np.isfinite(value) and value > 0):
                    raise RunError(f"--{name} {value}: expected a positive number")
            t, p = checked(args.file, *load(args.file, args.key, args.column))
        except (OSError, UnicodeDecodeError, ValueError, TypeError) as err:  # json.JSONDecodeError: a ValueError
            raise RunError(err if str(args.file) in str(err) else f"{args.file}: {err}") from None
    except RunError as err:
        return refuse(PROG, err)
    if args.scaled:
        t, p = t / np.sqrt(args.g / args.H), p * args.rho * args.g * args.H
    out = figures.errors(args.reference, t, p, args.rho, args.g, args.H)
    for k, v in out.items():
        print(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
