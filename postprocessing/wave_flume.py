"""Wave flume: the wave height a piston wave maker makes, against Biesel's transfer function.

Reads   RUN/summary.json (the case: water depth, flume length, the piston's sine_translation
        and the depth gauges), RUN/probes.nc (the depth gauges, from the probes plugin) and,
        if present, RUN/wall_loads.csv (the force on the piston, from the wall_loads plugin).
Writes  RUN/wave_flume.png: the free-surface elevation at every gauge with its measuring
        window shaded, and H/S against kh with Biesel's curve (every RUN given on one plot).

The piston is the first ``[[domain.planes]]`` (or else ``[[domain.walls]]``) entry whose
motion has a ``sine_translation`` part: its stroke S is twice the amplitude, its period T
gives omega = 2 pi / T, and k solves the linear dispersion relation omega^2 = g k tanh(k h) (h the depth of still water,
the first fluid block's top above the floor). Biesel's first-order transfer function of a
piston (Biesel & Suquet 1951; Dean & Dalrymple, Water Wave Mechanics for Engineers and
Scientists, ch. 6) is

    H / S = 2 (cosh 2kh - 1) / (sinh 2kh + 2kh)        (-> kh in shallow water, -> 2 in deep)

(a flap hinged at the floor: its own transfer function). The linear theory, these transfer
functions and Havelock's force, lives in the sibling module wave_theory.py.

Each gauge at a distance x from the piston's face at rest is measured in the window

    t0 = ramp_start + ramp + x / cg + margin T       (the fully ramped waves have arrived)
    t1 = ramp_start + (2 L - x) / cg                  (the first waves reflected from the far wall,
                                                       L the face's distance from it, return)

(cg the linear group velocity, t1 also no later than the last sample). The wave height is
the mean over the whole waves in the window (zero up-crossing to zero up-crossing of the
elevation less its mean over the window) of crest minus trough (a ripple on the surface
adds to it); H1 (columns H1/S) is twice the amplitude of a sine at omega fitted to the
whole window by least squares, a check that uses every sample (it reads low where the
amplitude varies across the window). The script prints the window, the number of waves,
H, H/S measured and Biesel's and the relative error per gauge, the decay of H along the
flume (an exponential fitted over the gauges, with its value extrapolated back to the
piston: a diagnostic of the damping on the way, not theory), and, with wall_loads.csv, the
horizontal force on the piston (N/m in 2D) in the window of a gauge at x = 0 (the ramp's end
to the far wall's reflection's return or the run's end): its mean and the amplitude and
phase against the displacement of its first harmonic (a least-squares fit at omega; the
mean, the still water's force, drops out), over the window and over each whole period in
it, beside Havelock's linear force (havelock: radiation damping and added mass) and the
relative difference. A path that is not a run of a piston flume: one line on stderr, exit
status 2.

    python postprocessing/wave_flume.py cases/wave_flume/output
    python postprocessing/wave_flume.py cases/wave_flume/output cases/wave_flume_kh18/output
"""

from __future__ import annotations

import argparse
import itertools
import math
import sys
from pathlib import Path

import numpy as np
from runs import RunError, open_run, pyplot, refuse
from wave_theory import (biesel, evanescent_wavenumbers, flap, group_velocity, havelock,  # noqa: F401
                         recorded_elevation, wavenumber)

PROG = Path(__file__).name
PNG = "wave_flume.png"
WALL_LOADS_CSV = "wall_loads.csv"


# ---------------------------------------------------------------------------- the run's flume


