"""The ``[probes]`` case table: its options and the probes it declares.

    [probes]
    every_dt = 1e-4                      # s; 0 (default): every step

    [[probes.pressure]]
    name = "P1"
    start = [3.22, 0.1555]               # a line sensor (m), averaged over `points` samples,
    end = [3.22, 0.1645]                 # or `point = [x, y]` for a point sensor
    mode = "wall"                        # or "particle"
    normal = [-1.0, 0.0]                 # optional: the face's normal into the fluid
                                         # (default: that of the wall the sensor lies on)
    reference = "buchner_2002_P1"        # optional: a shipped experiment
    H = 0.6                              # m, the column height that scales the reference

    [[probes.depth]]
    name = "H1"
    point = [1.0, 0.0]                   # a point on the floor (m)

Sensors ride with walls that move (``[[domain.motion]]``, ``[[domain.walls.motion]]``)
when they name the wall group with ``attach``:

    [[probes.pressure]]
    name = "paddle"
    point = [0.7, 0.05]                  # where case.toml draws the wall (t = 0)
    attach = "walls[1]"                  # rides with [[domain.walls]] entry 1; "tank": with the tank

An attached sensor's point, start, end and normal are given in the frame case.toml draws
the walls in; at every sample they are where the group's motion has carried them, and a
wall-mode sensor carries the particle pressures to its points with the apparent gravity
g - a_w of the wall's frame (a_w the acceleration of the wall at the point). An attached
depth gauge measures along the group's own up (-g turned with the group) from its moving
floor point. A wall with ``tank = true`` moves with the tank: ``walls[k]`` names the tank
for it. A sensor without ``attach`` stays where it is drawn, whatever moves.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

import numpy as np

from sphcore.api import CaseError, Option, validate_table
from sphcore_plugins.gauges import reference

from .sampling import line_points

TABLE = "probes"
NAME_RE = re.compile(r"^[A-Za-z0-9_-]+$")  # names become summary keys, CSV columns and file names
ON_WALL_TOL = 1e-9  # m: a sensor this far outside a wall plane still counts as on it

OPTIONS = {
    "every_dt": Option(0.0, "float", "s", "simulated time between samples; 0 samples every step "
                       "(impacts last a few ms: keep it well below that)", min=0.0),
    "pressure": Option([], "table_list", doc="pressure sensors: [[probes.pressure]] tables (keys in PRESSURE)"),
    "depth": Option([], "table_list", doc="water-depth gauges: [[probes.depth]] tables (keys in DEPTH)"),
}

#: keys of one ``[[probes.pressure]]`` entry
PRESSURE = {
    "name": Option(None, "str", doc="probe name (letters, digits, _ and -), unique in the case", nullable=True),
    "point": Option(None, "vector", "m", "sensor point; or give start and end", nullable=True),
    "start": Option(None, "vector", "m", "one end of a line sensor (a transducer's face seen edge-on)", nullable=True),
    "end": Option(None, "vector", "m", "the other end of the line sensor", nullable=True),
    "points": Option(5, "int", doc="sample points along a line sensor (centres of equal pieces), averaged",
                     positive=True),
    "mode": Option("wall", "str", doc="wall: particle pressures carried hydrostatically to the sensor (the "
                   "pressure a wall carries); particle: the plain Shepard interpolation", choices=("wall", "particle")),
    "normal": Option(None, "vector", doc="wall mode: normal of the sensor's face, into the fluid; only particles "
                     "in front of the face are read. Default: the normal of the wall plane or face the sensor "
                     "lies on (none for a sensor off every wall)", nullable=True),
    "reference": Option(None, "str", doc="shipped experiment to compare with: "
                        + ", ".join(reference.SERIES), nullable=True),
    "H": Option(None, "float", "m", "column height that scales the reference (p/(rho g H), t sqrt(g/H))",
                positive=True, nullable=True),
    "attach": Option(None, "str", doc="the moving walls the sensor rides with: \"tank\" ([[domain.motion]]) "
                     "or \"walls[k]\" ([[domain.walls]] entry k, with a motion of its own or tank = true); "
                     "point, start, end and normal are then where case.toml draws the walls, and move with "
                     "them; wall mode uses the apparent gravity g - a_w of the wall's frame. "
                     "Default: the sensor stays where it is drawn", nullable=True),
}

#: keys of one ``[[probes.depth]]`` entry
DEPTH = {
    "name": PRESSURE["name"],
    "point": Option(None, "vector", "m", "a point on the floor; the depth is measured above it along -g",
                    nullable=True),
    "attach": Option(None, "str", doc="the moving walls the gauge rides with: \"tank\" or \"walls[k]\" "
                     "(see probes.pressure's attach); point is then where case.toml draws the walls, and the "
                     "depth is measured along -g turned with them. Default: the gauge stays where it is drawn "
                     "and measures along -g", nullable=True),
}


@dataclass
class Probe:
    """One sensor: ``kind`` "pressure" or "depth"; ``points`` (k, dim) where it samples;
    ``start``/``end`` its extent (equal for a point); ``key`` its case key for messages."""

    name: str
    kind: str
    key: str
    start: np.ndarray
    end: np.ndarray
    points: np.ndarray
    mode: str = ""
    face_n: np.ndarray | None = None
    reference: str | None = None
    height: float | None = None
    #: ``attach`` as given, and the moving group it names (``case.moving[k].name``); None: fixed
    attach: str | None = None
    group: str | None = None


def _vec(file, key, value, dim):
    if len(value) != dim:
        raise CaseError(file, key, f"expected {dim} components for a {dim}D case, got {len(value)}")
    return np.asarray(value, float)


def _inside(case, file, key, pts):
    pts = np.atleast_2d(pts)
    d = case.planes.distances(pts)
    if (d < -ON_WALL_TOL).any():
        i, q = np.argwhere(d < -ON_WALL_TOL)[0]
        raise CaseError(file, key, f"point {pts[i].round(9).tolist()} lies outside the domain "
                        f"(wall plane {q}, {-d[i, q]:.6g} m beyond it)")
    faces = getattr(case, "faces", None)
    if faces is not None and faces.count:
        # a sensor on a wall face is fine; one inside a solid wall is not
        solid = ~faces.in_fluid(pts) & (faces.distances(pts) > ON_WALL_TOL)
        if solid.any():
            i = int(np.argmax(solid))
            raise CaseError(file, key, f"point {pts[i].round(9).tolist()} lies inside a solid wall "
                            "([[domain.walls]]); a sensor goes on its face or in the fluid")


def _wall_normal(case, pts) -> np.ndarray | None:
    """Unit normal (into the fluid) of the wall every point of ``pts`` lies on, within
    ON_WALL_TOL (m) of a wall plane or face; None when a point is off every wall or the
    points lie on different walls. On an edge or a corner (two or more walls at once) the
    first plane, or one of the faces, counts: a sensor there should give ``normal``."""
    found = None
    for x in pts:
        n = None
        if case.planes.count:
            d = case.planes.distances(x[None, :])[0]
            on = np.flatnonzero(np.abs(d) <= ON_WALL_TOL)
            if on.size:
                n = case.planes.normals[on[0]]
        faces = getattr(case, "faces", None)
        if n is None and faces is not None and faces.count and faces.distances(x[None, :])[0] <= ON_WALL_TOL:
            n = faces.normal_at(x[None, :])[0]
        if n is None or (found is not None and not np.allclose(n, found, atol=1e-9)):
            return None
        found = n
    return None if found is None else np.asarray(found, float)


def _face_normal(case, file, key, e, pts) -> np.ndarray | None:
    """The sensor face's normal of a wall-mode probe: given (``normal``) or found."""
    if e["mode"] != "wall":
        if e["normal"] is not None:
            raise CaseError(file, f"{key}.normal", "only a wall-mode sensor has a face (mode = \"wall\")")
        return None
    if e["normal"] is None:
        return _wall_normal(case, pts)
    n = _vec(file, f"{key}.normal", e["normal"], case.dim)
    norm = float(np.linalg.norm(n))
    if not np.isfinite(norm) or norm == 0.0:
        raise CaseError(file, f"{key}.normal", f"expected a nonzero finite vector, got {e['normal']}")
    return n / norm


