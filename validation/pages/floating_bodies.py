"""Floating bodies: a 2D box's equilibrium against Archimedes and its free heave decay
against linear potential flow, at two resolutions.

Runs ``cases/heave_decay`` (a box 0.2 m x 0.1 m of density 500 in a 3 m tank with 0.3 m of
water, released 5 mm above its draft; dx = 0.005 m, and dx = 0.01 m with ``--set``),
``cases/floating_box`` (the same box in a 1 m tank, dx = 0.01 m) to t = 10 s, about eleven
heave periods, ``cases/floating_box_3d`` (a box 0.6 m x 0.6 m x 0.4 m of density 500, free in
every degree of freedom, dx = 0.025 m) to t = 12.3 s, ten heave periods, and ``cases/heeled_box`` (a square heeled 5 deg: density 150, GM > 0, and
density 500, GM < 0, drawn at its own draft). The figures are ``postprocessing/body_motion.py``'s (extrema of the box's
height) against the equilibrium Archimedes gives the discrete water volume, and against
``postprocessing/heave_theory.py``'s free decay (the radiation coefficients of the
rectangle in this depth, linear potential flow).
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from _common import pyplot, run_case, save, status, table, toolkit

NAME = "floating_bodies"
TITLE = "Floating bodies: Archimedes and the free heave decay of a 2D box against potential flow"
RHO, G = 1000.0, 9.81
BEAM, HEIGHT, DENSITY = 0.2, 0.1, 500.0
DRAFT = DENSITY / RHO * HEIGHT  # Archimedes: half the height at density 500
DEPTH = 0.3  # m of water in both tanks
RELEASE = 0.5  # s: both cases hold the box until then
LONG_WAVE_RETURN = 1.6  # s after the release: the release's long waves back from the walls of the 3 m tank
ARCHIMEDES_T_END = 10.0  # s: cases/floating_box, about eleven heave periods
HEEL = 5.0  # deg: cases/heeled_box is drawn heeled by this much (orientation)
CAPSIZE = ["bodies[0].density=500", "domain.walls[0].min=[0.65, 0.2]", "domain.walls[0].max=[0.85, 0.4]"]
WINDOW = 2.0  # s: the Archimedes run's means are taken over windows this long
RIPPLE = 0.02  # of z0: swings of the box's height smaller than this are ripples, not extrema of the decay


def plan(runs: Path) -> list[dict]:
    """Every run of the page, the short ones first."""
    return [
        {"group": "roll", "label": "density 150 (shipped)", "density": 150.0, "case": "heeled_box", "sets": [],
         "t_end": None, "out": runs / "heeled_box_150"},
        {"group": "roll", "label": "density 500", "density": 500.0, "case": "heeled_box", "sets": CAPSIZE,
         "t_end": None, "out": runs / "heeled_box_500"},
        {"group": "decay", "label": "dx = 0.01 m", "case": "heave_decay", "sets": ["particles.dx=0.01"],
         "t_end": None, "out": runs / "heave_decay_dx0.01"},
        {"group": "archimedes", "label": "2D box, dx = 0.01 m (shipped)", "case": "floating_box", "sets": [],
         "t_end": ARCHIMEDES_T_END, "out": runs / "floating_box_10s"},
        {"group": "decay", "label": "dx = 0.005 m (shipped)", "case": "heave_decay", "sets": [], "t_end": None,
         "out": runs / "heave_decay_dx0.005"},
        {"group": "archimedes", "label": "3D box, dx = 0.025 m (shipped)", "case": "floating_box_3d", "sets": [],
         "t_end": None, "out": runs / "floating_box_3d"},
    ]


ROLL_RELEASE = 0.3  # s: cases/heeled_box holds the square until then
SQUARE = 0.2  # m: its side


def metacentric_height(density: float) -> float:
    """GM = KB + BM - KG of the upright square (m): T/2 + B^2/(12 T) - H/2, T = density/rho H."""
    draft = density / RHO * SQUARE
    return 0.5 * draft + SQUARE ** 2 / (12.0 * draft) - 0.5 * SQUARE


def roll_period(density: float) -> float:
    """2 pi sqrt(I / (rho g V GM)), the square's own inertia about its centre (no added inertia)."""
    mass = density * SQUARE ** 2
    inertia = mass * 2.0 * SQUARE ** 2 / 12.0
    return 2.0 * np.pi * np.sqrt(inertia / (RHO * G * SQUARE * (density / RHO * SQUARE) * metacentric_height(density)))