def flume(run) -> dict:
    """The flume of a run's case: depth h, the piston (face x, stroke S, period T, ramp end),
    the far wall's x and the depth gauges' x. Raises RunError for anything else."""
    cfg = run.config
    if not cfg:
        raise RunError(f"{run.dir}: no summary.json (expected the output directory of a finished sph run)")
    dim = cfg.get("case", {}).get("dim")
    if dim != 2:
        raise RunError(f"{run.dir}: a {dim}D run (expected a 2D wave flume)")
    domain = cfg.get("domain", {})
    piston = None  # (key of the motion, the entry, its sine_translation or sine_rotation part)
    for kind in ("planes", "walls"):
        for k, entry in enumerate(domain.get(kind) or []):
            for part in entry.get("motion") or []:
                kinds = ("sine_translation", "sine_rotation") if kind == "planes" else ("sine_translation",)
                if part.get("type") in kinds and piston is None:
                    piston = (f"domain.{kind}[{k}]", entry, part)
    if piston is None:
        raise RunError(f"{run.dir}: no [[domain.planes]] or [[domain.walls]] entry moves with a sine_translation "
                       f"(expected a piston wave maker) or a plane with a sine_rotation (a flap)")
    key, wall, part = piston
    if part["type"] == "sine_rotation":
        return _flap(run, cfg, domain, key, wall, part)
    axis = np.asarray(part["axis"], float)
    axis = axis / np.linalg.norm(axis)
    if abs(axis[0]) < 0.999:
        raise RunError(f"{run.dir}: {key} moves along {part['axis']} (expected a piston moving along x)")
    period = part.get("period") or (1.0 / part["frequency"] if part.get("frequency") else None)
    if key.startswith("domain.planes"):
        if float(np.asarray(wall["normal"], float)[0]) <= 0.0 or abs(float(wall["normal"][1])) > 1e-12:
            raise RunError(f"{run.dir}: {key} has the normal {wall['normal']} (expected a piston facing +x)")
        face = float(wall["point"][0])
    elif wall.get("shape") == "box":
        face = float(wall["max"][0])
    elif wall.get("points"):
        face = float(max(p[0] for p in wall["points"]))
    else:
        raise RunError(f"{run.dir}: {key} is a {wall.get('shape')} (expected a box or a polygon piston)")
    floor, far = _floor_and_far(run, domain)
    h, gauges, g = _water(run, cfg, floor)
    return {"h": h, "face": face, "far": far,
            "S": 2.0 * abs(float(part["amplitude"])), "T": float(period), "g": g,
            "ramp_end": float(part.get("ramp_start", 0.0)) + float(part.get("ramp", 0.0)),
            "ramp_start": float(part.get("ramp_start", 0.0)), "gauges": gauges, "load": f"{key}.motion",
            # X(t) = S/2 sin(omega t + phase0) along +x (sphcore's sine_translation, t absolute)
            "phase0": math.radians(float(part.get("phase", 0.0))) + (math.pi if part["amplitude"] * axis[0] < 0
                                                                     else 0.0)}


def _water(run, cfg, floor) -> tuple[float, list, float]:
    """(still-water depth h above ``floor``, the depth gauges (name, x), g) of a run's case."""
    block = run.first_block()
    if not block:
        raise RunError(f"{run.dir}: no fluid block in the case")
    _, hi = run.block_extent(block)
    gauges = [(d["name"], float(d["point"][0])) for d in (cfg.get("probes") or {}).get("depth") or []]
    if not gauges:
        raise RunError(f"{run.dir}: the case has no [[probes.depth]] gauges")
    return hi[1] - floor, gauges, abs(float(cfg.get("physics", {}).get("gravity", [0.0, -9.81])[1]))


def _floor_and_far(run, domain) -> tuple[float, float]:
    """The floor's height and the far wall's x: the box's (domain.min, domain.max), else the
    fixed planes facing up and facing -x."""
    if domain.get("min") is not None and domain.get("max") is not None:
        return float(domain["min"][1]), float(domain["max"][0])
    floor = far = None
    for entry in domain.get("planes") or []:
        if entry.get("motion"):
            continue
        n = np.asarray(entry["normal"], float)
        n = n / np.linalg.norm(n)
        if n[1] > 0.999:
            floor = float(entry["point"][1])
        elif n[0] < -0.999:
            far = float(entry["point"][0])
    if floor is None or far is None:
        raise RunError(f"{run.dir}: no floor and far wall (expected domain.min/max or fixed planes facing up and -x)")
    return floor, far


def wave_heights(t, eta):
    """Crest-to-trough heights of the whole waves of ``eta`` (zero up-crossing to zero
    up-crossing of eta less its mean); [] if fewer than two up-crossings."""
    e = eta - eta.mean()
    up = np.flatnonzero((e[:-1] < 0.0) & (e[1:] >= 0.0)) + 1
    return [float(e[a:b].max() - e[a:b].min()) for a, b in itertools.pairwise(up)]


def first_harmonic(t, y, omega):
    """(mean, amplitude A, phase p) of the least-squares fit y ~ mean + A sin(omega t + p)."""
    basis = np.column_stack([np.ones_like(t), np.cos(omega * t), np.sin(omega * t)])
    coef = np.linalg.lstsq(basis, y, rcond=None)[0]
    return float(coef[0]), float(math.hypot(coef[1], coef[2])), float(math.atan2(coef[1], coef[2]))


