"""The tank at rest: does the water stay still, and is its pressure hydrostatic? Each wall treatment.

Runs ``cases/hydrostatic_tank`` as shipped (1 m of water in a 1 m wide tank, dx = 0.02 m,
2,500 particles, 5 s) with the pressure gauge and one netCDF frame at the end, with the
case's modified pressure (the seed paper's formulation: the Tait pressure minus its
hydrostatic part, so that the water is at rest from the first step) and with the plain
Tait equation of state (``physics.modified_pressure=false``), each with the reflective walls,
reflective walls + the wall model (``wall_integral``) and ghost particles + reflective walls.
The figures are the ``pressure_gauge`` plugin's: particles lost, the largest displacement
of a particle from its start (in dx, all particles and below the top two layers), the
drift of the free surface, and the worst relative error of a layer's mean pressure
against rho0 g (H - y) below the top two layers; the plot is ``postprocessing/pressure_profile.py``'s
layer profile of the last frame.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from _common import TREATMENTS, cost, num, pct, plugins_set, pyplot, run_case, save, status, table, toolkit

NAME = "hydrostatic_tank"
TITLE = "Tank at rest: layer pressures vs rho g (H - y), displacement, particles lost"
CASE = "hydrostatic_tank"
T_END = 5.0
FORMULATIONS = {"modified pressure": "true", "plain Tait": "false"}


def _profile(out: Path, s: dict):
    """(y, relative error of the layer's mean pressure) of the run's last frame."""
    pp, runs = toolkit("pressure_profile"), toolkit("runs")
    run = runs.open_run(out, "tank_at_rest")
    frame = None
    for frame in run.frames():
        pass
    t, pos, f = frame
    _, hi = run.block_extent(run.first_block())
    prof, dx = pp.layer_profile(pos, f["pressure"], f["radius"], hi[1], float(run.config["fluid"]["rho0"]))
    return prof[:, 0], prof[:, 5], hi[1], dx


def build(runs: Path, figures: Path, rerun: bool) -> str:
    rows, profiles = [], {}
    for form, mp in FORMULATIONS.items():
        for label, plugins in TREATMENTS.items():
            out = runs / f"{'modified' if mp == 'true' else 'tait'}_{'_'.join(plugins)}"
            s = run_case(CASE, out, [plugins_set(plugins + ["pressure_gauge", "netcdf"]),
                                     f"physics.modified_pressure={mp}", f"netcdf.every_dt={T_END}"],
                         t_end=T_END, rerun=rerun)
            g = s.get("pressure_gauge", {})
            dx = s["config"]["particles"]["dx"] if "config" in s else 0.02
            if s["status"] == "completed":
                profiles[(form, label)] = _profile(out, s)
            rows.append([form, label, status(s), str(g.get("particles_lost", "-")),
                         num(g.get("max_displacement_m", float("nan")) / dx),
                         num(g.get("max_displacement_below_top_m", float("nan")) / dx),
                         num(g.get("surface_drift_m")), pct(g.get("pressure_max_layer_err"), signed=False),
                         *cost(s)])
    _plot(profiles, figures)
    return table(["pressure", "walls", "status", "particles lost", "largest displacement (dx)",
                  "below the top two layers (dx)", "surface drift (m)", "worst layer pressure error", "wall s",
                  "particle-steps/s"], rows)


def _plot(profiles: dict, figures: Path):
    plt = pyplot()
    fig, axes = plt.subplots(1, 2, figsize=(8, 4.2), sharey=True)
    for ax, form in zip(axes, FORMULATIONS):
        for i, label in enumerate(TREATMENTS):
            if (form, label) in profiles:
                y, err, H, dx = profiles[(form, label)]
                keep = y < H - 2 * dx  # the top two layers: the criterion leaves them out
                ax.plot(100 * err[keep], y[keep], "o-", ms=2.5, lw=0.8, color=f"C{i}", label=label)
        ax.axvline(0.0, color="k", lw=0.8)
        worst = max((float(np.nanmax(np.abs(profiles[(form, lb)][1]))) for lb in TREATMENTS if (form, lb) in profiles),
                    default=0.0)
        if worst < 1e-6:  # round-off: a scale of its own would only show the noise of the last digit
            ax.set_xlim(-1.0, 1.0)
            ax.text(0.05, 0.02, f"every layer within {100 * worst:.0e} %", transform=ax.transAxes, fontsize=8)
        ax.set_title(f"{form}, t = {T_END:g} s", fontsize=9)
        ax.set_xlabel("layer mean pressure error vs rho0 g (H - y) (%)")
        ax.grid(alpha=0.3)
    axes[0].set_ylabel("y (m)")
    axes[1].legend(fontsize=8, loc="upper right")
    fig.tight_layout()
    save(fig, figures, f"{NAME}_layers.png")
