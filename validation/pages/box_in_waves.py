"""A box moved by waves: SPHERIC test 12 (Hadzic et al. 2005) at two resolutions.

Runs ``cases/box_in_waves`` (a 2D box 0.1 m x 0.05 m of relative density 0.68, free in sway,
heave and roll, in a flume with 0.4 m of water; a flap hinged at the floor follows its
measured angle) at dx = 0.005 m (shipped) and dx = 0.01 m (``--set``). It compares the two
wave gauges and the box's three motions with the measured series of the experiment
(``cases/box_in_waves/reference``), each over the time the experiment gives it.

Definitions. A gauge's elevation is the depth probe's water depth less the still depth,
0.4 m. Heave and sway are the displacements of the box's centre of mass, roll its turn in
degrees, anticlockwise with x down the flume and y up (the data set does not say which
sense its roll counts: a correlation near -1 would say the other). The measured motions
start at about 0 at 6.3 s, when the group reaches the box, from a rest position the data
do not give; each computed motion is therefore shifted to equal the record's first value
at the record's first time (the box has by then drifted with the group's first waves and
settled at its own draft; the offset of that draft is reported separately). For each
series: the measured and computed ranges (max - min over the window), the root-mean-square
of their difference over the window divided by the measured root-mean-square, and the lag
of the computed series behind the measured one that maximises their correlation (searched
within +-0.3 s). The gauges are also given by linear theory from the flap's record
(``postprocessing/wave_theory.py``: the flap's transfer function and the dispersion of
each Fourier component), which checks the record, its sense and the gauges' places
independently of the runs.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from _common import CASES, pyplot, run_case, save, status, table, toolkit

NAME = "box_in_waves"
TITLE = "A box moved by waves: SPHERIC test 12 against Hadzic et al. (2005)"
DEPTH = 0.4  # m: still water
REFERENCE = CASES / "box_in_waves" / "reference"
SERIES = {  # name -> (label, unit, factor from SI to the unit shown)
    "N1": ("gauge N1 (x = 1.16 m)", "mm", 1e3),
    "N2": ("gauge N2 (x = 2.66 m)", "mm", 1e3),
    "heave": ("heave", "mm", 1e3),
    "sway": ("sway", "mm", 1e3),
    "roll": ("roll", "deg", 1.0),
}
GAUGES = {"N1": 1.16, "N2": 2.66}  # m from the flap's hinge
T_END = 8.5  # s: the case's t_end (the gauges' records go on to 10 s, the flap's to 8.6 s)
CALM_END = 4.0  # s: the box is still before this (the group's first waves reach it later)
RELEASE_PAD = 0.1  # s after the release: the box's first settling left out of the draft's mean
MAX_LAG = 0.3  # s: the lags searched
LAG_STEP = 0.002  # s


def plan(runs: Path) -> list[dict]:
    """The two resolutions, the coarse one first."""
    return [
        {"label": "dx = 0.01 m", "sets": ["particles.dx=0.01"], "out": runs / "dx0.01"},
        {"label": "dx = 0.005 m (shipped)", "sets": [], "out": runs / "dx0.005"},
    ]


def measured(name: str) -> tuple[np.ndarray, np.ndarray]:
    """The experiment's series ``name`` (times in s, values in SI units; roll in degrees) up
    to T_END, in the order tabulated: a few times repeat (three significant digits), kept."""
    d = np.loadtxt(REFERENCE / f"hadzic_2005_{name}.txt", comments="#", ndmin=2)
    d = d[d[:, 0] <= T_END]
    return d[:, 0], d[:, 1]


def linear_theory() -> dict:
    """The gauges' elevation by linear theory from the flap's recorded angle (positive away
    from the water): stroke at the still-water level -DEPTH tan(angle)."""
    theory = toolkit("wave_theory")
    rec = np.loadtxt(CASES / "box_in_waves" / "flap.txt", comments="#", ndmin=2)
    t, stroke = rec[:, 0], -DEPTH * np.tan(np.radians(rec[:, 1]))
    stroke = stroke - stroke[0]
    return {name: (t, theory.recorded_elevation(t, stroke, DEPTH, x, theory.flap)) for name, x in GAUGES.items()}


def _body(out: Path):
    """The box's times, centre positions (n, 3) and rotation about z (rad) from the run's
    loads file."""
    import xarray as xr

    with xr.open_dataset(out / "wall_loads.nc") as w:
        b = [g.strip() for g in w.attrs["wall_groups"].split(";")].index("bodies[0]")
        return w["time"].values, w["position"].values[:, b, :], w["rotation"].values[:, b, 2]


def computed(out: Path) -> dict:
    """The run's gauges and the box's motion as time series (SI units; roll in degrees),
    the motions shifted to the record's first value at the record's first time."""
    import xarray as xr

    with xr.open_dataset(out / "probes.nc") as p:
        names = [n.decode() if isinstance(n, bytes) else str(n) for n in p["probe_name"].values]
        tp = p["time"].values
        depth = p["depth"].values
    tb, pos, angle = _body(out)
    series = {n: (tp, depth[:, i] - DEPTH) for i, n in enumerate(names)}
    motions = {"heave": pos[:, 1], "sway": pos[:, 0], "roll": np.degrees(angle)}
    for name, y in motions.items():
        te, ye = measured(name)
        series[name] = (tb, y - np.interp(te[0], tb, y) + ye[0])
    return series


def draft_offset(out: Path, release: float) -> tuple[float, float]:
    """The box's mean height less where it was drawn (at its Archimedes draft) and the
    spread of it, from the release to the waves' arrival (mm)."""
    t, pos, _ = _body(out)
    y = pos[:, 1]
    keep = (t >= release + RELEASE_PAD) & (t <= CALM_END)
    return 1e3 * float(np.mean(y[keep]) - y[0]), 1e3 * float(np.std(y[keep]))


