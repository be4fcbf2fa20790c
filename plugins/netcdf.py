"""netCDF output: every frame of a run appended to one CF-style file, ``particles.nc``.

Dimensions ``time`` (unlimited), ``particle`` (fixed for the run), ``spatial`` (dim).
Per frame: time (s), step, position (m), velocity (m/s), density (kg/m^3), pressure (Pa);
once: mass (kg), radius (m), kind, id. Particles are stored sorted by id, so index i along
``particle`` is the same particle in every frame whatever order the core keeps them in.
The validated case is copied into global attributes named ``section.key``. A case whose
walls move adds, per frame, each moving group's pose (``wall_shift``, ``wall_rotation``,
``wall_velocity``, ``wall_angular_velocity``, along ``wall_group`` in the order of the
global attribute ``wall_groups``) and once its ``wall_centre``: a point X of a group as
case.toml draws it is at wall_centre + wall_shift + wall_rotation (X - wall_centre).

The file is netCDF-3 64-bit-data (CDF-5) rather than netCDF-4/HDF5, because
- HDF5 locks the file while the run has it open, so a second process (a notebook
  watching the run, a post-processing script) could not read it;
- a CDF-5 file is a header plus appended records: after ``sync`` the header counts only
  complete frames, and a killed run leaves a file that opens with all of them;
- it still holds int64 and float64 exactly (the classic format has no int64).
"""

from __future__ import annotations

import datetime as _dt
import json
import re
from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

import sphcore
from sphcore.api import (FLUID, GHOST, SPHERE, CaseError, OutputError, ScheduledWriter, hookimpl, leading_complete,
                         mark_written)

if TYPE_CHECKING:  # imported where a file is opened: a run that writes none does not pay for it
    import netCDF4


TABLE = "netcdf"
FILE_NAME = "particles.nc"
FORMAT = "NETCDF3_64BIT_DATA"

# name: (dimensions, dtype, attributes). No CF standard name exists for a generic
# fluid's velocity, density or pressure: the candidates (sea_water_pressure,
# sea_water_density, sea_water_x_velocity, ...) assert sea water and absolute pressure
# (including the atmosphere above), which a Tait-EOS particle pressure is not.
FRAME_VARS = {
    "position": (("time", "particle", "spatial"), "f8", {"units": "m", "long_name": "particle position"}),
    "velocity": (("time", "particle", "spatial"), "f8", {"units": "m s-1", "long_name": "particle velocity"}),
    "density": (("time", "particle"), "f8", {"units": "kg m-3", "long_name": "particle density"}),
    "pressure": (("time", "particle"), "f8",
                 {"units": "Pa", "long_name": "particle pressure from the equation of state"}),
    "step": (("time",), "i8", {"units": "1", "long_name": "time step index"}),
    # a frame's time is set to NaN first and to t last: a complete frame has a time
    "time": (("time",), "f8", {"units": "s", "standard_name": "time", "long_name": "simulated time since the start of the run"}),
}
STATIC_VARS = {
    "mass": ("f8", "m", {"units": "kg", "long_name": "particle mass"}),
    "radius": ("f8", "radius", {"units": "m", "long_name": "particle radius for wall contact"}),
    "kind": ("i1", "kind", {"units": "1", "long_name": "particle kind",
                            "flag_values": np.array([FLUID, SPHERE, GHOST], np.int8),
                            "flag_meanings": "fluid sphere ghost"}),
    "id": ("i8", "id", {"units": "1", "long_name": "particle identifier, stable across the run"}),
}
STATE_OF = {"position": "pos", "velocity": "vel", "density": "rho", "pressure": "p"}
# the poses of the moving wall groups (sphcore.geometry.motion), when the case has any: a
# point X of group g (where case.toml draws it) is at centre + shift + rotation (X - centre)
POSE_VARS = {
    "wall_shift": (("time", "wall_group", "spatial"), "f8",
                   {"units": "m", "long_name": "translation of each moving wall group"}),
    "wall_rotation": (("time", "wall_group", "spatial", "body_axis"), "f8",
                      {"units": "1", "long_name": "rotation of each moving wall group (world axis, body axis)"}),
    "wall_velocity": (("time", "wall_group", "spatial"), "f8",
                      {"units": "m s-1", "long_name": "velocity of each moving wall group's centre"}),
    "wall_angular_velocity": (("time", "wall_group", "axis3"), "f8",
                              {"units": "rad s-1", "long_name": "angular velocity of each moving wall group "
                               "(x, y, z; z alone in 2D)"}),
}


