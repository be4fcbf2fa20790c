"""Open a run's output for a post-processing script, or refuse it with one clean line.

A run is the directory ``sph run`` wrote (the case's ``output.dir`` or ``--output DIR``):

- ``summary.json``: the run's figures and its validated case (``config``), which gives the
  scripts their defaults (column width, water depth, density);
- frames: the ``vtu`` plugin's ``.pvd`` (and its ``.vtu`` files) or the ``netcdf``
  plugin's ``particles.nc``;
- the ``probes`` plugin's ``probes.nc`` (appended sample by sample) and ``probes.csv``
  (written at the end of the run).

Every script opens its run with :func:`open_run` and reads what it needs through the
returned :class:`Run`. A path that is not what the script reads (missing, a directory sph
did not write, a run without frames or probes, a run of another kind: a tank at rest given
to the wavefront script) raises :class:`RunError`, whose message names the file and what
was expected; the script prints it as one line ``<script>: error: ...`` on stderr and exits
with status 2 (:func:`refuse`): never a traceback, never a plot of nonsense.

The scripts import this module as their sibling, ``from runs import ...``: Python puts a
script's own folder first on ``sys.path`` when it runs ``python postprocessing/X.py``.
"""

from __future__ import annotations

import json
import sys
from dataclasses import dataclass
from pathlib import Path

import numpy as np

PROBES_NC = "probes.nc"
PROBES_CSV = "probes.csv"
PARTICLES_NC = "particles.nc"


class RunError(Exception):
    """A path that is not what a script reads; the message names the file and what was expected."""


def refuse(script: str, err: Exception) -> int:
    """Print ``err`` as one line ``<script>: error: ...`` on stderr; the exit status, 2."""
    print(f"{script}: error: {err}", file=sys.stderr)
    return 2


def pyplot():
    """matplotlib's pyplot on the file-only Agg backend (imported here: only plots need it)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    return plt


@dataclass
class Run:
    dir: Path  # the output directory (a script writes its figures here, beside what sph wrote)
    config: dict  # the validated case, section -> key -> value; {} for a run without summary.json
    named: Path | None = None  # the file the user named instead of the directory, if any

    def first_block(self) -> dict:
        """The first fluid block of the case ({} if none is known)."""
        fluid = [b for b in self.config.get("blocks", []) if b.get("kind", "fluid") == "fluid"]
        return fluid[0] if fluid else {}

    def block_extent(self, block: dict) -> tuple[list[float], list[float]]:
        """(min, max) corners of a block (m), from its ``max`` or its ``count`` of particles."""
        return _block_extent(block, self.config["particles"]["dx"])

    # --------------------------------------------------------------------- frames

    def frames_file(self) -> Path:
        """The .pvd (preferred) or particles.nc holding the run's frames."""
        if self.named is not None and self.named.suffix in (".pvd", ".nc") and self.named.name != PROBES_NC:
            return self.named
        pvd = sorted(self.dir.glob("*.pvd"))
        path = pvd[0] if pvd else self.dir / PARTICLES_NC
        if not path.is_file():
            raise RunError(f"{self.dir}: no frames of a run (expected a .pvd from the vtu plugin or "
                           f"{PARTICLES_NC} from the netcdf plugin)")
        return path

    def frames(self):
        """Yield (t in s, positions (n, 3) in m, {field: per-particle array}) for every frame,
        whichever writer made them (the fields include ``pressure``, ``density``, ``radius``)."""
        path = self.frames_file()
        if path.suffix == ".nc":
            import xarray as xr

            try:
                ds = xr.open_dataset(path)
            except (OSError, ValueError) as err:
                raise RunError(f"{path}: cannot read the frames: {err}") from None
            with ds:
                for k in range(ds.sizes["time"]):
                    fr = ds.isel(time=k)
                    pos = np.zeros((ds.sizes["particle"], 3))
                    pos[:, : ds.sizes["spatial"]] = fr["position"].values
                    yield float(fr["time"]), pos, {v: fr[v].values for v in ("density", "pressure", "radius")}
            return
        import pyvista as pv

        reader = pv.get_reader(str(path))
        for t in reader.time_values:
            reader.set_active_time_value(t)
            mesh = reader.read()
            mesh = mesh[0] if isinstance(mesh, pv.MultiBlock) else mesh
            yield float(t), np.asarray(mesh.points, float), {k: np.asarray(mesh.point_data[k])
                                                             for k in mesh.point_data}

    # --------------------------------------------------------------------- probes

    def _probe_file(self, name: str) -> Path:
        path = self.named if self.named is not None and self.named.name == name else self.dir / name
        if not path.is_file():
            raise RunError(f"{self.dir}: no {name} (was the probes plugin in plugins.use?)")
        return path

    def probes(self) -> dict:
        """The samples of ``probes.nc``: {t (s), rho0, g, probes: [{name, kind ("pressure" or
        "depth"), reference (or None), H (m, or None), values (Pa or m, one per t)}]}. A sample
        a failed write left without its time is left out."""
        import netCDF4

        path = self._probe_file(PROBES_NC)
        try:
            with netCDF4.Dataset(path) as ds:
                ds.set_auto_maskandscale(False)
                t = np.array(ds["time"][:])
                ok = np.isfinite(t)
                names, refs = _text(ds["probe_name"][:]), _text(ds["probe_reference"][:])
                kinds, heights = np.array(ds["probe_kind"][:]), np.array(ds["probe_H"][:])
                p, d = np.array(ds["pressure"][:])[ok], np.array(ds["depth"][:])[ok]
                rho0, g = float(ds.getncattr("rho0")), float(ds.getncattr("g"))
        except (OSError, RuntimeError, KeyError, AttributeError, IndexError) as err:
            raise RunError(f"{path}: cannot read the probes: {err}") from None
        probes = [{"name": n, "kind": "pressure" if k == 0 else "depth", "reference": r or None,
                   "H": None if not np.isfinite(hh) else float(hh), "values": (p if k == 0 else d)[:, i]}
                  for i, (n, r, k, hh) in enumerate(zip(names, refs, kinds, heights))]
        return {"t": t[ok], "rho0": rho0, "g": g, "probes": probes}

    def probe_table(self) -> dict:
        """The columns of ``probes.csv`` by probe name: {"time": s, "<name>": Pa or m}."""
        path = self._probe_file(PROBES_CSV)
        return read_probe_table(path)