def _flap(run, cfg, domain, key, wall, part) -> dict:
    """The flume of a flap: a plane facing +x turning about a hinge on the floor; its stroke
    at the still-water level S = 2 h tan(amplitude)."""
    if float(np.asarray(wall["normal"], float)[0]) <= 0.0 or abs(float(wall["normal"][1])) > 1e-12:
        raise RunError(f"{run.dir}: {key} has the normal {wall['normal']} (expected a flap facing +x)")
    floor, far = _floor_and_far(run, domain)
    face = float(wall["point"][0])
    hinge = np.asarray(part["centre"], float)
    if abs(hinge[0] - face) > 1e-9 or abs(hinge[1] - floor) > 1e-9:
        raise RunError(f"{run.dir}: {key} turns about {part['centre']} (expected a hinge on the floor at its face)")
    h, gauges, g = _water(run, cfg, floor)
    period = part.get("period") or (1.0 / part["frequency"] if part.get("frequency") else None)
    return {"h": h, "face": face, "far": far, "S": 2.0 * h * math.tan(math.radians(abs(float(part["amplitude"])))),
            "T": float(period), "g": g, "ramp_end": float(part.get("ramp_start", 0.0)) + float(part.get("ramp", 0.0)),
            "ramp_start": float(part.get("ramp_start", 0.0)), "gauges": gauges, "load": f"{key}.motion",
            "paddle": "flap", "phase0": 0.0}


def measure(run, margin=0.0) -> dict:
    """The flume of ``run`` and, per gauge, its window, waves and H/S."""
    f = flume(run)
    data = run.probes()
    t = data["t"]
    byname = {p["name"]: p for p in data["probes"] if p["kind"] == "depth"}
    omega = 2.0 * math.pi / f["T"]
    k = float(wavenumber(omega, f["h"], f["g"]))
    kh = k * f["h"]
    cg = group_velocity(k, f["h"], f["g"])
    span = f["far"] - f["face"]
    rows = []
    for name, xg in f["gauges"]:
        if name not in byname:
            raise RunError(f"{run.dir}: probes.nc has no depth gauge {name}")
        x = xg - f["face"]
        t0 = f["ramp_end"] + x / cg + margin * f["T"]
        t1 = min(f["ramp_start"] + (2.0 * span - x) / cg, float(t[-1]))
        eta = byname[name]["values"] - f["h"]
        sel = (t >= t0) & (t <= t1)
        heights = wave_heights(t[sel], eta[sel]) if sel.sum() > 2 else []
        H = float(np.mean(heights)) if heights else math.nan
        H1 = first_harmonic(t[sel], eta[sel], omega)[1] * 2.0 if sel.sum() > 3 else math.nan
        rows.append({"name": name, "x": x, "t0": t0, "t1": t1, "waves": len(heights), "H": H,
                     "HS": H / f["S"], "HS1": H1 / f["S"], "eta": eta})
    theory = flap(kh) if f.get("paddle") == "flap" else biesel(kh)
    return {**f, "rho0": data["rho0"], "k": k, "kh": kh, "cg": cg, "L": 2.0 * math.pi / k, "biesel": float(theory),
            "t": t, "rows": rows, "dir": run.dir}


