"""Read a run's frames (ParaView .pvd written by the ``vtu`` plugin, or the ``netcdf``
plugin's particles.nc) as (time, points, fields) without knowing which writer made them."""

from __future__ import annotations

from pathlib import Path

import numpy as np


def frames(path):
    """Yield (t, pos (n, 3), fields dict) for every frame of a run.

    ``path`` is a .pvd, a .nc, or a run's output directory (the .pvd is preferred).
    """
    path = Path(path)
    if path.is_dir():
        pvd = sorted(path.glob("*.pvd"))
        nc = path / "particles.nc"
        path = pvd[0] if pvd else nc
    if path.suffix == ".nc":
        import xarray as xr

        with xr.open_dataset(path) as ds:
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
        yield float(t), np.asarray(mesh.points, float), {k: np.asarray(mesh.point_data[k]) for k in mesh.point_data}