def case_attributes(config: dict, prefix: str = "") -> dict:
    """Flatten ``{section: {key: value}}`` into netCDF global attributes ``section.key``.

    Numbers stay numbers (bools become the strings "true"/"false": netCDF has no boolean),
    non-empty lists of numbers become arrays, any other list (strings, tables) a JSON
    string; None (an unset derived value) is left out.
    """
    out = {}
    for key, value in config.items():
        name = re.sub(r"[^A-Za-z0-9_.+-]", "_", f"{prefix}{key}")
        if value is None:
            continue
        if isinstance(value, dict):
            out.update(case_attributes(value, name + "."))
        elif isinstance(value, bool):
            out[name] = "true" if value else "false"
        elif isinstance(value, (int, np.integer)):
            out[name] = np.int64(value)
        elif isinstance(value, (float, np.floating)):
            out[name] = np.float64(value)
        elif isinstance(value, str):
            out[name] = value
        elif isinstance(value, (list, tuple)) and value and all(
            isinstance(v, (int, float)) and not isinstance(v, bool) for v in value
        ):
            kind = np.int64 if all(isinstance(v, int) for v in value) else np.float64
            out[name] = np.asarray(value, dtype=kind)
        else:
            out[name] = json.dumps(value, default=str)
    return out


def output_error(path: Path, what: str, err: Exception) -> OutputError:
    reason = getattr(err, "strerror", None) or str(err)
    return OutputError(f"{path}: cannot {what}: {reason}")


def new_dataset(path: Path, title: str, comment: str, attrs: dict) -> netCDF4.Dataset:
    """A new netCDF file at ``path`` with an unlimited ``time`` dimension and the CF global
    attributes (Conventions, title, source, history, comment, then ``attrs``); the
    particle and probe files of a run share it. A failure is an OutputError naming the file."""
    import netCDF4
    mark_written(path)  # sph's from now on, whatever happens next (the marker lists it)
    try:
        ds = netCDF4.Dataset(path, "w", format=FORMAT)
    except (OSError, RuntimeError) as err:
        raise output_error(path, "create the netCDF file", err) from err
    try:
        ds.set_auto_maskandscale(False)
        ds.createDimension("time", None)
        ds.setncatts({
            "Conventions": "CF-1.8",
            "title": title,
            "source": f"sphcore {sphcore.__version__}",
            "history": f"{_dt.datetime.now(_dt.timezone.utc).isoformat(timespec='seconds')} created by sphcore",
            "comment": comment,
            **attrs,
        })
    except (OSError, RuntimeError) as err:
        del ds  # not close(): see NetcdfWriter._abandon
        drop_cut(path)
        raise output_error(path, "write the netCDF header", err) from err
    return ds


def drop_cut(path: Path) -> None:
    """Remove a netCDF file whose header could not be written (a full disk): it holds no
    frame and cannot be read as a series, so the run leaves none rather than an unreadable
    one. The file is this run's own, created with mode "w" a moment before."""
    path.unlink(missing_ok=True)