def paddle_force(run, m, margin=0.0) -> dict | None:
    """Mean and first harmonic of the piston's Fx from wall_loads.csv, in the gauges' window at
    x = 0: from the ramp's end (plus margin periods) to the return of the far wall's reflection
    (ramp_start + 2 L / cg) or the run's end; beside it Havelock's force (havelock)."""
    path = run.dir / WALL_LOADS_CSV
    if not path.is_file() or m.get("paddle") == "flap":  # Havelock's force is a piston's
        return None
    try:
        lines = [ln for ln in path.read_text().splitlines() if ln.strip() and not ln.startswith("#")]
        header = lines[0].strip().split(",")
        data = np.loadtxt(lines[1:], delimiter=",", ndmin=2)
    except (OSError, IndexError, ValueError) as err:
        raise RunError(f"{path}: cannot read the wall loads: {err}") from None
    col = f"{m['load']}.Fx"
    if col not in header:
        return None
    # a row is the mean force over the interval that ends at its t: it stands for the midpoint
    t, fx = data[:, 0], data[:, header.index(col)]
    t = t - 0.5 * np.diff(t, prepend=t[0])
    t0 = m["ramp_end"] + margin * m["T"]
    back = m["ramp_start"] + 2.0 * (m["far"] - m["face"]) / m["cg"]
    t1 = min(back, float(t[-1]))
    sel = (t >= t0) & (t <= t1) & np.isfinite(fx)
    if sel.sum() < 4:
        return None
    # least squares fit of mean + A sin(omega t + p): the first harmonic (the mean, the still
    # water's force, drops out; the reflective impulses make the raw series spiky, and half
    # its range overstates the swing); the force on the water is -Fx
    ts, fs = t[sel], fx[sel]
    omega = 2.0 * math.pi / m["T"]
    mean, amplitude, p = first_harmonic(ts, -fs, omega)
    phase = (p - m["phase0"] + math.pi) % (2.0 * math.pi) - math.pi
    # the same fit over each whole period of the window: the spread of the amplitude (the noise)
    whole = [(ts >= t0 + j * m["T"]) & (ts < t0 + (j + 1) * m["T"]) for j in range(int((t1 - t0) / m["T"]))]
    periods = [first_harmonic(ts[q], -fs[q], omega)[1] for q in whole if q.sum() >= 4]
    return {"mean": -mean, "amplitude": amplitude, "phase": phase, "periods": periods,
            "half_range": float(0.5 * (fs.max() - fs.min())), "from": t0, "to": float(ts[-1]),
            "reflection": back <= float(t[-1]),
            "hydrostatic": 0.5 * m["rho0"] * m["g"] * m["h"] ** 2,
            "theory": havelock(omega, m["h"], m["S"], m["g"], m["rho0"])}


def decay(m):
    """(rate, H/S at x = 0) of H/S = a exp(-rate x) fitted over the gauges (least squares on
    its logarithm); None with fewer than two gauges measured. A diagnostic of the damping of
    the waves on their way, not part of linear theory."""
    pts = [(r["x"], r["HS"]) for r in m["rows"] if r["waves"] and r["HS"] > 0.0]
    if len(pts) < 2 or len({x for x, _ in pts}) < 2:
        return None
    x, y = np.array(pts).T
    slope, icpt = np.polyfit(x, np.log(y), 1)
    return float(-slope), float(math.exp(icpt))


def report(m, force):
    print(f"{m['dir']}: h = {m['h']:.4g} m, S = {m['S']:.4g} m, T = {m['T']:.4g} s, kh = {m['kh']:.4f}, "
          f"L = {m['L']:.4g} m, H/L (Biesel) = {m['biesel'] * m['S'] / m['L']:.4f}, cg = {m['cg']:.4g} m/s, "
          f"piston face to far wall {m['far'] - m['face']:.4g} m")
    print(f"  Biesel H/S = {m['biesel']:.4f}" + (" (a flap hinged at the floor)" if m.get("paddle") == "flap" else ""))
    print(f"  {'gauge':<8}{'x [m]':>8}{'x/h':>6}{'window [s]':>18}{'waves':>7}{'H [m]':>10}{'H/S':>8}"
          f"{'Biesel':>8}{'error':>9}   {'H1/S':>7}{'error':>9}")
    for r in m["rows"]:
        err = (r["HS"] / m["biesel"] - 1.0) * 100.0
        window = f"{r['t0']:.2f} - {r['t1']:.2f}"
        print(f"  {r['name']:<8}{r['x']:>8.3f}{r['x'] / m['h']:>6.1f}{window:>18}{r['waves']:>7}"
              f"{r['H']:>10.5f}{r['HS']:>8.4f}{m['biesel']:>8.4f}{err:>8.1f}%   {r['HS1']:>7.4f}"
              f"{(r['HS1'] / m['biesel'] - 1.0) * 100.0:>8.1f}%")
    good = [r["HS"] for r in m["rows"] if r["waves"]]
    if good:
        mean = float(np.mean(good))
        print(f"  mean over the gauges: H/S = {mean:.4f}, error {(mean / m['biesel'] - 1.0) * 100.0:+.1f}%")
    fit = decay(m)
    if fit is not None:
        rate, at0 = fit
        print(f"  decay along the flume (exp fit over the gauges): H loses {(1.0 - math.exp(-rate)) * 100.0:.1f}% "
              f"per metre, "
              f"{(1.0 - math.exp(-rate * m['L'])) * 100.0:.1f}% per wavelength; H/S extrapolated to the piston "
              f"{at0:.4f} ({(at0 / m['biesel'] - 1.0) * 100.0:+.1f}% from Biesel)")
    if force is not None:
        end = "the far wall's reflection returns" if force["reflection"] else "the run's end"
        hv = force["theory"]
        print(f"  piston force Fx over t = {force['from']:.2f} - {force['to']:.2f} s (a gauge's window at x = 0, "
              f"to {end}): "
              f"mean {force['mean']:.1f} N/m (still water rho0 g h^2 / 2 = {force['hydrostatic']:.1f}), "
              f"half the range, spikes included: {force['half_range']:.1f} N/m")
        print(f"  first harmonic of the force on the water (-Fx, mean removed), phase against the piston's "
              f"displacement: measured {force['amplitude']:.2f} N/m at {math.degrees(force['phase']):.1f} deg, "
              f"Havelock {hv['amplitude']:.2f} N/m at {math.degrees(hv['phase']):.1f} deg, "
              f"difference {(force['amplitude'] / hv['amplitude'] - 1.0) * 100.0:+.1f}%; measured over each whole "
              f"period: {', '.join(f'{a:.1f}' for a in force['periods']) or 'none'} N/m")
        print(f"  Havelock: radiation damping {hv['damping']:.1f} N s/m^2 ({hv['radiation']:.2f} N/m with the "
              f"velocity), added mass {hv['added_mass']:.3f} kg/m ({hv['inertia']:.2f} N/m with the acceleration)")


