"""Case directories: read ``case.toml``, apply ``--set`` overrides, validate, derive.

A case is data: TOML is parsed, never executed. Every problem raises
:class:`sphcore.errors.CaseError` naming the file, the key and what was expected.
"""

from __future__ import annotations

import copy
import math
from dataclasses import dataclass, field
from pathlib import Path

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

import numpy as np

from sphcore.case import defaults
from sphcore.case.bodies import parse_bodies
from sphcore.case.options import check_value, validate_table
from sphcore.case.overrides import fold, parse_set
from sphcore.case.motion import parse_motion
from sphcore.case.walls import parse_walls
from sphcore.errors import CaseError
from sphcore.geometry.faces import Faces
from sphcore.geometry.motion import MovingGroup
from sphcore.geometry.planes import Planes, outline, recession_direction

CASE_FILE = "case.toml"


@dataclass
class Case:
    """A validated case: ``config[section][key]`` with every default filled in."""

    file: Path
    dir: Path
    config: dict
    planes: Planes
    blocks: list = field(default_factory=list)
    faces: Faces | None = None  # finite walls ([[domain.walls]]); None or empty without
    restart_keys: frozenset = frozenset()  # "table.key" of plugin options that may change on --restart
    moving: tuple = ()  # wall groups with a prescribed motion (sphcore.geometry.motion.MovingGroup)

    def __post_init__(self):
        if self.faces is None:
            self.faces = Faces.empty(self.planes.normals.shape[1] if self.planes.count else self.dim)

    @property
    def dim(self) -> int:
        return self.config["case"]["dim"]

    @property
    def name(self) -> str:
        return self.config["case"]["name"] or self.dir.name

    @property
    def dx(self) -> float:
        return self.config["particles"]["dx"]

    @property
    def radius(self) -> float:
        r = self.config["particles"]["radius"]
        return 0.5 * self.dx if r is None else r

    @property
    def h(self) -> float:
        """Smoothing length (m)."""
        return self.config["kernel"]["h_over_dx"] * self.dx

    @property
    def gravity(self) -> np.ndarray:
        """Gravity (3,) padded with zeros; only the first dim components act."""
        g = np.zeros(3)
        g[: self.dim] = self.config["physics"]["gravity"][: self.dim]
        return g


#: a case file is a few kB; reading stops here (a link to /dev/zero must not fill memory)
MAX_CASE_BYTES = 1 << 20
#: tables nested deeper than this are refused (the parser recurses once per level)
MAX_DEPTH = 32


def _depth(value, level=0) -> int:
    if level > MAX_DEPTH:
        return level
    if isinstance(value, dict):
        return max([_depth(v, level + 1) for v in value.values()], default=level + 1)
    if isinstance(value, list):
        return max([_depth(v, level + 1) for v in value], default=level + 1)
    return level


def read_toml(path: Path) -> dict:
    """The parsed case file. Bounded: only a regular file of at most MAX_CASE_BYTES, UTF-8,
    nested at most MAX_DEPTH deep; anything else is a CaseError (exit status 2)."""
    path = Path(path)
    try:
        if path.exists() and not path.is_file():
            what = "a directory" if path.is_dir() else "not a regular file (a device, a pipe)"
            raise CaseError(path, "-", f"{what}: expected a TOML text file")
        with open(path, "rb") as f:
            data = f.read(MAX_CASE_BYTES + 1)
    except FileNotFoundError:
        raise CaseError(path, "-", "no such file (a case directory holds case.toml)") from None
    except OSError as e:
        raise CaseError(path, "-", f"cannot read: {e.strerror}") from None
    if len(data) > MAX_CASE_BYTES:
        raise CaseError(path, "-", f"larger than {MAX_CASE_BYTES >> 10} KiB: expected a case file of a few kB")
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as e:
        raise CaseError(path, "-", f"not UTF-8 text (byte {e.start}): expected a TOML text file") from None
    try:
        raw = tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        # the parser's message ends with "(at line L, column C)": show that as the key
        msg = str(e)
        where = msg[msg.rfind("(at ") + 4:-1] if msg.endswith(")") and "(at " in msg else "syntax"
        raise CaseError(path, where, f"not valid TOML: {msg}") from None
    except RecursionError:
        raise CaseError(path, "-", f"nested too deeply: expected at most {MAX_DEPTH} levels of tables") from None
    if _depth(raw) > MAX_DEPTH:
        raise CaseError(path, "-", f"nested too deeply: expected at most {MAX_DEPTH} levels of tables") from None
    return raw


def parse_override(text: str) -> tuple[list, object]:
    """``section.key=value`` (or ``blocks[0].count=...``) -> (path, value); see
    :mod:`sphcore.case.overrides`, the one grammar of ``--set`` and ``--vary``."""
    try:
        path, value = parse_set(text)
    except RecursionError:
        raise CaseError("--set", text.split("=", 1)[0], f"nested too deeply: expected at most {MAX_DEPTH} levels") from None
    if _depth(value) > MAX_DEPTH:
        raise CaseError("--set", ".".join(map(str, path)), f"nested too deeply: expected at most {MAX_DEPTH} levels")
    return list(path), value


