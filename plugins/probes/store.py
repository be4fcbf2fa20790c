"""Where probe samples go: ``probes.nc`` (appended and synced per sample) and ``probes.csv``.

``probes.nc`` is netCDF-3 CDF-5 like ``particles.nc`` (readable while the run writes, a
killed run keeps every synced sample; see :mod:`sphcore_plugins.netcdf`). Dimensions
``time`` (unlimited) x ``probe``; ``pressure`` (Pa) holds NaN in the columns of depth probes
and ``depth`` (m) NaN in those of pressure probes; ``dry`` is 1 where no fluid particle was
within the kernel support of any sample point (pressure 0, depth 0). The probes' names,
kinds, modes, extents (``probe_start``/``probe_end``, m), column heights H and reference
names are variables along ``probe``; ``rho0`` and ``g`` are global attributes. Where a
sensor rides with moving walls, ``probe_attach`` names their group ("tank", "walls[k]";
empty for a fixed sensor) and its extent is where case.toml draws the walls (the walls'
pose at every frame is in ``particles.nc``); a file with no attached sensor has no
``probe_attach``.
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

import numpy as np

from sphcore.api import leading_complete, write_atomically
from sphcore_plugins.netcdf import (
    case_attributes,
    drop_cut,
    header_cut,
    new_dataset,
    output_error,
    rewrite_first,
    series_on_disk,
)

if TYPE_CHECKING:  # imported where a file is opened: a run that writes none does not pay for it
    import netCDF4

FILE_NAME = "probes.nc"
CSV_NAME = "probes.csv"
KIND_CODES = {"pressure": 0, "depth": 1}
MODE_CODES = {"": -1, "wall": 0, "particle": 1}
#: every variable the header defines (a file without all of them was cut while its header was written)
HEADER_VARS = {"time", "step", "pressure", "depth", "dry", "probe_name", "probe_reference", "probe_kind",
               "probe_mode", "probe_start", "probe_end", "probe_points", "probe_H"}


def _chars(names):
    import netCDF4
    width = max(1, max(len(s) for s in names))
    return netCDF4.stringtochar(np.array(list(names), dtype=f"S{width}")), width


class ProbeFile:
    """``probes.nc`` of one run: create at the first sample, append, sync, reopen on restart."""

    def __init__(self, directory: Path):
        self.path = Path(directory) / FILE_NAME
        self.ds: netCDF4.Dataset | None = None
        self.row = 0

    def create(self, probes, dim, rho0, g, config, case_name=""):
        ds = new_dataset(
            self.path, f"sphcore probes: {case_name}",
            "pressure: Shepard kernel interpolation of the fluid within 2h (wall mode: hydrostatic "
            "extrapolation to the sensor); depth: first height above the floor point where the "
            "fluid fraction drops below 0.5; see sphcore_plugins.probes.sampling",
            {"rho0": np.float64(rho0), "g": np.float64(g), **case_attributes(config or {})})
        try:
            ds.createDimension("probe", len(probes))
            ds.createDimension("spatial", dim)
            names, width = _chars([p.name for p in probes])
            refs, rwidth = _chars([p.reference or "" for p in probes])
            ds.createDimension("name_strlen", width)
            ds.createDimension("reference_strlen", rwidth)
            v = ds.createVariable("time", "f8", ("time",), fill_value=False)
            v.setncatts({"units": "s", "standard_name": "time", "long_name": "simulated time since gate release"})
            ds.createVariable("step", "i8", ("time",), fill_value=False).setncatts(
                {"units": "1", "long_name": "time step index"})
            ds.createVariable("pressure", "f8", ("time", "probe"), fill_value=False).setncatts(
                {"units": "Pa", "long_name": "gauge pressure at the sensor (NaN for depth probes)"})
            ds.createVariable("depth", "f8", ("time", "probe"), fill_value=False).setncatts(
                {"units": "m", "long_name": "water depth above the probe point along -g (NaN for pressure probes)"})
            ds.createVariable("dry", "i1", ("time", "probe"), fill_value=False).setncatts(
                {"units": "1", "long_name": "1: no fluid particle within 2h of any sample point (value 0)",
                 "flag_values": np.array([0, 1], np.int8), "flag_meanings": "wet dry"})
            ds.createVariable("probe_name", "S1", ("probe", "name_strlen"))[:] = names
            ds.createVariable("probe_reference", "S1", ("probe", "reference_strlen"))[:] = refs
            kv = ds.createVariable("probe_kind", "i1", ("probe",), fill_value=False)
            kv.setncatts({"units": "1", "flag_values": np.array(list(KIND_CODES.values()), np.int8),
                          "flag_meanings": " ".join(KIND_CODES)})
            kv[:] = [KIND_CODES[p.kind] for p in probes]
            mv = ds.createVariable("probe_mode", "i1", ("probe",), fill_value=False)
            mv.setncatts({"units": "1", "flag_values": np.array([0, 1], np.int8), "flag_meanings": "wall particle",
                          "comment": "-1 for depth probes"})
            mv[:] = [MODE_CODES[p.mode] for p in probes]
            for name, field, doc in (("probe_start", "start", "one end of the sensor (a point sensor: the point)"),
                                     ("probe_end", "end", "other end of the sensor (a point sensor: the point)")):
                var = ds.createVariable(name, "f8", ("probe", "spatial"), fill_value=False)
                var.setncatts({"units": "m", "long_name": doc})
                var[:] = np.array([getattr(p, field) for p in probes])
            nv = ds.createVariable("probe_points", "i4", ("probe",), fill_value=False)
            nv.setncatts({"units": "1", "long_name": "sample points averaged along the sensor"})
            nv[:] = [len(p.points) for p in probes]
            hv = ds.createVariable("probe_H", "f8", ("probe",), fill_value=False)
            hv.setncatts({"units": "m", "long_name": "column height that scales the reference (NaN: none)"})
            hv[:] = [np.nan if p.height is None else p.height for p in probes]
            if any(p.attach for p in probes):
                attach, awidth = _chars([p.attach or "" for p in probes])
                ds.createDimension("attach_strlen", awidth)
                av = ds.createVariable("probe_attach", "S1", ("probe", "attach_strlen"))
                av.setncatts({"long_name": "moving walls the sensor rides with (empty: fixed); probe_start and "
                              "probe_end are then where case.toml draws the walls"})
                av[:] = attach
            ds.sync()
        except (OSError, RuntimeError) as err:
            del ds  # not close(): see sphcore_plugins.netcdf.NetcdfWriter._abandon
            drop_cut(self.path)
            raise output_error(self.path, "write the netCDF header", err) from err
        self.ds, self.row = ds, 0

    def append(self, t, step, pressure, depth, dry):
        """One sample: arrays along ``probe``; synced before returning."""
        try:
            ds = self.ds
            ds["time"][self.row] = np.nan  # a sample with a time is complete (see netcdf.py)
            ds["step"][self.row] = int(step)
            ds["pressure"][self.row] = pressure
            ds["depth"][self.row] = depth
            ds["dry"][self.row] = dry
            ds["time"][self.row] = float(t)
            ds.sync()
        except (OSError, RuntimeError) as err:
            self.ds = None  # let the collector close it (see netcdf.py)
            raise output_error(self.path, f"write the sample at step {step}", err) from err
        self.row += 1

    def on_disk(self):
        """(path, samples) for a restart's check (see sphcore.api.check_series)."""
        return series_on_disk(self.path, HEADER_VARS)

    def reopen(self, last_step) -> dict | None:
        """Reopen an earlier run's file, keep the leading complete samples with step <= ``last_step``
        and go on appending; returns the kept series {time, step, pressure, depth, dry}, or None
        when there is no file."""
        import netCDF4
        if not self.path.exists():
            return None
        try:
            if header_cut(self.path, HEADER_VARS):
                return None  # no sample in it: the first sample writes it anew
            with netCDF4.Dataset(self.path) as src:
                src.set_auto_maskandscale(False)
                steps, times = src["step"][:], src["time"][:]
            keep = leading_complete(times, steps, last_step)
            if keep < len(steps):
                rewrite_first(self.path, keep)
            ds = netCDF4.Dataset(self.path, "a")
            ds.set_auto_maskandscale(False)
            kept = {name: np.array(ds[name][:keep]) for name in ("time", "step", "pressure", "depth", "dry")}
        except (OSError, RuntimeError, KeyError, IndexError) as err:
            raise output_error(self.path, "reopen the netCDF file to restart", err) from err
        self.ds, self.row = ds, keep
        return kept

    def close(self):
        if self.ds is None:
            return
        ds, self.ds = self.ds, None
        try:
            ds.close()
        except (OSError, RuntimeError) as err:
            raise output_error(self.path, "close", err) from err


def write_csv(path: Path, probes, t, values):
    """``probes.csv``: time_s, then one column per probe (``<name>_pa`` or ``<name>_m``);
    written to a temporary name and renamed, so a reader never sees half a file."""
    path = Path(path)
    header = ",".join(["time_s"] + [f"{p.name}_{'pa' if p.kind == 'pressure' else 'm'}" for p in probes])
    data = np.column_stack([np.asarray(t, float), np.asarray(values, float).reshape(len(t), len(probes))])
    write_atomically(path, lambda tmp: np.savetxt(tmp, data, delimiter=",", header=header, comments="", fmt="%.10g"))