def plot(m, all_runs, png):
    plt = pyplot()
    fig, (ax, bx) = plt.subplots(1, 2, figsize=(13, 5), gridspec_kw={"width_ratios": [1.8, 1]})
    step = 2.5 * max(m["biesel"] * m["S"], 1e-6)
    for j, r in enumerate(m["rows"]):
        off = -j * step
        ax.plot(m["t"], r["eta"] + off, lw=0.9, color=f"C{j % 10}", label=f"{r['name']} (x = {r['x']:.2f} m)")
        ax.fill_between([r["t0"], r["t1"]], off - 0.45 * step, off + 0.45 * step, color=f"C{j % 10}",
                        alpha=0.12, lw=0)
    ax.set_xlabel("t [s]")
    ax.set_ylabel("elevation [m] (gauges offset)")
    ax.set_title(f"kh = {m['kh']:.2f}: elevation at the gauges, measuring windows shaded")
    ax.legend(fontsize=8, loc="upper left")
    top = max(2.5, max(x["kh"] for x in all_runs) * 1.2)
    kh = np.linspace(1e-3, top, 300)
    if any(x.get("paddle") != "flap" for x in all_runs):
        bx.plot(kh, biesel(kh), "k-", label="Biesel, piston (linear)")
    if any(x.get("paddle") == "flap" for x in all_runs):
        bx.plot(kh, flap(kh), "k--", label="Biesel, flap (linear)")
    for x in all_runs:
        for j, r in enumerate(x["rows"]):
            if r["waves"]:
                bx.plot(x["kh"], r["HS"], "o", ms=5, alpha=0.8, color=f"C{j % 10}")
        bx.plot(x["kh"], x["biesel"], "kx", ms=8)
    bx.set_xlabel("kh")
    bx.set_ylabel("H / S")
    bx.set_title("piston transfer function (dots: gauges, colours as left)")
    bx.grid(alpha=0.3)
    bx.legend(fontsize=8, loc="lower right")
    fig.tight_layout()
    fig.savefig(png, dpi=110)
    plt.close(fig)


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog=PROG, description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("run", nargs="+", help="a run's output directory (holding summary.json and probes.nc)")
    ap.add_argument("--margin", type=float, default=0.0, metavar="PERIODS",
                    help="start each window this many wave periods later (default 0)")
    ap.add_argument("--no-plot", action="store_true", help="print the table only")
    args = ap.parse_args(argv)
    if not args.margin >= 0.0:
        return refuse(PROG, ValueError(f"--margin must be >= 0, got {args.margin}"))
    try:
        runs = [open_run(p) for p in args.run]
        measured = [measure(r, args.margin) for r in runs]
        for r, m in zip(runs, measured):
            report(m, paddle_force(r, m, args.margin))
    except RunError as err:
        return refuse(PROG, err)
    if not args.no_plot:
        for m in measured:
            png = m["dir"] / PNG
            plot(m, measured, png)
            print(f"wrote {png}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
