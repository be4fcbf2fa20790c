"""Energy budget of a run written by the ``netcdf`` plugin: kinetic + potential + Tait
elastic energy per frame, and how much it ever grew (docs/speed_accuracy.md).

    python docs/energy_budget.py OUTPUT/particles.nc [...] [--threshold 0.5]

E = sum_i m_i (|v_i|^2 / 2 + g y_i + e(rho_i)), with the Tait internal energy per unit
mass e = B / rho0 (r^(gamma-1) / (gamma-1) + 1/r - gamma/(gamma-1)), r = rho / rho0,
B = c0^2 rho0 / gamma (the integral of p / rho^2 d rho from rho0). In 2D the energies are
per metre of depth (J/m). With walls of restitution CR <= 1 and artificial viscosity
alpha >= 0, E can only fall; growth is numerical. c0, rho0 and gamma are read from the
``summary.json`` next to the file when it holds them (c0), else from the options.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

import numpy as np
import xarray as xr


def budget(path, c0, rho0=1000.0, gamma=7.0, g=9.81, up=1):
    """Rows (t, E_kin, E_pot, E_elastic, max |rho/rho0 - 1|, max |v|, finite) per frame."""
    ds = xr.open_dataset(path)
    m = ds["mass"].values
    m = m[0] if m.ndim == 2 else m
    b = c0 ** 2 * rho0 / gamma
    rows = []
    for k in range(ds.sizes["time"]):
        v, x, rho = ds["velocity"].values[k], ds["position"].values[k], ds["density"].values[k]
        r = rho / rho0
        ek = 0.5 * float((m * (v ** 2).sum(-1)).sum())
        ep = float((m * g * x[:, up]).sum())
        ei = float((m * b / rho0 * (r ** (gamma - 1) / (gamma - 1) + 1 / r - gamma / (gamma - 1))).sum())
        finite = bool(np.isfinite(v).all() and np.isfinite(x).all() and np.isfinite(rho).all())
        rows.append((float(ds["time"].values[k]), ek, ep, ei, float(np.abs(r - 1).max()),
                     float(np.linalg.norm(v, axis=1).max()), finite))
    return rows


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("files", nargs="+")
    ap.add_argument("--c0", type=float, help="sound speed (m/s) when no summary.json says it")
    ap.add_argument("--rho0", type=float, default=1000.0)
    ap.add_argument("--gamma", type=float, default=7.0)
    ap.add_argument("--threshold", type=float, default=0.5, help="energy growth (J/m) reported as the crossing time")
    a = ap.parse_args()
    for f in a.files:
        summary = Path(f).with_name("summary.json")
        c0 = json.loads(summary.read_text()).get("c0") if summary.exists() else a.c0
        if not c0:
            raise SystemExit(f"{f}: no summary.json with c0 next to it: pass --c0")
        rows = budget(f, c0, a.rho0, a.gamma)
        e = np.array([r[1] + r[2] + r[3] for r in rows])
        de = e - e[0]
        k = int(np.argmax(de))
        over = [f"{r[0]:.3f} s" for r, d in zip(rows, de) if d > a.threshold]
        print(f"{f}: E0 = {e[0]:.3f}, max growth {de[k]:+.3f} at t = {rows[k][0]:.3f} s, final {de[-1]:+.3f}; "
              f"growth > {a.threshold:g} first at {'t = ' + over[0] if over else 'no frame'}; "
              f"max |rho/rho0 - 1| = {max(r[4] for r in rows):.3f}, max |v| = {max(r[5] for r in rows):.2f} m/s; "
              f"{'all frames finite' if all(r[6] for r in rows) else 'NON-FINITE values in some frame'}")


if __name__ == "__main__":
    main()
