"""The seed paper's dam break: the surge front against Cruchaga et al. (2007) and Martin &
Moyce (1952), and the residual column at the back wall against Martin & Moyce, each wall treatment.

Runs ``cases/dam_break`` as shipped (a 0.114 x 0.228 m column, dx = 0.114 m / 36, 2,592
particles, 0.3 s) with the front gauge alone for output, with the reflective walls,
reflective walls + the wall model (``wall_integral``) and ghost particles + reflective walls,
and the seed paper's own variant: reflective walls with explicit Euler at dt = 1e-5 s, the
free surface held at p = 0, the corrected kernel gradient and the reflected velocity taken
at the end point. The figures are the ``front_gauge`` plugin's
(:mod:`sphcore_plugins.gauges.front` defines the front: the tip of the chain of particles
within two spacings of the floor, centres at most two spacings apart, plus its radius; and
the residual height: the depth one spacing from the back wall).
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from _common import TREATMENTS, cost, num, pct, plugins_set, pyplot, run_case, save, status, table

NAME = "dam_break"
TITLE = "The seed paper's 2D dam break: front vs Cruchaga et al. (2007) and Martin & Moyce (1952)"
CASE = "dam_break"
PAPER = "reflective, the seed paper's scheme"
PAPER_SETS = [plugins_set(["reflective", "free_surface", "front_gauge"]), 'integrator.scheme="euler"', "time.dt=1e-5",
              'reflective.velocity="end"', "corrections.kernel_gradient=true"]
G = 9.81


def build(runs: Path, figures: Path, rerun: bool) -> str:
    variants = {label: [plugins_set(plugins + ["front_gauge"])] for label, plugins in TREATMENTS.items()}
    variants[PAPER] = PAPER_SETS
    results = {}
    for k, (label, sets) in enumerate(variants.items()):
        out = runs / ("paper" if label == PAPER else "_".join(TREATMENTS[label]))
        s = run_case(CASE, out, sets, rerun=rerun)
        front = np.loadtxt(out / "front.csv", delimiter=",", skiprows=1, ndmin=2) if (out / "front.csv").exists() \
            else None
        results[label] = (s, front)
    _plot(results, figures)
    rows = []
    for label, (s, _) in results.items():
        f = s.get("front_gauge", {})
        rows.append([label, status(s), f"{num(f.get('x_front_0.10s_m'))} ({pct(f.get('err_cruchaga_0.10s'))})",
                     f"{num(f.get('x_front_0.20s_m'))} ({pct(f.get('err_cruchaga_0.20s'))})",
                     pct(f.get("rms_rel_err_martin_moyce_T3"), signed=False),
                     pct(f.get("rms_rel_err_martin_moyce_height"), signed=False), *cost(s)])
    from sphcore_plugins.gauges import reference

    cr = reference.cruchaga()
    md = (f"Cruchaga et al. (2007): x_front = {cr[0, 1]:.3g} m at {cr[0, 0]:.2g} s and {cr[1, 1]:.3g} m at "
          f"{cr[1, 0]:.2g} s.\n\n")
    return md + table(["walls", "status", "x_front at 0.1 s, m (vs Cruchaga)", "x_front at 0.2 s, m (vs Cruchaga)",
                       "front RMS vs Martin & Moyce (T <= 3)", "back-wall height RMS vs Martin & Moyce", "wall s",
                       "particle-steps/s"], rows)


def _plot(results: dict, figures: Path):
    from sphcore_plugins.gauges import reference

    a = 0.114
    plt = pyplot()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(9, 3.8))
    mm, cr, mmh = reference.martin_moyce(), reference.cruchaga(), reference.martin_moyce_height()
    ax.plot(mm[:, 0], mm[:, 1], "ks", ms=4, mfc="none", label="Martin & Moyce 1952")
    ax.plot(cr[:, 0] * math.sqrt(2 * G / a), cr[:, 1] / a, "k^", ms=6, label="Cruchaga et al. 2007")
    bx.plot(mmh[:, 0], mmh[:, 1], "ks", ms=4, mfc="none", label="Martin & Moyce 1952")
    for i, (label, (_, front)) in enumerate(results.items()):
        if front is None:
            continue
        ax.plot(front[:, 0] * math.sqrt(2 * G / a), front[:, 1] / a, "-", lw=1, color=f"C{i}", label=label)
        if front.shape[1] > 2:
            bx.plot(front[:, 0] * math.sqrt(G / a), front[:, 2] / (2 * a), "-", lw=1, color=f"C{i}", label=label)
    ax.set_xlabel("T = t sqrt(2g/a)")
    ax.set_ylabel("Z = x_front / a")
    ax.set_xlim(0, 3.5)
    bx.set_xlim(0, 3.5)
    ax.set_ylim(1, 4)
    bx.set_xlabel("tau = t sqrt(g/a)")
    bx.set_ylabel("H = eta / (2a) at the back wall")
    for x in (ax, bx):
        x.grid(alpha=0.3)
    ax.legend(fontsize=7)
    fig.tight_layout()
    save(fig, figures, f"{NAME}_front.png")