def apply_overrides(raw: dict, overrides) -> dict:
    """A copy of ``raw`` with each ``KEY=VALUE`` (text, or a (path, value) pair) set; a key
    may index an array of tables (``blocks[0].count``). Sweeps use the same."""
    out = copy.deepcopy(raw)
    pairs = [parse_override(t) if isinstance(t, str) else t for t in overrides or ()]
    for path, value in fold(raw, pairs):
        node = out
        for part in path[:-1]:
            node = node.setdefault(part, {})
            if not isinstance(node, dict):
                raise CaseError("--set", ".".join(map(str, path)), "that section is not a table")
        node[path[-1]] = value
    return out


def _vector(file, key, value, dim, allow_longer=False):
    if value is None:
        raise CaseError(file, key, f"required: a list of {dim} numbers")
    if len(value) != dim and not (allow_longer and len(value) > dim):
        raise CaseError(file, key, f"expected {dim} components for a {dim}D case, got {len(value)}")
    return np.asarray(value[:dim], float)


def _planes(file, cfg, dim, bounded_by_walls=False) -> Planes:
    dom = cfg["domain"]
    normals, points = [], []
    if (dom["min"] is None) != (dom["max"] is None):
        raise CaseError(file, "domain.min" if dom["min"] is None else "domain.max", "min and max come together")
    if dom["min"] is not None:
        lo = _vector(file, "domain.min", dom["min"], dim)
        hi = _vector(file, "domain.max", dom["max"], dim)
        if np.any(hi <= lo):
            raise CaseError(file, "domain.max", f"expected every component above domain.min {lo.tolist()}")
        box = Planes.box(lo, hi)
        normals += list(box.normals)
        points += list(box.points)
    for k, entry in enumerate(dom["planes"]):
        key = f"domain.planes[{k}]"
        e = validate_table(defaults.PLANE, entry, file, key)
        n = _vector(file, f"{key}.normal", e["normal"], dim)
        scale = np.abs(n).max()  # scaled first: the norm of a vector of huge components overflows
        if not (np.isfinite(scale) and scale > 0):
            raise CaseError(file, f"{key}.normal", "expected a non-zero vector of finite components")
        n = n / scale
        normals.append(n / np.linalg.norm(n))
        points.append(_vector(file, f"{key}.point", e["point"], dim))
    if not normals:
        if bounded_by_walls:
            return Planes(np.zeros((0, dim)), np.zeros((0, dim)))
        raise CaseError(file, "domain", "no walls: give domain.min/max, [[domain.planes]] or a closed "
                        "[[domain.walls]] entry with fluid = \"inside\"")
    planes = Planes.from_lists(normals, points)
    u = recession_direction(planes.normals)
    if u is not None and not bounded_by_walls:
        raise CaseError(file, "domain.planes", f"the planes bound no region: it is open along {(np.round(u, 6) + 0.0).tolist()}")
    return planes


def _blocks(file, cfg, dim):
    if not cfg["blocks"]:
        raise CaseError(file, "blocks", "expected at least one [[blocks]] table of particles")
    out = []
    for k, entry in enumerate(cfg["blocks"]):
        key = f"blocks[{k}]"
        b = validate_table(defaults.BLOCK, entry, file, key)
        b["min"] = _vector(file, f"{key}.min", b["min"], dim)
        if b["count"] is not None and b["max"] is not None:
            raise CaseError(file, f"{key}.count", "give either count or max, not both")
        if b["count"] is not None:
            if len(b["count"]) != dim or not all(isinstance(c, int) and not isinstance(c, bool) and c > 0 for c in b["count"]):
                raise CaseError(file, f"{key}.count", f"expected {dim} positive integers")
        elif b["max"] is None:
            raise CaseError(file, f"{key}.max", "required (or give count)")
        else:
            b["max"] = _vector(file, f"{key}.max", b["max"], dim)
            if np.any(b["max"] <= b["min"]):
                raise CaseError(file, f"{key}.max", "expected every component above min")
        b["velocity"] = np.zeros(dim) if b["velocity"] is None else _vector(file, f"{key}.velocity", b["velocity"], dim)
        if b["kind"] == "sphere" and cfg["physics"]["sph"]:
            raise CaseError(file, f"{key}.kind", "rigid spheres take no SPH forces: set physics.sph = false "
                            "(mixing spheres with SPH fluid is not modelled)")
        out.append(b)
    return out