def read_probe_table(path: Path) -> dict:
    """The columns of a ``probes.csv`` (``time_s``, then ``<name>_pa`` / ``<name>_m``) by
    name, units stripped: {"time": ..., "H1": ..., "P1": ...}."""
    try:
        header = path.read_text().splitlines()[0].strip().split(",")
        data = np.loadtxt(path, delimiter=",", skiprows=1, ndmin=2)
    except (OSError, IndexError, ValueError) as err:
        raise RunError(f"{path}: cannot read the probe samples: {err}") from None
    if header[0] != "time_s" or data.shape[0] == 0 or data.shape[1] != len(header):
        raise RunError(f"{path}: expected a header time_s,<probe>_pa|<probe>_m,... and one row per sample")
    return {("time" if name == "time_s" else name.rsplit("_", 1)[0]): data[:, k] for k, name in enumerate(header)}


def _text(chars) -> list[str]:
    import netCDF4

    return [s.strip() for s in netCDF4.chartostring(np.asarray(chars)).tolist()]


def _block_extent(block, dx):
    lo = [float(v) for v in block["min"]]
    if block.get("max") is not None:
        hi = [float(v) for v in block["max"]]
    else:
        hi = [a + c * dx for a, c in zip(lo, block["count"])]
    return lo, hi


KINDS = ("dam_break", "tank_at_rest")


def open_run(path, kind: str | None = None) -> Run:
    """The run at ``path``: an output directory, or a file in one (its .pvd, particles.nc,
    probes.nc or probes.csv). With ``kind`` the run's summary.json must say it is one:
    "dam_break" (a 2D fluid column against the back wall with room to spread) or
    "tank_at_rest" (fluid covering the whole floor of a 2D tank, at rest). Raises RunError."""
    p = Path(path)
    if not p.exists():
        raise RunError(f"{p}: no such file or directory (expected the output directory of a run)")
    d = p if p.is_dir() else p.parent
    summary = d / "summary.json"
    config = {}
    if summary.is_file():
        try:
            config = json.loads(summary.read_text()).get("config") or {}
        except (OSError, ValueError, AttributeError) as err:
            raise RunError(f"{summary}: cannot read the run's summary: {err}") from None
        if not isinstance(config, dict) or not all(isinstance(v, dict) or (isinstance(v, list) and all(
                isinstance(e, dict) for e in v)) for v in config.values()):
            raise RunError(f"{summary}: its config is not a validated case (expected section tables)")
    elif kind is not None:
        raise RunError(f"{d}: no summary.json (expected the output directory of a finished sph run)")
    run = Run(d, config, None if p.is_dir() else p)
    if kind is not None and config:
        try:
            _check_kind(run, kind)
        except (KeyError, TypeError, IndexError, AttributeError) as err:
            raise RunError(f"{summary}: its config is not a validated case ({type(err).__name__}: {err})") from None
    return run


def _check_kind(run: Run, kind: str):
    if kind not in KINDS:
        raise ValueError(f"kind {kind!r}: expected one of {KINDS}")
    cfg = run.config
    block, dom = run.first_block(), cfg["domain"]
    if cfg["case"]["dim"] != 2 or not block or dom.get("min") is None:
        raise RunError(f"{run.dir} is not a {kind.replace('_', ' ')} run: it needs a 2D fluid block in a box domain")
    dx = cfg["particles"]["dx"]
    lo, hi = run.block_extent(block)
    moving = any(abs(v) > 0 for v in (block.get("velocity") or [0.0]))
    if kind == "dam_break":
        against_wall = abs(lo[0] - dom["min"][0]) < dx and abs(lo[1] - dom["min"][1]) < dx
        if not against_wall or hi[0] > dom["max"][0] - 2 * dx:
            raise RunError(f"{run.dir} is not a dam break: its fluid block does not stand against the back wall "
                           f"with room to spread")
    elif abs(lo[0] - dom["min"][0]) > dx or abs(hi[0] - dom["max"][0]) > dx or moving:
        raise RunError(f"{run.dir} is not a tank at rest: its fluid does not cover the whole floor at rest")
