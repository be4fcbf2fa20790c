"""Probes: every probe of a run plotted against its experiment, with the error figures.

Reads   RUN/probes.nc, written by the probes plugin (RUN: a run's output directory).
Writes  RUN/probe_<name>.png for every probe (a name sph itself never writes): a pressure
        probe that names a reference as p/(rho g H) against t sqrt(g/H) with Buchner's
        points, or against t/T (T = sqrt(H/g)) with Lobovsky's 2.5-97.5 % band shaded and
        its median; other pressure probes in Pa against s, depth probes in m against s.
        Prints each probe's maximum and, for a probe with a reference, the error figures
        of the run summary (sphcore_plugins.probes.figures).

``--windows WIDTH`` also prints, for each pressure probe with a reference, the means of
simulation and experiment over consecutive windows of WIDTH in the experiment's time scale
(figures.window_means). A missing directory, a run without probes.nc or a WIDTH that is not
> 0: one line on stderr, exit status 2.

    python postprocessing/probes.py cases/dam_break_buchner/output
"""

from __future__ import annotations

import argparse
import math
import sys
from pathlib import Path

import numpy as np
from runs import RunError, open_run, pyplot, refuse

from sphcore_plugins.gauges import reference
from sphcore_plugins.probes import figures

PROG = Path(__file__).name
PNG = "probe_{}.png"


def read(path) -> dict:
    """The probes of ``path`` (a probes.nc or the run directory holding it), as
    :meth:`runs.Run.probes` reads them: {t, rho0, g, probes: [{name, kind, reference, H, values}]}."""
    return open_run(path).probes()


def plot(run, probe, t, rho0, g, png):
    plt = pyplot()
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
    ref, height = probe["reference"], probe["H"]
    kind = reference.SERIES[ref].kind
    rows = figures.window_means(t * math.sqrt(g / height), probe["values"] / (rho0 * g * height),
                                reference.series(ref), kind, width)
    print(f"  window means of p/(rho g H) ({'band median' if kind == 'lobovsky' else 'points'} for the experiment):")
    print(f"  {'from':>8s} {'sphcore':>9s} {'experiment':>11s} {'difference':>11s}")
    for a, sim, exp in rows:
        print(f"  {a:8.3f} {sim:9.3f} {exp:11.3f} {sim - exp:+11.3f}")


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", help="a run's output directory (holding probes.nc)")
    ap.add_argument("--windows", type=float, default=None, metavar="WIDTH",
                    help="print window means of p/(rho g H), simulation against experiment, windows of WIDTH")
    args = ap.parse_args(argv)
    try:
        if args.windows is not None and not (math.isfinite(args.windows) and args.windows > 0):
            raise RunError(f"--windows: expected a width > 0, got {args.windows}")
        run = open_run(args.run)
        data = run.probes()
    except RunError as err:
        return refuse(PROG, err)
    t = data["t"]
    for probe in data["probes"]:
        png = run.dir / PNG.format(probe["name"])
        plot(run.dir, probe, t, data["rho0"], data["g"], png)
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