def validate(raw: dict, file: Path, plugin_schemas: dict | None = None) -> Case:
    """Validate a raw TOML dict. ``plugin_schemas`` maps table name -> {key: Option}."""
    plugin_schemas = plugin_schemas or {}
    cfg = {}
    for section, value in raw.items():
        if section not in defaults.CORE and section not in plugin_schemas:
            known = ", ".join(sorted(set(defaults.CORE) | set(plugin_schemas)))
            raise CaseError(file, section, f"unknown section (known: {known})")
    for section, schema in defaults.CORE.items():
        if isinstance(schema, dict):
            cfg[section] = validate_table(schema, raw.get(section, {}), file, section)
        else:
            cfg[section] = check_value(schema, raw.get(section, schema.default), file, section)
    for table, schema in plugin_schemas.items():
        cfg[table] = validate_table(schema, raw.get(table, {}), file, table)
    dim = cfg["case"]["dim"]
    if len(cfg["physics"]["gravity"]) < dim:
        raise CaseError(file, "physics.gravity", f"expected at least {dim} components")
    if cfg["checks"]["rho_min"] >= cfg["checks"]["rho_max"]:
        raise CaseError(file, "checks.rho_max", "expected a value above checks.rho_min")
    if cfg["scheme"]["name"] == "dfsph":
        _check_incompressible(file, cfg)
    faces, ranges = parse_walls(file, cfg["domain"]["walls"], dim, Path(file).parent)
    tank = any(sign < 0 for _, _, sign in faces.groups)
    planes = _planes(file, cfg, dim, bounded_by_walls=tank)
    moving = _moving_groups(file, cfg, dim, ranges, faces, planes)
    taken = {k for k, w in enumerate(cfg["domain"]["walls"]) if w.get("tank") or w.get("motion")}
    moving = moving + tuple(parse_bodies(file, cfg, dim, ranges, faces, taken, planes))
    blocks = _blocks(file, cfg, dim)
    restart_keys = frozenset(f"{table}.{key}" for table, schema in plugin_schemas.items()
                             for key, opt in schema.items() if opt.restart)
    return Case(file=Path(file), dir=Path(file).parent, config=cfg, planes=planes, blocks=blocks,
                faces=faces, restart_keys=restart_keys, moving=moving)


def _moving_groups(file, cfg, dim, ranges, faces, planes) -> tuple[MovingGroup, ...]:
    """The wall groups with a prescribed motion: the tank (its planes and the walls with
    tank = true) and each wall with a motion of its own; fixed walls are in none."""
    t_end, case_dir, walls = cfg["time"]["t_end"], Path(file).parent, cfg["domain"]["walls"]
    groups = []

    def reach(motion, plane_index, face_index):
        """The group's largest distance from its centre of rotation (inf: unbounded planes)."""
        centre = motion.pose(0.0).centre
        points = [faces.verts[face_index].reshape(-1, dim)] if len(face_index) else []
        if len(plane_index):
            box = outline(planes) if len(plane_index) == planes.count else None
            if box is None:  # some of the planes alone bound no region
                return math.inf
            points.append(box.reshape(-1, dim))
        return float(np.sqrt(((np.concatenate(points) - centre) ** 2).sum(axis=1).max())) if points else 0.0

    none = np.zeros(0, np.int64)
    # planes of their own motion ([[domain.planes]] entries come after the box's 2 dim planes)
    first = 2 * dim if cfg["domain"]["min"] is not None else 0
    own = []
    for k, entry in enumerate(cfg["domain"]["planes"]):
        key = f"domain.planes[{k}].motion"
        m = parse_motion(file, key, entry.get("motion", []), dim, case_dir, t_end)
        if m is not None:
            own.append(MovingGroup(key, m, np.array([first + k], np.int64), none, math.inf))
    tank = parse_motion(file, "domain.motion", cfg["domain"]["motion"], dim, case_dir, t_end)
    if tank is not None:
        idx = [np.arange(*ranges[k]) for k, w in enumerate(walls) if w.get("tank", False)]
        idx = np.concatenate(idx).astype(np.int64) if idx else none
        taken = np.zeros(planes.count, bool)
        for g in own:
            taken[g.planes] = True
        carried = np.flatnonzero(~taken).astype(np.int64)
        groups.append(MovingGroup("domain.motion", tank, carried, idx, reach(tank, carried, idx)))
    groups += own
    for k, w in enumerate(walls):
        m = parse_motion(file, f"domain.walls[{k}].motion", w.get("motion", []), dim, case_dir, t_end)
        if m is not None:
            idx = np.arange(*ranges[k], dtype=np.int64)
            groups.append(MovingGroup(f"domain.walls[{k}].motion", m, none, idx, reach(m, none, idx)))
    return tuple(groups)


def case_file(case_dir) -> Path:
    p = Path(case_dir)
    return p / CASE_FILE if p.is_dir() else p


def _check_incompressible(file, cfg) -> None:
    """The keys the divergence-free scheme cannot honour are refused, not ignored: its
    pressure is the solves', never a function of the density."""
    if not cfg["physics"]["sph"]:
        raise CaseError(file, "scheme.name", "dfsph solves for the SPH pressure; physics.sph is false")
    if cfg["physics"]["modified_pressure"]:
        raise CaseError(file, "physics.modified_pressure", "dfsph solves for the full pressure: expected false "
                        "with scheme.name = \"dfsph\"")
    if cfg["corrections"]["shepard_every"]:
        raise CaseError(file, "corrections.shepard_every", "dfsph sums its density every step: expected 0 with "
                        "scheme.name = \"dfsph\"")
    if cfg["bodies"]:
        raise CaseError(file, "bodies", "floating bodies are not coupled to dfsph's solves (their loads would miss the "
                        "solved pressure): use scheme.name = \"wcsph\"")