def roll_figures(spec: dict, s: dict) -> dict | None:
    """The square's roll angle (rz, from its drawn 5 deg heel: the angle from upright is
    5 deg + rz) after the release: its extrema and the largest angle from upright."""
    if s["status"] not in ("completed", "unstable"):
        return None
    bm = toolkit("body_motion")
    cols = bm.read(spec["out"])
    t, rz = cols["t"], cols["bodies[0].rz"]
    heel = HEEL + np.degrees(rz)
    keep = t >= ROLL_RELEASE
    te, he = bm.extrema(t[keep], heel[keep], 0.2)
    te, he = np.r_[ROLL_RELEASE, te], np.r_[HEEL, he]
    return {"t": t, "heel": heel, "te": te, "he": he, "largest": float(np.max(np.abs(heel[keep]))),
            "final": float(np.mean(heel[t >= t[-1] - 0.5])),
            "period": 2.0 * float(np.mean(np.diff(te[:5]))) if len(te) >= 3 else float("nan")}


def equilibrium(s: dict) -> float:
    """The body's centre height at rest by Archimedes with the run's own water: the level
    eta that the particles' volume n dx^dim and the body's displaced volume give the tank,
    A eta = n dx^dim + A_wp T (A the tank's plan area, A_wp the box's, T its draft), less
    the draft, plus half the box's height. Gravity is along the last axis."""
    cfg = s["config"]
    dim = len(cfg["domain"]["min"])
    assert np.flatnonzero(cfg["physics"]["gravity"][:dim]).tolist() == [dim - 1], "gravity along the last axis"
    dx = float(cfg["particles"]["dx"])
    tank = np.subtract(cfg["domain"]["max"], cfg["domain"]["min"])
    box = np.subtract(cfg["domain"]["walls"][0]["max"], cfg["domain"]["walls"][0]["min"])
    height, draft = float(box[-1]), float(cfg["bodies"][0]["density"]) / RHO * float(box[-1])
    level = (s["n_particles"] * dx ** dim + np.prod(box[:-1]) * draft) / np.prod(tank[:-1])
    return float(level - draft + 0.5 * height)


def _series(out: Path):
    bm = toolkit("body_motion")
    cols = bm.read(out)
    return cols["t"], cols["bodies[0].y"], bm


def decay_figures(spec: dict, s: dict) -> dict | None:
    """The decay's extrema over [release, release + LONG_WAVE_RETURN], measured from the
    Archimedes equilibrium and divided by the release offset z0."""
    if s["status"] != "completed":
        return None
    t, y, bm = _series(spec["out"])
    eq = equilibrium(s)
    keep = (t >= RELEASE) & (t <= RELEASE + LONG_WAVE_RETURN)
    z0 = float(y[np.searchsorted(t, RELEASE)] - eq)
    te, ye = bm.extrema(t[keep], y[keep], RIPPLE * abs(z0))
    te, ye = np.r_[RELEASE, te], np.r_[eq + z0, ye]
    x = (ye - eq) / z0
    late = (t >= RELEASE + 0.5 * LONG_WAVE_RETURN) & (t <= RELEASE + LONG_WAVE_RETURN)
    return {"t": t - RELEASE, "x": (y - eq) / z0, "te": te - RELEASE, "xe": x, "z0": z0, "eq": eq,
            "offset": float(np.mean(y[late]) - eq), "dx": float(s["config"]["particles"]["dx"]),
            "period": 2.0 * float(np.mean(np.diff(te[:4]))) if len(te) >= 4 else float("nan"),
            "delta": float(np.log(abs(x[0]) / abs(x[2]))) if len(x) >= 3 else float("nan")}


