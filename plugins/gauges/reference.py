"""Published dam-break data shipped with the package (see data/README.md for sources).

- Cruchaga et al. (2007), the seed paper's two experimental front positions and its own
  SPH values (m, s);
- Martin & Moyce (1952), n^2 = 2 surge front, Z = x/a against T = t sqrt(2 g / a), and
  residual column height at the back wall, H = eta/(2a) against tau = t sqrt(g/a);
- Buchner (2002) wall pressure at sensors P1 and P2, p/(rho g H) against t sqrt(g/H)
  (H = 0.6 m column);
- Lobovsky et al. (2014) wall pressure at sensor 2 (15 mm above the floor), the 2.5 %,
  50 % and 97.5 % percentiles of p/(rho g H) over repeated runs against t/T, T = sqrt(H/g)
  (H = 0.3 m);
- SPHERIC test 2 (Kleefsman et al. 2005): 3D dam break against a box, pressures P1-P4 on
  the box (Pa) and water depths H1-H4 (m) against t (s).

The pressure series are named (``SERIES``) so that a case can ask for one by name
(``[[probes.pressure]] reference = "buchner_2002_P1"``).
"""

from __future__ import annotations

import csv
from dataclasses import dataclass
from functools import lru_cache
from pathlib import Path

import numpy as np

DATA = Path(__file__).parent / "data"


def _rows(name):
    with open(DATA / name) as f:
        return list(csv.DictReader(line for line in f if not line.startswith("#")))


def _columns(name, *cols) -> np.ndarray:
    return np.array([[float(r[c]) for c in cols] for r in _rows(name)])


@lru_cache(maxsize=None)
def cruchaga() -> np.ndarray:
    """Rows (t_s, x_experiment_m, x_seed_sph_m)."""
    return _columns("cruchaga_2007_front_from_seed.csv", "t_s", "x_front_experiment_m", "x_front_seed_sph_m")


@lru_cache(maxsize=None)
def martin_moyce() -> np.ndarray:
    """Rows (T, Z), transcription A."""
    return _columns("martin_moyce_1952_n2-2_front.csv", "T_A", "Z_A")


@lru_cache(maxsize=None)
def martin_moyce_height() -> np.ndarray:
    """Rows (tau, H): tau = t sqrt(g/a), H = eta/(2a) at the back wall (n^2 = 2 column)."""
    return _columns("martin_moyce_1952_n2-2_height.csv", "tau", "H")


@lru_cache(maxsize=None)
def kleefsman() -> dict:
    """SPHERIC test 2 columns: {"t": s, "P1".."P4": Pa (gauge), "H1".."H4": m}."""
    cols = ("t", "P1", "P2", "P3", "P4", "H1", "H2", "H3", "H4")
    a = _columns("spheric_test2_kleefsman_2005.csv", *cols)
    return {c: np.ascontiguousarray(a[:, k]) for k, c in enumerate(cols)}


@dataclass(frozen=True)
class Series:
    """A shipped pressure reference: what it is and how it is scaled.

    ``kind`` is "buchner" (one experimental curve, time = t sqrt(g/H)) or "lobovsky"
    (a percentile band, time = t/T with T = sqrt(H/g): the same number, sqrt(g/H) t).
    ``height_m`` is the experiment's column height and ``sensor_height_m`` the sensor's
    centre above the floor, both from the file's header.
    """

    name: str
    kind: str
    file: str
    label: str
    height_m: float
    sensor_height_m: float


SERIES = {
    "buchner_2002_P1": Series("buchner_2002_P1", "buchner", "buchner_2002_dam_break_2d_P1.csv",
                              "Buchner 2002, P1 (experiment)", 0.6, 0.160),
    "buchner_2002_P2": Series("buchner_2002_P2", "buchner", "buchner_2002_dam_break_2d_P2.csv",
                              "Buchner 2002, P2 (experiment)", 0.6, 0.584),
    "lobovsky_2014_sensor2": Series("lobovsky_2014_sensor2", "lobovsky", "lobovsky_2014_sensor2_band.csv",
                                    "Lobovsky et al. 2014, sensor 2 (2.5-97.5 % band)", 0.3, 0.015),
}


@lru_cache(maxsize=None)
def series(name: str) -> np.ndarray:
    """The named pressure reference as an array.

    buchner: rows (t sqrt(g/H), p/(rho g H)); lobovsky: rows (t/T, p2.5, median, p97.5),
    p in rho g H units. KeyError for an unknown name.
    """
    s = SERIES[name]
    if s.kind == "buchner":
        col = "P1" if name.endswith("P1") else "P2"
        return _columns(s.file, "time", col)
    return _columns(s.file, "t_over_T", "p2.5", "median", "p97.5")