def compare(te, ye, tc, yc) -> dict:
    """Ranges, the normalised RMS difference and the best lag of (tc, yc) against the
    measured (te, ye), over the measured times."""
    at = np.interp(te, tc, yc)
    rms = float(np.sqrt(np.mean((at - ye) ** 2)) / np.sqrt(np.mean(ye ** 2)))
    lags = np.arange(-MAX_LAG, MAX_LAG + 0.5 * LAG_STEP, LAG_STEP)
    a = ye - ye.mean()
    corr = []
    for lag in lags:
        c = np.interp(te + lag, tc, yc)
        c = c - c.mean()
        corr.append(float(np.dot(a, c) / (np.linalg.norm(a) * np.linalg.norm(c) + 1e-300)))
    best = int(np.argmax(corr))
    return {"range_exp": float(np.ptp(ye)), "range_sph": float(np.ptp(at)), "rms": rms, "lag": float(lags[best]),
            "corr": corr[best]}


def _plot(results: dict, theory: dict, figures: Path) -> None:
    plt = pyplot()
    fig, axes = plt.subplots(len(SERIES), 1, figsize=(8, 11))
    for ax, (name, (label, unit, f)) in zip(axes, SERIES.items()):
        te, ye = measured(name)
        pad = 0.5
        ax.plot(te, f * ye, "k.", ms=3, label="Hadzic et al. (2005), measured")
        if name in theory:
            tt, yt = theory[name]
            keep = (tt >= te[0] - 0.5) & (tt <= te[-1] + 0.5)
            ax.plot(tt[keep], f * yt[keep], color="0.6", lw=1.0, label="linear theory from the flap's record")
        for run_label, series in results.items():
            tc, yc = series[name]
            keep = (tc >= te[0] - pad) & (tc <= te[-1] + pad)
            ax.plot(tc[keep], f * yc[keep], lw=1.2, label=f"sphcore, {run_label}")
        ax.set_ylabel(f"{label} [{unit}]")
        ax.grid(alpha=0.3)
    axes[0].legend(fontsize=8)
    axes[2].legend(fontsize=8)
    axes[-1].set_xlabel("t [s]")
    fig.tight_layout()
    save(fig, figures, f"{NAME}.png")


def _row(label: str, name: str, series) -> list[str]:
    title, _, f = SERIES[name]
    te, ye = measured(name)
    c = compare(te, ye, *series)
    return [label, title, f"{te[0]:.2f}-{te[-1]:.2f}", f"{f * c['range_exp']:.1f}", f"{f * c['range_sph']:.1f}",
            f"{c['range_sph'] / c['range_exp']:.2f}", f"{c['rms']:.2f}", f"{c['lag']:+.3f}", f"{c['corr']:.2f}"]


def build(runs: Path, figures: Path, rerun: bool) -> str:
    results, costs = {}, []
    theory = linear_theory()
    rows = [_row("linear theory", name, theory[name]) for name in GAUGES]
    for spec in plan(runs):
        s = run_case("box_in_waves", spec["out"], spec["sets"], rerun=rerun)
        release = float(s["config"]["bodies"][0]["release"])
        offset = draft_offset(spec["out"], release) if s["status"] == "completed" else (float("nan"),) * 2
        costs.append([spec["label"], status(s), str(s["n_particles"]), f"{offset[0]:+.2f} ({offset[1]:.2f})",
                      f"{s['wall_time_s']:.0f}", f"{s['particle_steps_per_s']:.3g}"])
        if s["status"] != "completed":
            continue
        series = computed(spec["out"])
        results[spec["label"]] = series
        rows += [_row(spec["label"], name, series[name]) for name in SERIES]
    _plot(results, theory, figures)
    offset_head = (f"box height less its drawn draft, {RELEASE_PAD:g} s after the release to {CALM_END:g} s: "
                   "mean (spread) [mm]")
    md = [table(["run", "status", "particles", offset_head, "wall time [s]", "particle-steps/s"], costs),
          "\n",
          table(["run", "series", "window [s]", "measured range", "computed range", "ratio",
                 "RMS difference / measured RMS", "lag of the best fit [s]", "correlation at that lag"], rows)]
    return "".join(md)
