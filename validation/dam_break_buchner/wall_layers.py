"""Mean pressure of the layers of one dx above the floor, in a window of x, frame by frame.

The figure behind "the floor layer's excess" in docs/wall_pressure.md: for each frame of a
run's particles.nc (the ``netcdf`` plugin), the fluid particles with xa < x < xb are
binned in layers of one dx from the floor (z = 0), and each layer's mean pressure and
vertical velocity printed, with rho g dx, the hydrostatic step from one layer to the next.

    python validation/dam_break_buchner/wall_layers.py RUN_DIR --dx 0.015 --x 1.8 2.6 [--layers 4] [--times 0.35 0.4]
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import xarray as xr

G = 9.81


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("run", help="a run's output directory or its particles.nc")
    ap.add_argument("--dx", type=float, required=True, help="the run's particle spacing (m)")
    ap.add_argument("--x", type=float, nargs=2, required=True, metavar=("XA", "XB"), help="window along x (m)")
    ap.add_argument("--layers", type=int, default=4)
    ap.add_argument("--times", type=float, nargs="*", help="only the frames nearest these times (s)")
    ap.add_argument("--rho0", type=float, default=1000.0)
    args = ap.parse_args(argv)
    path = Path(args.run)
    path = path / "particles.nc" if path.is_dir() else path
    if not path.is_file():
        print(f"wall_layers.py: error: {path}: no such file (expected a run's particles.nc, the netcdf plugin's)",
              file=sys.stderr)
        return 2
    with xr.open_dataset(path) as ds:
        for k in range(ds.sizes["time"]):
            t = float(ds["time"][k])
            if args.times and min(abs(t - w) for w in args.times) > 0.5e-3:
                continue
            fr = ds.isel(time=k)
            pos, vel = fr["position"].values, fr["velocity"].values
            p, kind = fr["pressure"].values, fr["kind"].values
            up = pos.shape[1] - 1  # the vertical axis
            x, z = pos[:, 0], pos[:, up]
            inside = (kind == 0) & (x > args.x[0]) & (x < args.x[1])
            cells = []
            for layer in range(args.layers):
                m = inside & (z >= layer * args.dx) & (z < (layer + 1) * args.dx)
                cells.append(f"{p[m].mean():6.0f} Pa ({vel[m, up].mean():+.3f} m/s)" if m.any() else "     -")
            print(f"t {t:.3f} s: " + " | ".join(cells) + f"   rho g dx = {args.rho0 * G * args.dx:.0f} Pa")
    return 0


if __name__ == "__main__":
    raise SystemExit(main())