def archimedes_figures(s: dict, out: Path) -> dict | None:
    """Means of the body's height over windows of WINDOW s after the release (the first
    window left out), against the Archimedes equilibrium; their slope (the drift); the
    largest horizontal displacement of its centre and the largest rotation after the
    release."""
    if s["status"] != "completed":
        return None
    dim = len(s["config"]["domain"]["min"])
    up = "yz"[dim - 2]
    cols = toolkit("body_motion").read(out)
    t, y = cols["t"], cols[f"bodies[0].{up}"]
    release = float(s["config"]["bodies"][0].get("release", 0.0))
    eq = equilibrium(s)
    starts = np.arange(release + WINDOW, float(t[-1]) - WINDOW + 1e-9, WINDOW)
    means = [float(np.mean(y[(t >= a) & (t < a + WINDOW)]) - eq) for a in starts]
    slope = float(np.polyfit(starts + 0.5 * WINDOW, means, 1)[0]) if len(means) > 1 else float("nan")
    after = t >= release
    across = np.stack([cols[f"bodies[0].{a}"] for a in "xy"[:dim - 1]], axis=1)
    shift = float(np.max(np.linalg.norm(across[after] - across[after][0], axis=1)))
    turns = np.stack([cols[f"bodies[0].r{a}"] for a in ("xyz" if dim == 3 else "z")], axis=1)
    turn = float(np.max(np.linalg.norm(turns[after] - turns[after][0], axis=1)))
    return {"starts": starts, "means": means, "slope": slope, "dx": float(s["config"]["particles"]["dx"]),
            "t": t, "y": y - eq, "up": up, "shift": shift, "turn": turn, "dim": dim}


def theory(t_end: float) -> dict:
    """The linear free decay of this box in this depth (postprocessing/heave_theory.py),
    its extrema counted from the release as the runs' are."""
    ht = toolkit("heave_theory")
    mass = DENSITY * BEAM * HEIGHT
    nat = ht.natural_period(mass, BEAM, DRAFT, DEPTH, RHO, G)
    d = ht.free_decay(mass, BEAM, DRAFT, DEPTH, np.linspace(0.0, t_end, 1001), RHO, G)
    te, xe = np.r_[0.0, d["t_extrema"]], np.r_[1.0, d["x_extrema"]]
    return {"t": d["t"], "x": d["x"], "te": te, "xe": xe, "natural": nat,
            "period": 2.0 * float(np.mean(np.diff(te[:4]))), "delta": float(np.log(1.0 / abs(xe[2])))}


def _plot(decays: dict, pf: dict, figures: Path) -> None:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.6))
    ax.plot(pf["t"], pf["x"], "k-", lw=1.2, label="linear potential flow")
    for (label, m), colour in zip(decays.items(), ("C3", "C0")):
        if m is not None:
            ax.plot(m["t"], m["x"], "-", color=colour, lw=0.9, label=f"sphcore, {label}")
    ax.axvline(LONG_WAVE_RETURN, color="0.6", ls=":", lw=0.8)
    ax.text(LONG_WAVE_RETURN + 0.02, 0.8, "long waves back\nfrom the walls", fontsize=7, color="0.4")
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.set_xlim(0.0, 2.5)
    ax.set_xlabel("t after the release [s]")
    ax.set_ylabel("(y - y_eq) / z0")
    ax.legend(fontsize=8)
    fig.tight_layout()
    save(fig, figures, f"{NAME}_heave_decay.png")


def _plot_archimedes(arch: list, figures: Path) -> None:
    plt = pyplot()
    shown = [(label, m) for label, _, m in arch if m is not None]
    fig, axes = plt.subplots(len(shown), 1, figsize=(7, 2.6 * len(shown)), squeeze=False)
    for ax, (label, m) in zip(axes[:, 0], shown):
        ax.plot(m["t"], 1e3 * m["y"], "-", lw=0.8, label=f"{label}: centre - Archimedes equilibrium")
        ax.plot(m["starts"] + 0.5 * WINDOW, 1e3 * np.asarray(m["means"]), "ks", ms=4, label=f"{WINDOW:g} s means")
        for s in (-0.5, 0.5):
            ax.axhline(1e3 * s * m["dx"], color="0.6", ls="--", lw=0.7)
        ax.set_xlabel("t [s]")
        ax.set_ylabel(f"{m['up']} [mm]")
        ax.legend(fontsize=8)
    fig.tight_layout()
    save(fig, figures, f"{NAME}_archimedes.png")


def _plot_rolls(rolls: dict, figures: Path) -> None:
    plt = pyplot()
    fig, ax = plt.subplots(figsize=(7, 3.2))
    for (label, (spec, _, m)), colour in zip(rolls.items(), ("C0", "C3")):
        if m is not None:
            gm = metacentric_height(spec["density"])
            ax.plot(m["t"], m["heel"], "-", color=colour, lw=0.9, label=f"{label}, GM = {1e3 * gm:+.0f} mm")
    ax.axhline(0.0, color="0.6", lw=0.6)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("heel from upright [deg]")
    ax.legend(fontsize=8)
    fig.tight_layout()
    save(fig, figures, f"{NAME}_roll.png")