WALL_RE = re.compile(r"^walls\[(\d+)\]$")


def _group(case, file, key, attach) -> str | None:
    """The moving group (``case.moving[k].name``) that ``attach`` names: "tank" the tank
    (``domain.motion``), "walls[k]" the wall's own motion, or the tank's for a wall with
    tank = true. None when ``attach`` is None."""
    if attach is None:
        return None
    moving = {g.name for g in getattr(case, "moving", ())}
    walls = case.config["domain"]["walls"]
    names = (["tank"] if "domain.motion" in moving else []) + [
        f"walls[{k}]" for k, w in enumerate(walls)
        if (w.get("tank", False) and "domain.motion" in moving) or f"domain.walls[{k}].motion" in moving]
    can = (f"; the walls that move here: {', '.join(repr(n) for n in names)}" if names else
           "; no wall moves in this case ([[domain.motion]], [[domain.walls.motion]]): remove attach")
    m = WALL_RE.match(attach)
    if attach == "tank":
        if "domain.motion" in moving:
            return "domain.motion"
        raise CaseError(file, key, "expected a wall group that moves, but the tank has no [[domain.motion]]" + can)
    if m is None:
        raise CaseError(file, key, f"expected \"tank\" or \"walls[k]\" (k the index of a [[domain.walls]] "
                        f"entry), got {attach!r}" + can)
    k = int(m.group(1))
    if k >= len(walls):
        raise CaseError(file, key, f"expected \"walls[k]\" with k < {len(walls)} (the case has {len(walls)} "
                        f"[[domain.walls]] entries), got {attach!r}" + can)
    if walls[k].get("tank", False):
        if "domain.motion" in moving:
            return "domain.motion"
        raise CaseError(file, key, f"expected a wall that moves, but {attach} moves with the tank (tank = true) "
                        "and the tank has no [[domain.motion]]" + can)
    if f"domain.walls[{k}].motion" in moving:
        return f"domain.walls[{k}].motion"
    raise CaseError(file, key, f"expected a wall that moves, but {attach} has no motion "
                    "([[domain.walls.motion]]) and does not move with the tank" + can)


