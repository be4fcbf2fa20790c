"""Score another code's wall-pressure series against a shipped experiment, with sphcore's figures.

    python postprocessing/peer_series.py FILE --reference buchner_2002_P1 --H 0.6 [--key KEY]
                                          [--column NAME] [--scaled] [--rho 1000] [--g 9.81]

FILE is either a CSV with two columns, time (s) and pressure (Pa), header lines starting
with "#" or a non-numeric first row allowed; or a JSON file holding ``{KEY: {"time": [...],
"values": [...]}}`` in s and Pa (the layout of TrixiParticles.jl's validation reference
files; ``--key`` names the series, e.g. ``pressure_P4_fluid_1``). ``--column NAME``: a CSV
whose first non-comment row names its columns (time first), several series side by side;
the one named is scored. ``--scaled``: the file holds t sqrt(g/H) and p/(rho g H) (published
curves digitised in the experiment's dimensionless form) instead of s and Pa. The figures are those of
the ``probes`` plugin (:mod:`sphcore_plugins.probes.figures`): for a Buchner reference the
mean absolute error of p/(rho g H) over t sqrt(g/H) in [2.6, 5.5] and the first rise; for
the Lobovsky band the share of samples inside it and the peak. Nothing of the peer is
shipped with sphcore: the file is the user's.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

import numpy as np

from sphcore_plugins.gauges import reference
from sphcore_plugins.probes import figures


def load(path: Path, key: str | None, column: str | None = None) -> tuple[np.ndarray, np.ndarray]:
    """(t, p) of the peer's series, in the file's units."""
    if path.suffix.lower() == ".json":
        data = json.loads(path.read_text())
        if key is None or key not in data:
            keys = ", ".join(k for k, v in data.items() if isinstance(v, dict) and "values" in v)
            raise ValueError(f"{path}: --key must name one of: {keys}")
        return np.asarray(data[key]["time"], float), np.asarray(data[key]["values"], float)
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


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("file", type=Path)
    ap.add_argument("--reference", required=True, choices=sorted(reference.SERIES))
    ap.add_argument("--H", type=float, required=True, help="initial column height (m)")
    ap.add_argument("--key", help="series name inside a JSON file")
    ap.add_argument("--column", help="CSV: the column to score, named in the file's header row")
    ap.add_argument("--scaled", action="store_true", help="the file holds t sqrt(g/H) and p/(rho g H), not s and Pa")
    ap.add_argument("--rho", type=float, default=1000.0)
    ap.add_argument("--g", type=float, default=9.81)
    args = ap.parse_args(argv)
    if not args.file.is_file():
        print(f"{args.file}: no such file", file=sys.stderr)
        return 2
    try:
        t, p = load(args.file, args.key, args.column)
    except (ValueError, json.JSONDecodeError) as e:
        print(e, file=sys.stderr)
        return 2
    if args.scaled:
        t, p = t / np.sqrt(args.g / args.H), p * args.rho * args.g * args.H
    out = figures.errors(args.reference, t, p, args.rho, args.g, args.H)
    for k, v in out.items():
        print(f"{k} = {v:.4g}" if isinstance(v, float) else f"{k} = {v}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