class NetcdfWriter(ScheduledWriter):
    """Pluggy plugin ``netcdf``: all frames in ``<output_dir>/particles.nc`` on the ``[netcdf]`` schedule."""

    table = TABLE
    what = "netCDF frame"

    def __init__(self):
        super().__init__()
        self.ds: netCDF4.Dataset | None = None  # opened at the first frame due, not before
        self.path: Path | None = None
        self.row = 0  # index along time of the next frame
        self.ids: np.ndarray | None = None  # the file's particle ids (sorted)

    @hookimpl
    def sph_summary(self, ctx):
        return {"frames": self.row} if self.row else None

    @hookimpl
    def sph_finish(self, ctx):
        self.close()

    # ---------------------------------------------------------------- writing

    def close(self) -> None:
        """Close the file (idempotent)."""
        if self.ds is None:
            return
        try:
            self.ds.sync()
        except (OSError, RuntimeError) as err:
            self._abandon()
            raise output_error(self.path, "close", err) from err
        ds, self.ds = self.ds, None
        ds.close()

    def _abandon(self) -> None:
        """Drop the dataset after a failed write without calling close().

        netCDF4-python keeps a dataset whose close() failed marked open and closes it again
        when it is garbage-collected, which crashes the interpreter (double free in
        libnetcdf). Letting the collector close it once is safe; the frames synced before
        stay readable.
        """
        self.ds = None
        self._failed = True

    def write_frame(self, ctx) -> None:
        """Append the current state as the next frame and sync it to disk."""
        if ctx.output_dir is None:
            raise OutputError("netcdf: this run has no output directory")
        st = ctx.host()
        order = np.argsort(st.id, kind="stable")
        if self.ds is None:
            if st.n == 0:  # a netCDF dimension of length 0 would be a second unlimited one
                raise OutputError(f"{Path(ctx.output_dir) / FILE_NAME}: no particles to write")
            self._create(ctx, st, order)
        ids = st.id[order]
        if not np.array_equal(ids, self.ids):
            raise OutputError(
                f"{self.path}: the set of particles changed ({len(self.ids)} in the file, "
                f"{len(ids)} now); one netCDF file needs the same particles in every frame")
        try:
            # time = NaN first: should a write fail mid-frame (disk full), the library may
            # still count the record, and the partial frame then reads as time = NaN.
            self.ds["time"][self.row] = np.nan
            for name, field in STATE_OF.items():
                self.ds[name][self.row] = getattr(st, field)[order]
            self.ds["step"][self.row] = int(ctx.step)
            for g, group in enumerate(getattr(ctx.case, "moving", ())):
                pose = group.motion.pose(ctx.t)
                self.ds["wall_shift"][self.row, g] = pose.shift
                self.ds["wall_rotation"][self.row, g] = pose.rotation
                self.ds["wall_velocity"][self.row, g] = pose.velocity
                self.ds["wall_angular_velocity"][self.row, g] = pose.omega
            self.ds["time"][self.row] = float(ctx.t)  # last: a frame with a time is complete
            # sync: header and data on disk now, so a killed run keeps this frame
            self.ds.sync()
        except (OSError, RuntimeError) as err:
            self._abandon()
            raise output_error(self.path, f"write the frame at step {ctx.step}", err) from err
        self.row += 1

    def _create(self, ctx, st, order) -> None:
        self.path = Path(ctx.output_dir) / FILE_NAME
        case = ctx.case
        ds = new_dataset(self.path, f"sphcore particles: {getattr(case, 'name', '')}",
                         "particles sorted by id; the case's parameters follow as section.key attributes",
                         case_attributes(getattr(case, "config", {}) or {}))
        try:
            ds.createDimension("particle", st.n)
            ds.createDimension("spatial", st.dim)
            for name, (dims, dtype, attrs) in FRAME_VARS.items():
                ds.createVariable(name, dtype, dims, fill_value=False).setncatts(attrs)
            for name, (dtype, field, attrs) in STATIC_VARS.items():
                var = ds.createVariable(name, dtype, ("particle",), fill_value=False)
                var.setncatts(attrs)
                var[:] = getattr(st, field)[order]
            moving = getattr(case, "moving", ())
            if moving:
                ds.createDimension("wall_group", len(moving))
                ds.createDimension("body_axis", st.dim)
                ds.createDimension("axis3", 3)
                ds.setncattr("wall_groups", "; ".join(g.name for g in moving))
                for name, (dims, dtype, attrs) in POSE_VARS.items():
                    ds.createVariable(name, dtype, dims, fill_value=False).setncatts(attrs)
                centre = ds.createVariable("wall_centre", "f8", ("wall_group", "spatial"), fill_value=False)
                centre.setncatts({"units": "m", "long_name": "centre of rotation of each moving wall group"})
                centre[:] = np.array([g.motion.pose(0.0).centre for g in moving])
            ds.sync()
        except (OSError, RuntimeError) as err:
            del ds  # not close(): see _abandon
            drop_cut(self.path)
            self._failed = True
            raise output_error(self.path, "write the netCDF header", err) from err
        self.ds, self.row, self.ids = ds, 0, st.id[order].copy()

    # ---------------------------------------------------------------- restart

    def frames_on_disk(self, ctx):
        return series_on_disk(Path(ctx.output_dir) / FILE_NAME, set(FRAME_VARS) | set(STATIC_VARS))

    def reopen_for_restart(self, ctx) -> None:
        """Reopen ``particles.nc`` of an earlier run and go on appending; frames up to ``ctx.step`` stay.

        Called with ``ctx`` at the restart point or at the first step after it (the first
        output of a restarted run). Frames after ``ctx.step`` (written after the checkpoint)
        are dropped by rewriting the file without them, as a netCDF record dimension cannot
        shrink; a frame at ``ctx.step`` itself holds the same state (checkpoints restart bit
        for bit) and stays. The particle dimension stays; the schedule counts the kept
        frames as written.
        """
        import netCDF4
        path = Path(ctx.output_dir or ".") / FILE_NAME
        if ctx.output_dir is None or not path.exists():
            return  # nothing written before: the first frame creates the file
        try:
            if header_cut(path, set(FRAME_VARS) | set(STATIC_VARS)):
                return  # no frame in it: this run's first frame writes it anew
            with netCDF4.Dataset(path) as src:
                src.set_auto_maskandscale(False)
                steps, times = src["step"][:], src["time"][:]
            # frames to keep: the leading ones up to the restart step (a NaN time marks
            # a frame left incomplete by a failed write, a time out of order a cut file)
            keep = leading_complete(times, steps, ctx.step)
            if keep < len(steps):
                rewrite_first(path, keep)
            ds = netCDF4.Dataset(path, "a")
            ds.set_auto_maskandscale(False)
            ids = ds["id"][:]
        except (OSError, RuntimeError, KeyError, IndexError) as err:
            raise output_error(path, "reopen the netCDF file to restart", err) from err
        self.ds, self.path, self.row, self.ids = ds, path, keep, ids
        if keep:
            t_last = float(times[keep - 1])
            self.schedule.resume(t_last, int(steps[keep - 1]) if steps[keep - 1] == ctx.step else None)