def _name(file, key, e, seen):
    name = e["name"]
    if name is None:
        raise CaseError(file, f"{key}.name", "required: a name for the probe")
    if not NAME_RE.match(name):
        raise CaseError(file, f"{key}.name", f"expected letters, digits, _ or - only, got {name!r}")
    if name in seen:
        raise CaseError(file, f"{key}.name", f"probe name {name!r} is used twice")
    seen.add(name)
    return name


def parse(case) -> tuple[float, list[Probe]]:
    """(every_dt, probes) of ``case.config["probes"]``; every problem is a CaseError naming the key."""
    cfg, file, dim = case.config[TABLE], case.file, case.dim
    probes, seen = [], set()
    for k, entry in enumerate(cfg["pressure"]):
        key = f"{TABLE}.pressure[{k}]"
        e = validate_table(PRESSURE, entry, file, key)
        name = _name(file, key, e, seen)
        if e["point"] is not None:
            if e["start"] is not None or e["end"] is not None:
                raise CaseError(file, f"{key}.point", "give either point or start and end, not both")
            start = end = _vec(file, f"{key}.point", e["point"], dim)
            pts = start[None, :].copy()
            _inside(case, file, f"{key}.point", pts)
        else:
            if e["start"] is None or e["end"] is None:
                missing = "start" if e["start"] is None else "end"
                raise CaseError(file, f"{key}.{missing}", "required: a point, or both start and end of a line sensor")
            start = _vec(file, f"{key}.start", e["start"], dim)
            end = _vec(file, f"{key}.end", e["end"], dim)
            if np.array_equal(start, end):
                raise CaseError(file, f"{key}.end", "expected a point other than start (or use point = ...)")
            _inside(case, file, f"{key}.start", start)
            _inside(case, file, f"{key}.end", end)
            pts = line_points(start, end, e["points"])
        ref = e["reference"]
        if ref is not None:
            if ref not in reference.SERIES:
                raise CaseError(file, f"{key}.reference", f"unknown reference {ref!r} (shipped: {', '.join(reference.SERIES)})")
            if e["H"] is None:
                raise CaseError(file, f"{key}.H", f"required with reference = {ref!r}: the column height (m) that "
                                "scales p/(rho g H) and t sqrt(g/H)")
        face_n = _face_normal(case, file, key, e, pts)
        group = _group(case, file, f"{key}.attach", e["attach"])
        probes.append(Probe(name, "pressure", key, start, end, pts, e["mode"], face_n, ref, e["H"],
                            attach=e["attach"], group=group))
    for k, entry in enumerate(cfg["depth"]):
        key = f"{TABLE}.depth[{k}]"
        e = validate_table(DEPTH, entry, file, key)
        name = _name(file, key, e, seen)
        if e["point"] is None:
            raise CaseError(file, f"{key}.point", "required: a point on the floor")
        x0 = _vec(file, f"{key}.point", e["point"], dim)
        _inside(case, file, f"{key}.point", x0)
        group = _group(case, file, f"{key}.attach", e["attach"])
        probes.append(Probe(name, "depth", key, x0, x0.copy(), x0[None, :].copy(), attach=e["attach"], group=group))
    if not probes:
        raise CaseError(file, TABLE, "no probe: add [[probes.pressure]] or [[probes.depth]] tables, "
                        "or remove probes from plugins.use")
    return cfg["every_dt"], probes
