"""Forces and moments of the fluid on each moving wall group, as time series: ``wall_loads``.

The plugins whose walls take momentum from the fluid add it to the run as they act
(:meth:`sphcore.plugin.context.RunContext.add_wall_load`): the reflective walls the
momentum their reflections give the particles (with the opposite sign), a pressure model
its force times the step. At each sample this writer divides what was added since the
previous sample by the time between them, so a row holds the mean force (N; N/m in 2D)
and the mean moment about the group's centre of rotation where it is (N m; N m/m about z
in 2D) over the interval that ends at its time: reflective impulses, which come in single
steps, then read as the force they amount to over the interval (a paddle's force, a
sloshing load), not as spikes of one step.

Files (in the output directory): ``wall_loads.nc`` (netCDF-3 CDF-5 like ``particles.nc``:
readable while the run writes, a killed run keeps every synced row; dimensions ``time``,
``wall_group`` (in the order of the attribute ``wall_groups``), ``axis3``; variables
``force`` and ``moment`` with units) and ``wall_loads.csv`` (written when the run ends:
``t``, then ``<group>.Fx`` .. ``<group>.Mz`` columns). The summary gives, per group, the
largest magnitude of the force and of the moment, with their times, and the extremes of
each component. The first row (t = 0) has no interval and holds NaN.

    [plugins]
    use = ["reflective", "wall_loads"]

    [wall_loads]
    every_dt = 0.005   # s between rows (or every_steps)
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from sphcore.api import OutputError, ScheduledWriter, hookimpl, leading_complete, rotation_vector, write_atomically
from sphcore_plugins.netcdf import (
    case_attributes,
    drop_cut,
    header_cut,
    new_dataset,
    output_error,
    rewrite_first,
    series_on_disk,
)

TABLE = "wall_loads"
FILE_NAME = "wall_loads.nc"
CSV_NAME = "wall_loads.csv"
HEADER = {"time", "step", "force", "moment", "position", "rotation", "velocity", "angular_velocity"}
COMPONENTS = ("Fx", "Fy", "Fz", "Mx", "My", "Mz")
#: the group's motion at each row: its centre of rotation, rotation vector, their rates
KINEMATICS = {"position": ("x", "y", "z"), "rotation": ("rx", "ry", "rz"), "velocity": ("vx", "vy", "vz"),
              "angular_velocity": ("wx", "wy", "wz")}


class WallLoadsWriter(ScheduledWriter):
    """Pluggy plugin ``wall_loads``: the moving walls' loads on the ``[wall_loads]`` schedule."""

    table = TABLE
    what = "wall-loads row"

    def __init__(self):
        super().__init__()
        self.ds = None
        self.row = 0
        self.groups: tuple = ()

    @hookimpl
    def sph_configure(self, case):
        super().sph_configure(case)
        self.groups = tuple(g.name for g in getattr(case, "moving", ()))

    @hookimpl
    def sph_summary(self, ctx):
        if not self.groups or ctx.output_dir is None or not (Path(ctx.output_dir) / FILE_NAME).exists():
            return None
        t, loads = read_loads(Path(ctx.output_dir) / FILE_NAME)
        out = {"rows": int(len(t))}
        for g, name in enumerate(self.groups):
            f, m = loads[:, g, :3], loads[:, g, 3:]
            ok = np.isfinite(f).all(axis=1)
            if not ok.any():
                continue
            fmag, mmag = np.linalg.norm(f[ok], axis=1), np.linalg.norm(m[ok], axis=1)
            tt = t[ok]
            out[name] = {"max_force": float(fmag.max()), "t_max_force": float(tt[np.argmax(fmag)]),
                         "max_moment": float(mmag.max()), "t_max_moment": float(tt[np.argmax(mmag)]),
                         **{f"min_{c}": float(loads[ok, g, k].min()) for k, c in enumerate(COMPONENTS)},
                         **{f"max_{c}": float(loads[ok, g, k].max()) for k, c in enumerate(COMPONENTS)}}
        return out

    @hookimpl
    def sph_finish(self, ctx):
        if self.ds is not None:
            self.ds.close()
            self.ds = None
        path = Path(ctx.output_dir or ".") / FILE_NAME
        if ctx.output_dir is not None and self.groups and path.exists():
            t, loads = read_loads(path)
            motion = read_kinematics(path)
            columns = COMPONENTS + tuple(c for cs in KINEMATICS.values() for c in cs)
            header = "t," + ",".join(f"{g}.{c}" for g in self.groups for c in columns)
            table = np.concatenate([loads, motion], axis=2)
            rows = [",".join([repr(float(t[i]))] + [repr(float(x)) for x in table[i].ravel()]) for i in range(len(t))]
            text = "# force in N (N/m in 2D), moment in N m (N m/m in 2D) about each group's centre of rotation; " \
                   "its position (m), rotation vector (rad), velocity (m/s) and angular velocity (rad/s)\n" \
                   + header + "\n" + "".join(r + "\n" for r in rows)
            write_atomically(Path(ctx.output_dir) / CSV_NAME, lambda tmp: tmp.write_text(text))

    # ---------------------------------------------------------------- writing

    def write_frame(self, ctx) -> None:
        if ctx.output_dir is None or not self.groups:
            return
        kept = ctx.kept(self)
        sums = ctx.run.kept.setdefault("wall_impulses", {})
        interval = float(ctx.t) - float(kept.get("t_last", ctx.t))
        values = np.full((len(self.groups), 6), np.nan)
        for g, name in enumerate(self.groups):
            acc = sums.get(name, [0.0] * 6)
            if interval > 0:
                values[g] = np.asarray(acc) / interval
            sums[name] = [0.0] * 6
        kept["t_last"] = float(ctx.t)
        if self.ds is None:
            self._create(ctx)
        try:
            self.ds["time"][self.row] = np.nan
            self.ds["force"][self.row] = values[:, :3]
            self.ds["moment"][self.row] = values[:, 3:]
            for name, rows in kinematics(ctx, self.groups).items():
                self.ds[name][self.row] = rows
            self.ds["step"][self.row] = int(ctx.step)
            self.ds["time"][self.row] = float(ctx.t)  # last: a row with a time is complete
            self.ds.sync()
        except (OSError, RuntimeError) as err:
            raise output_error(self.path, f"write the wall loads at step {ctx.step}", err) from err
        self.row += 1

    def _create(self, ctx) -> None:
        self.path = Path(ctx.output_dir) / FILE_NAME
        dim = ctx.case.dim
        unit_f, unit_m = ("N m-1", "N") if dim == 2 else ("N", "N m")
        ds = new_dataset(self.path, f"sphcore wall loads: {ctx.case.config['case']['name'] or ctx.case.dir.name}",
                         "mean force and moment of the fluid on each moving wall group over the interval ending "
                         "at each time; moments about the group's centre of rotation where it is",
                         {"wall_groups": "; ".join(self.groups), **case_attributes(ctx.case.config)})
        try:
            ds.createDimension("wall_group", len(self.groups))
            ds.createDimension("axis3", 3)
            ds.createVariable("step", "i8", ("time",), fill_value=False).setncatts(
                {"units": "1", "long_name": "time step index"})
            ds.createVariable("time", "f8", ("time",), fill_value=False).setncatts(
                {"units": "s", "standard_name": "time", "long_name": "end of the averaging interval"})
            ds.createVariable("force", "f8", ("time", "wall_group", "axis3"), fill_value=False).setncatts(
                {"units": unit_f, "long_name": "force of the fluid on the wall group (x, y, z)"})
            ds.createVariable("moment", "f8", ("time", "wall_group", "axis3"), fill_value=False).setncatts(
                {"units": unit_m, "long_name": "moment of the fluid on the wall group about its centre of rotation"})
            for name, (unit, meaning) in {
                    "position": ("m", "the group's centre of rotation (a body's centre of mass) where it is"),
                    "rotation": ("rad", "rotation vector (axis times angle) of the group from where case.toml "
                                        "draws it (2D: about z)"),
                    "velocity": ("m s-1", "velocity of the group's centre of rotation"),
                    "angular_velocity": ("rad s-1", "angular velocity of the group")}.items():
                ds.createVariable(name, "f8", ("time", "wall_group", "axis3"), fill_value=False).setncatts(
                    {"units": unit, "long_name": meaning})
            ds.sync()
        except (OSError, RuntimeError) as err:
            del ds  # not close(): see sphcore_plugins.netcdf.NetcdfWriter._abandon
            drop_cut(self.path)
            raise output_error(self.path, "write the wall loads' header", err) from err
        self.ds, self.row = ds, 0

    def frames_on_disk(self, ctx):
        return series_on_disk(Path(ctx.output_dir) / FILE_NAME, HEADER)

    def reopen_for_restart(self, ctx) -> None:
        """Keep the rows up to the restart's step and go on appending."""
        import netCDF4
        path = Path(ctx.output_dir or ".") / FILE_NAME
        if ctx.output_dir is None or not path.exists():
            return
        try:
            if header_cut(path, HEADER):
                return
            with netCDF4.Dataset(path) as src:
                src.set_auto_maskandscale(False)
                steps, times = src["step"][:], src["time"][:]
            keep = leading_complete(times, steps, ctx.step)
            if keep < len(steps):
                rewrite_first(path, keep)
            ds = netCDF4.Dataset(path, "a")
            ds.set_auto_maskandscale(False)
        except (OSError, RuntimeError, KeyError, IndexError) as err:
            raise OutputError(f"{path}: cannot reopen the wall loads to restart: {err}") from err
        self.ds, self.path, self.row = ds, path, keep
        if keep:
            t_last = float(times[keep - 1])
            # the next row's interval starts at the last row kept (a checkpoint taken before
            # that row was written does not know it)
            ctx.kept(self)["t_last"] = t_last
            self.schedule.resume(t_last, int(steps[keep - 1]) if steps[keep - 1] == ctx.step else None)