def series_on_disk(path: Path, names):
    """(path, frames) of a netCDF series for a restart's check (``ScheduledWriter.frames_on_disk``):
    ``(time, step)`` of every record, None when the file is missing, [] when its header was
    cut; None for a link (the output directory refuses it). A file that is not a regular,
    readable netCDF file is a CaseError naming it."""
    import netCDF4
    if path.is_symlink():
        return None
    if not path.exists():
        return path, None
    redo = "restore it, or run again with --overwrite (or --output DIR)"
    if not path.is_file():
        raise CaseError(path, "--restart", f"not a regular file; {redo}")
    try:
        if header_cut(path, names):
            return path, []
        with netCDF4.Dataset(path) as src:
            src.set_auto_maskandscale(False)
            times, steps = np.asarray(src["time"][:], float), np.asarray(src["step"][:])
    except (OSError, RuntimeError, KeyError, IndexError, ValueError) as err:
        reason = getattr(err, "strerror", None) or str(err) or type(err).__name__
        raise CaseError(path, "--restart", f"not a readable netCDF file ({reason}); {redo}") from None
    return path, list(zip(times.tolist(), steps.tolist()))


def header_cut(path: Path, names) -> bool:
    """Was the file cut while its header was written (a run killed, or its disk full, inside
    its first frame's create, which syncs the whole header before any frame): empty, without
    every one of the variables ``names``, or without a single record? The last covers a
    header whose variables were declared but whose static data (the particle ids) never
    reached the disk. Such a file holds no frame; a restart writes it anew."""
    import netCDF4
    if path.stat().st_size == 0:
        return True
    with netCDF4.Dataset(path) as src:
        return not set(names) <= set(src.variables) or len(src.dimensions["time"]) == 0


def rewrite_first(path: Path, keep: int) -> None:
    """Replace ``path`` by a copy holding only its first ``keep`` frames (atomic rename)."""
    import netCDF4
    tmp = path.with_name(f".{path.name}.tmp")
    try:
        with netCDF4.Dataset(path) as src, netCDF4.Dataset(tmp, "w", format=src.data_model) as dst:
            src.set_auto_maskandscale(False)
            dst.set_auto_maskandscale(False)
            dst.setncatts({k: src.getncattr(k) for k in src.ncattrs()})
            for name, dim in src.dimensions.items():
                dst.createDimension(name, None if dim.isunlimited() else len(dim))
            for name, var in src.variables.items():
                out = dst.createVariable(name, var.dtype, var.dimensions, fill_value=False)
                out.setncatts({k: var.getncattr(k) for k in var.ncattrs()})
                if "time" not in var.dimensions:
                    out[:] = var[:]
            for i in range(keep):  # frame by frame: a run's frames need not fit in memory
                for name, var in src.variables.items():
                    if "time" in var.dimensions:
                        dst[name][i] = var[i]
        tmp.replace(path)
    finally:
        tmp.unlink(missing_ok=True)  # only still there if something failed
