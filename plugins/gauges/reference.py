"""Published dam-break data shipped with the package (see data/README.md for sources).

- Cruchaga et al. (2007), the seed paper's two experimental front positions and its own
  SPH values (m, s);
- Martin & Moyce (1952), n^2 = 2 surge front, Z = x/a against T = t sqrt(2 g / a).
"""

from __future__ import annotations

import csv
from functools import lru_cache
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data"


def _rows(name):
    with open(DATA / name) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


@lru_cache(maxsize=None)
def cruchaga() -> np.ndarray:
    """Rows (t_s, x_experiment_m, x_seed_sph_m)."""
    return np.array([[float(r["t_s"]), float(r["x_front_experiment_m"]), float(r["x_front_seed_sph_m"])]
                     for r in _rows("cruchaga_2007_front_from_seed.csv")])


@lru_cache(maxsize=None)
def martin_moyce() -> np.ndarray:
    """Rows (T, Z), transcription A."""
    return np.array([[float(r["T_A"]), float(r["Z_A"])] for r in _rows("martin_moyce_1952_n2-2_front.csv")])