def read_loads(path: Path):
    """(t (n,), loads (n, groups, 6): Fx Fy Fz Mx My Mz) of a ``wall_loads.nc``, complete rows."""
    import netCDF4
    with netCDF4.Dataset(path) as ds:
        ds.set_auto_maskandscale(False)
        t = np.asarray(ds["time"][:], float)
        loads = np.concatenate([np.asarray(ds["force"][:], float), np.asarray(ds["moment"][:], float)], axis=2)
    ok = np.isfinite(t)
    return t[ok], loads[ok]


def kinematics(ctx, groups) -> dict:
    """Each group's motion now: {variable: (groups, 3)} (2D: the third component of the
    position and velocity 0, rotations about z)."""
    moving = {g.name: g for g in getattr(ctx.case, "moving", ())}
    out = {name: np.zeros((len(groups), 3)) for name in KINEMATICS}
    for k, name in enumerate(groups):
        pose = moving[name].motion.pose(ctx.t)
        dim = len(pose.shift)
        out["position"][k, :dim] = pose.centre + pose.shift
        out["velocity"][k, :dim] = pose.velocity
        out["rotation"][k] = rotation_vector(pose.rotation)
        out["angular_velocity"][k] = pose.omega
    return out


def read_kinematics(path: Path) -> np.ndarray:
    """(n, groups, 12) of a ``wall_loads.nc``: position, rotation, velocity, angular velocity,
    complete rows."""
    import netCDF4
    with netCDF4.Dataset(path) as ds:
        ds.set_auto_maskandscale(False)
        t = np.asarray(ds["time"][:], float)
        parts = [np.asarray(ds[name][:], float) for name in KINEMATICS]
    return np.concatenate(parts, axis=2)[np.isfinite(t)]