def build(runs: Path, figures: Path, rerun: bool) -> str:
    decays, summaries, arch, rolls = {}, {}, [], {}
    for spec in plan(runs):
        s = run_case(spec["case"], spec["out"], spec["sets"], t_end=spec["t_end"], rerun=rerun)
        summaries[spec["label"]] = s
        if spec["group"] == "decay":
            decays[spec["label"]] = decay_figures(spec, s)
        elif spec["group"] == "roll":
            rolls[spec["label"]] = (spec, s, roll_figures(spec, s))
        else:
            arch.append((spec["label"], s, archimedes_figures(s, spec["out"])))
    pf = theory(2.5)
    _plot(decays, pf, figures)
    nat = pf["natural"]
    rows = [["linear potential flow", "", "", f"{pf['period']:.3f}", f"{pf['delta']:.2f}",
             *[f"{t:.3f} / {x:+.3f}" for t, x in zip(pf["te"][1:4], pf["xe"][1:4])], "", ""]]
    for label, m in decays.items():
        s = summaries[label]
        if m is None:
            rows.append([label, status(s)] + ["-"] * 7 + [f"{s['wall_time_s']:.0f}"])
            continue
        rows.append([label, f"{DRAFT / m['dx']:.0f}", f"{1e3 * m['offset']:+.2f} ({m['offset'] / m['dx']:+.2f} dx)",
                     f"{m['period']:.3f}", f"{m['delta']:.2f}",
                     *[f"{t:.3f} / {x:+.3f}" for t, x in zip(m["te"][1:4], m["xe"][1:4])],
                     f"{s['n_particles']}", f"{s['wall_time_s']:.0f}"])
    md = [(f"### Free heave decay, `heave_decay` (z0 = 5 mm; potential flow: natural period "
           f"{nat['period']:.3f} s, C33 = {nat['C33']:.3f}, b' = {nat['b_vugts']:.3f}, small-damping decrement "
           f"{nat['delta']:.2f})\n"),
          table(["run", "particles over the draft", "mean offset from Archimedes, last 0.8 s of the window [mm]",
                 "period [s]", "log decrement, first cycle", "1st extremum: t [s] / x", "2nd", "3rd",
                 "particles", "wall time [s]"], rows)]
    if arch:
        _plot_archimedes(arch, figures)
        md.append(f"\n### Archimedes ({WINDOW:g} s means of the body's height less the Archimedes equilibrium, "
                  "after the release)\n")
        rows = []
        for label, s, m in arch:
            if m is None:
                rows.append([label, status(s)] + ["-"] * 6)
                continue
            span = f"{m['starts'][0]:.1f}-{m['starts'][-1] + WINDOW:.1f}"
            rows.append([label, span, ", ".join(f"{1e3 * v:+.2f}" for v in m["means"]),
                         f"{max(map(abs, m['means'])) / m['dx']:.3f}",
                         f"{1e3 * m['slope']:+.3f}", f"{1e3 * m['shift']:.3f}", f"{np.degrees(m['turn']):.4f}",
                         f"{s['n_particles']:,}, {s['steps']} steps, {s['wall_time_s']:.0f} s"])
        md.append(table(["run", "from-to [s]", "means [mm]", "largest mean / dx (absolute)", "drift of the means [mm/s]",
                         "largest horizontal shift [mm]", "largest rotation [deg]", "particles, steps, wall time"],
                        rows))
    if rolls:
        _plot_rolls(rolls, figures)
        rows = []
        for label, (spec, s, m) in rolls.items():
            gm, d = metacentric_height(spec["density"]), spec["density"]
            theory_t = f"{roll_period(d):.3f}" if gm > 0 else "- (capsizes)"
            if m is None:
                rows.append([label, f"{1e3 * gm:+.1f}", theory_t, status(s), "-", "-", "-", "-"])
                continue
            rows.append([label, f"{1e3 * gm:+.1f}", theory_t, status(s), f"{m['period']:.3f}" if gm > 0 else "-",
                         f"{m['largest']:.1f}", f"{m['final']:.1f}", f"{s['wall_time_s']:.0f}"])
        md += [(f"\n### Roll stability, `heeled_box` (square {SQUARE:g} m, heeled {HEEL:g} deg, released at "
                f"{ROLL_RELEASE:g} s)\n"),
               table(["run", "GM [mm]", "roll period from GM [s]", "run", "roll period [s]",
                      "largest heel [deg]", "heel over the last 0.5 s [deg]", "wall time [s]"], rows)]
    return "\n".join(md)
