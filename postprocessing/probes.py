"""Plot every probe of a run against its experiment and print the error figures.

    python postprocessing/probes.py RUN_DIR [--windows WIDTH]

Reads ``RUN_DIR/probes.nc`` (written by the ``probes`` plugin). For each pressure probe
that names a reference: p/(rho g H) against t sqrt(g/H) with Buchner's points, or against
t/T (T = sqrt(H/g)) with Lobovsky's 2.5-97.5 % band shaded and its median; other pressure
probes in Pa against s, depth probes in m against s. One ``probe_<name>.png`` per probe
beside the run (a name sph itself never writes). The error figures are those of the run
summary (:mod:`sphcore_plugins.probes.figures`); ``--windows WIDTH`` also prints, for each
pressure probe with a reference, the means of simulation and experiment over consecutive
windows of WIDTH in the experiment's time scale (:func:`figures.window_means`). A missing
directory, a run without ``probes.nc`` or a WIDTH that is not > 0 prints one line on
stderr and exits with status 2.
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np

PNG = "probe_{}.png"


def _text(chars) -> list[str]:
    import netCDF4

    return [s.strip() for s in netCDF4.chartostring(np.asarray(chars)).tolist()]


def read(path: Path) -> dict:
    """The probes of ``path`` (probes.nc): {t, rho0, g, probes: [{name, kind, reference, H, values}]}."""
    import netCDF4

    with netCDF4.Dataset(path) as ds:
        ds.set_auto_maskandscale(False)
        t = np.array(ds["time"][:])
        ok = np.isfinite(t)  # a sample left incomplete by a failed write has no time
        names, refs = _text(ds["probe_name"][:]), _text(ds["probe_reference"][:])
        kinds, heights = np.array(ds["probe_kind"][:]), np.array(ds["probe_H"][:])
        p, d = np.array(ds["pressure"][:])[ok], np.array(ds["depth"][:])[ok]
        rho0, g = float(ds.getncattr("rho0")), float(ds.getncattr("g"))
    probes = [{"name": n, "kind": "pressure" if k == 0 else "depth", "reference": r or None,
               "H": None if not np.isfinite(hh) else float(hh), "values": (p if k == 0 else d)[:, i]}
              for i, (n, r, k, hh) in enumerate(zip(names, refs, kinds, heights))]
    return {"t": t[ok], "rho0": rho0, "g": g, "probes": probes}


def plot(run, probe, t, rho0, g, png):
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    from sphcore_plugins.gauges import reference

    fig, ax = plt.subplots(figsize=(7, 4))
    ref, height, v = probe["reference"], probe["H"], probe["values"]
    if probe["kind"] == "depth":
        ax.plot(t, v, "-", lw=1, label="sphcore")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("water depth [m]")
    elif ref is None:
        ax.plot(t, v, "-", lw=1, label="sphcore")
        ax.set_xlabel("t [s]")
        ax.set_ylabel("pressure [Pa]")
    else:
        series, data = reference.SERIES[ref], reference.series(ref)
        tau = t * math.sqrt(g / height)
        if series.kind == "lobovsky":
            ax.fill_between(data[:, 0], data[:, 1], data[:, 3], color="0.8", label=series.label)
            ax.plot(data[:, 0], data[:, 2], "k-", lw=0.8, label="experiment median")
            ax.set_xlabel("t / T,  T = sqrt(H/g)")
            ax.set_xlim(0, max(float(data[-1, 0]), float(tau[-1]) if tau.size else 0))
        else:
            ax.plot(data[:, 0], data[:, 1], "ko", ms=3, mfc="none", label=series.label)
            ax.set_xlabel("t sqrt(g/H)")
        ax.plot(tau, v / (rho0 * g * height), "-", lw=1, label=f"sphcore ({run.name})")
        ax.set_ylabel("p / (rho g H)")
        top = 1.5 * max(float(np.max(data[:, -1])), 0.1)
        ax.set_ylim(-0.1 * top, top)  # impact spikes of a weakly compressible run would flatten the rest
    ax.set_title(f"probe {probe['name']}" + (f" vs {ref}" if ref else ""))
    ax.grid(alpha=0.3)
    ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(png, dpi=120)
    plt.close(fig)


def print_windows(probe, t, rho0, g, width):
    """The window means of a referenced pressure probe, one line per window."""
    from sphcore_plugins.gauges import reference
    from sphcore_plugins.probes import figures

    ref, height = probe["reference"], probe["H"]
    kind = reference.SERIES[ref].kind
    rows = figures.window_means(t * math.sqrt(g / height), probe["values"] / (rho0 * g * height),
                                reference.series(ref), kind, width)
    print(f"  window means of p/(rho g H) ({'band median' if kind == 'lobovsky' else 'points'} for the experiment):")
    print(f"  {'from':>8s} {'sphcore':>9s} {'experiment':>11s} {'difference':>11s}")
    for a, sim, exp in rows:
        print(f"  {a:8.3f} {sim:9.3f} {exp:11.3f} {sim - exp:+11.3f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("run", help="a run's output directory (holding probes.nc)")
    ap.add_argument("--windows", type=float, default=None, metavar="WIDTH",
                    help="print window means of p/(rho g H), simulation against experiment, windows of WIDTH")
    args = ap.parse_args(argv)
    if args.windows is not None and not (math.isfinite(args.windows) and args.windows > 0):
        print(f"probes.py: error: --windows: expected a width > 0, got {args.windows}", file=sys.stderr)
        return 2
    run = Path(args.run)
    path = run / "probes.nc"
    if not run.is_dir():
        print(f"probes.py: error: {run}: no such run directory", file=sys.stderr)
        return 2
    if not path.is_file():
        print(f"probes.py: error: {run}: no probes.nc (was the probes plugin in plugins.use?)", file=sys.stderr)
        return 2
    try:
        data = read(path)
    except (OSError, RuntimeError, KeyError) as err:
        print(f"probes.py: error: {path}: cannot read: {err}", file=sys.stderr)
        return 2
    from sphcore_plugins.probes import figures

    t = data["t"]
    for probe in data["probes"]:
        png = run / PNG.format(probe["name"])
        plot(run, probe, t, data["rho0"], data["g"], png)
        v = probe["values"]
        unit = "Pa" if probe["kind"] == "pressure" else "m"
        i = int(np.argmax(v)) if v.size else 0
        print(f"{probe['name']}: max {v[i]:.6g} {unit} at t = {t[i]:.6g} s -> {png}" if v.size else
              f"{probe['name']}: no samples")
        if probe["reference"] and v.size:
            errs = figures.errors(probe["reference"], t, v, data["rho0"], data["g"], probe["H"])
            for k, value in errs.items():
                print(f"  {k:28s} {value:.4f}" if isinstance(value, float) else f"  {k:28s} {value}")
            if args.windows is not None:
                print_windows(probe, t, data["rho0"], data["g"], args.windows)
    return 0


if __name__ == "__main__":
    sys.exit(main())
