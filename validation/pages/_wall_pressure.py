"""The 2D dam breaks with wall-pressure sensors (Buchner 2002, Lobovsky et al. 2014): each
case run with each boundary treatment, its probes read back and plotted against the
experiment in the experiment's scaling, p / (rho g H) against t sqrt(g/H).

The error figures are the ``probes`` plugin's, in the run's summary.json
(:mod:`sphcore_plugins.probes.figures` defines them: MAE, band fraction, offset, noise,
first rise), the same numbers ``postprocessing/probes.py RUN`` prints.
"""

from __future__ import annotations

import math
from pathlib import Path

from _common import TREATMENTS, plugins_set, pyplot, run_case, save, toolkit


def run_all(case: str, runs: Path, rerun: bool) -> dict:
    """label -> (summary, probes) for each boundary treatment, the case's probes only for output;
    probes is None for a run that did not complete."""
    out = {}
    for label, plugins in TREATMENTS.items():
        d = runs / "_".join(plugins)
        s = run_case(case, d, [plugins_set(plugins + ["probes"])], rerun=rerun)
        out[label] = (s, toolkit("runs").open_run(d).probes() if s["status"] == "completed" else None)
    return out


def plot_probe(results: dict, name: str, figures: Path, png: str, title: str) -> None:
    """The probe ``name`` of every run (one panel per treatment) against its experiment."""
    from sphcore_plugins.gauges import reference

    plt = pyplot()
    done = [(label, data) for label, (_, data) in results.items() if data is not None]
    fig, axes = plt.subplots(len(done), 1, figsize=(7, 2.3 * len(done) + 0.6), sharex=True, squeeze=False)
    for ax, (label, data) in zip(axes[:, 0], done):
        probe = next(p for p in data["probes"] if p["name"] == name)
        ref, height = probe["reference"], probe["H"]
        series, exp = reference.SERIES[ref], reference.series(ref)
        if series.kind == "lobovsky":
            ax.fill_between(exp[:, 0], exp[:, 1], exp[:, 3], color="0.8", label=series.label)
            ax.plot(exp[:, 0], exp[:, 2], "k-", lw=0.8, label="experiment, median")
        else:
            ax.plot(exp[:, 0], exp[:, 1], "ko", ms=2.5, mfc="none", label=series.label)
        tau = data["t"] * math.sqrt(data["g"] / height)
        ax.plot(tau, probe["values"] / (data["rho0"] * data["g"] * height), "-", lw=0.8, color="C0",
                label=f"sphcore, {label}")
        top = 1.5 * max(float(exp[:, -1].max()), 0.1)
        ax.set_ylim(-0.1 * top, top)  # an impact's acoustic spikes would flatten the rest
        ax.set_xlim(0, max(float(exp[-1, 0]), float(tau[-1])))
        ax.set_ylabel("p / (rho g H)")
        ax.grid(alpha=0.3)
        ax.legend(fontsize=7, loc="upper left")
    axes[-1, 0].set_xlabel("t sqrt(g/H)")
    axes[0, 0].set_title(title, fontsize=9)
    fig.tight_layout()
    save(fig, figures, png)
