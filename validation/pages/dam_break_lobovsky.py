"""Lobovsky et al. (2014): the wall pressure of a 2D dam break at sensor 2, each wall treatment.

Runs ``cases/dam_break_lobovsky`` as shipped (H = 0.3 m, dx = H/40, 3,200 particles, to
t / sqrt(H/g) = 7.5) with the probes plugin alone for output, with the reflective walls,
reflective walls + the wall model (``wall_integral``) and ghost particles + reflective
walls. The figures are the probes plugin's (``sphcore_plugins.probes.figures``): the
fraction of the run's samples with t / sqrt(H/g) in [2, 7] inside the experiment's
2.5-97.5 % band, the offset from the band's median, the noise, and the peak against the
band's peak range.
"""

from __future__ import annotations

from pathlib import Path

from _common import cost, num, pct, status, table
from _wall_pressure import plot_probe, run_all

NAME = "dam_break_lobovsky"
TITLE = "2D dam break, wall pressure at sensor 2 vs Lobovsky et al. (2014)"
CASE = "dam_break_lobovsky"


def build(runs: Path, figures: Path, rerun: bool) -> str:
    results = run_all(CASE, runs, rerun)
    if any(data is not None for _, data in results.values()):
        plot_probe(results, "sensor2", figures, f"{NAME}_sensor2.png",
                   "Lobovsky et al. (2014) dam break, sensor 2 (15 mm above the floor), H = 0.3 m, dx = H/40")
    rows = []
    for label, (s, _) in results.items():
        p = s.get("probes", {})
        band = f"{num(p.get('probe_sensor2_band_peak_lo_rhogH'))}-{num(p.get('probe_sensor2_band_peak_hi_rhogH'))}"
        rows.append([label, status(s), pct(p.get("probe_sensor2_in_band_fraction"), signed=False),
                     f"{p.get('probe_sensor2_offset_rhogH', float('nan')):+.3f}",
                     num(p.get("probe_sensor2_noise_rhogH")), num(p.get("probe_sensor2_peak_rhogH")), band,
                     *cost(s)])
    return table(["walls", "status", "in band", "offset", "noise", "peak (rho g H)", "experiment's peak range",
                  "wall s", "particle-steps/s"], rows)
