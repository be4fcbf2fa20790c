"""Buchner (2002): the wall pressure of a 2D dam break at sensors P1 and P2, each wall treatment.

Runs ``cases/dam_break_buchner`` as shipped (H = 0.6 m, dx = H/40, 3,200 particles, to
t sqrt(g/H) = 6.5) with the probes plugin alone for output, with the reflective walls,
reflective walls + the wall model (``wall_integral``) and ghost particles + reflective
walls. The figures are the probes plugin's (``sphcore_plugins.probes.figures``): MAE of
p / (rho g H) over t sqrt(g/H) in [2.6, 5.5], its offset (median difference) and noise,
and the first rise (p / (rho g H) reaching 0.1) against the experiment's.
"""

from __future__ import annotations

from pathlib import Path

from _common import cost, num, status, table
from _wall_pressure import plot_probe, run_all

NAME = "dam_break_buchner"
TITLE = "2D dam break, wall pressure at P1 and P2 vs Buchner (2002)"
CASE = "dam_break_buchner"


def build(runs: Path, figures: Path, rerun: bool) -> str:
    results = run_all(CASE, runs, rerun)
    for probe in ("P1", "P2"):
        if any(data is not None for _, data in results.values()):
            plot_probe(results, probe, figures, f"{NAME}_{probe}.png",
                       f"Buchner (2002) dam break, sensor {probe}, H = 0.6 m, dx = H/40")
    rows = []
    for label, (s, _) in results.items():
        p = s.get("probes", {})
        rows.append([label, status(s), num(p.get("probe_P1_mae_rhogH")), f"{p.get('probe_P1_offset_rhogH', float('nan')):+.3f}",
                     num(p.get("probe_P1_noise_rhogH")), f"{p.get('probe_P1_rise_dtau', float('nan')):+.3f}",
                     num(p.get("probe_P2_mae_rhogH")), f"{p.get('probe_P2_offset_rhogH', float('nan')):+.3f}",
                     *cost(s)])
    return table(["walls", "status", "P1 MAE", "P1 offset", "P1 noise", "P1 first rise - exp.", "P2 MAE",
                  "P2 offset", "wall s", "particle-steps/s"], rows)
