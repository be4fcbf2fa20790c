"""A tank at rest, linearised: growth rates, the acoustic quarter wave and the sloshing mode.

    python validation/hydrostatic_tank/rest_stability.py [--h 1.3 1.5 1.7 1.9 2.0] [--size 0.4 0.4] [--span S]
        [--boundary wall_model ghosts reflective] [--set KEY=VALUE ...] [--jitter A --run T]
        [--relax T [TAU]] [--no-modes]

Builds ``cases/hydrostatic_tank`` with plain Tait pressure (no modified pressure), its block
cut to ``--size`` (width, depth in m; the default 20 x 20 particles keeps each row to a few
seconds; ``--span`` makes it a 3D tank that deep across), and for every smoothing length and
boundary linearises the rates about the hydrostatic start (:mod:`sphcore.physics.linearised`). Keep
the width and the span above 4h + 2 dx: in a narrower channel particles reach two opposite
walls, where the wall model adds the two walls' single-wall lattice errors (an
approximation: 0.026 g sideways 7 dx under the surface at h = 2 dx in a channel 6 dx
across), and the figures then describe the channel, not the walls. Prints

- the largest growth rate Re lambda (1/s; > 0: the rest state is unstable and any
  disturbance, round-off included, grows as exp(Re lambda t)) and where that mode's
  displacement is largest (column, row of the initial lattice from the lower left);
- the quarter-wave acoustic mode of the column (density ~ cos(pi z / 2H)) against
  omega = pi c0 / (2 H), and the depth the scheme behaves as if it had, pi c0 / (2 omega):
  its excess over H, in dx, is how far below the floor the scheme's wall acts;
- the first sloshing mode (velocity of the linear wave potential cos(k x) cosh(k z),
  k = pi / L) against omega^2 = g k tanh(k H), with its damping (the artificial viscosity).

With ``--jitter A --run T`` each tank is also run for T seconds from its start with every
position moved by a random amount of up to A dx (seeded), and the largest displacement from
the unmoved lattice printed every 0.5 s: an unstable rest state shows its growth from a
disturbance the exact lattice does not have (a run from the exact lattice may stay put by
symmetry alone).

With ``--relax T [TAU]`` each tank starts from the core's relaxed start (``[relax]``,
:mod:`sphcore.run.relax`: T seconds of the case's dynamics with every velocity damped as
exp(-t / TAU), TAU = 0.3 s by default, from random velocities of about the ``--jitter``
amplitude, default 1e-3 dx here); the linearisation and the run start from that state, and
the run's displacements are measured from it. The line ``relaxed``
gives the largest move from the lattice (dx), the largest speed before the stop and the
worst layer's pressure error below the top two (``pressure_gauge``'s definition). What it
shows: at h = 1.5 dx an unstable lattice settles
into a nearby arrangement whose growth is slower (wall model 2.23 -> 1.27 1/s), at 1.3 dx
none is found nearby, and with the wall model the layers under the free surface keep their
error (a zigzag made at the top corners). ``--no-modes`` skips the linearisation (its dense matrix grows as the
square of the particle count: use it for the full 1 m tank's run, ``--size 1.0 1.0``).

Figures are printed, never asserted (``tests/test_rest_linearised.py`` asserts the known
answers); the validation page "The tank at rest" (docs/validation/hydrostatic_tank.md)
cites its growth rates.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from sphcore.case.overrides import parse_set
from sphcore.physics.linearised import column_at_rest
from sphcore.run import runner
from sphcore.run.build import build
from sphcore_plugins.gauges.hydrostatic import layer_errors, worst_layer_error

ROOT = Path(__file__).resolve().parents[2]
BOUNDARIES = {"wall_model": '["reflective","wall_integral"]', "ghosts": '["ghost","reflective"]',
              "reflective": '["reflective"]'}


def tank(h: float, boundary: str, size=(0.4, 0.4), sets=(), span=None, case_dir=ROOT / "cases" / "hydrostatic_tank"):
    """A Simulation of the plain-Tait tank at rest (hydrostatic start), block cut to ``size``
    (width, depth); with ``span`` a 3D tank that deep across (the third axis; y is up)."""
    w, d = size
    over = ["physics.modified_pressure=false", f"kernel.h_over_dx={h}", f"plugins.use={BOUNDARIES[boundary]}"]
    if span is None:
        over += [f"domain.max=[{w},{1.5 * d}]", f"blocks[0].max=[{w},{d}]"]
    else:
        over += ["case.dim=3", "domain.min=[0,0,0]", f"domain.max=[{w},{1.5 * d},{span}]", "blocks[0].min=[0,0,0]",
                 f"blocks[0].max=[{w},{d},{span}]"]
    over += list(sets)
    case, pm = runner.load(case_dir, [parse_set(s) for s in over])
    return build(case, pm)


def worst_layer(sim) -> float:
    """The largest pressure error (%) of a layer below the top two (``pressure_gauge``)."""
    st, prm = sim.state, sim.params
    z = st.pos @ prm.up
    top = float(sim.case.config["blocks"][0]["max"][int(np.argmax(np.abs(prm.up)))])
    rows = layer_errors(z, st.p, sim.case.dx, top, prm.rho0, prm.g_abs)
    return 100.0 * worst_layer_error(rows, top, sim.case.dx, 2)


def jittered_run(sim, amp: float, t_end: float, every: float = 0.5):
    """Run ``sim`` for ``t_end`` s from its state moved by up to ``amp`` dx; print the
    largest displacement (dx) from the unmoved state every ``every`` s, and the worst layer."""
    st, dx = sim.state, sim.case.dx
    start = dict(zip(st.id.tolist(), st.pos.copy()))
    st.pos += amp * dx * np.random.default_rng(1).uniform(-1.0, 1.0, st.pos.shape)
    sim.integrator.invalidate()
    line, t0, mark = [], sim.t, every
    while sim.t - t0 < t_end - 1e-12:
        sim.advance()
        if sim.t - t0 >= mark - 1e-12:
            ref = np.array([start[i] for i in st.id.tolist()])
            line.append(f"{np.linalg.norm(st.pos - ref, axis=1).max() / dx:.3g}")
            mark += every
    print(f"      largest displacement (dx) every {every} s from a {amp:g} dx jitter: {' '.join(line)}; "
          f"worst layer below the top two {worst_layer(sim):.2f} %", flush=True)


def relaxed(sim):
    """Print what the core's relaxation of ``sim``'s start did (``[relax]``, sphcore.run.relax)."""
    r = sim.ctx.stats("core")["relax"]
    print(f"      relaxed {r['time_s']:g} s (tau {r['damping_time_s']:g} s): moved {r['max_move_dx']:.3g} dx from the "
          f"lattice, speed {r['last_speed_m_s']:.2g} m/s before the stop, worst layer below the top two "
          f"{worst_layer(sim):.2f} %", flush=True)
    return sim


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--h", type=float, nargs="+", default=[1.3, 1.5, 1.7, 1.9, 2.0], help="h / dx")
    ap.add_argument("--size", type=float, nargs=2, default=[0.4, 0.4], metavar=("WIDTH", "DEPTH"))
    ap.add_argument("--boundary", nargs="+", default=list(BOUNDARIES), choices=list(BOUNDARIES))
    ap.add_argument("--set", action="append", default=[], help="more case overrides, as sph run --set")
    ap.add_argument("--span", type=float, help="a 3D tank this deep across (m); keep it and the width above 4h + 2 dx")
    ap.add_argument("--jitter", type=float, default=0.0, help="with --run: random start offsets, up to this many dx")
    ap.add_argument("--run", type=float, default=0.0, help="also run each tank this many seconds (s)")
    ap.add_argument("--relax", type=float, nargs="+", metavar=("T", "TAU"),
                    help="relax each tank first: T s of damped motion, damping time TAU s (default 0.3)")
    ap.add_argument("--modes", action=argparse.BooleanOptionalAction, default=True,
                    help="linearise (default); --no-modes: the run only")
    a = ap.parse_args()
    if not a.modes and a.run <= 0:
        ap.error("--no-modes leaves only the run: give --run T (s)")
    if a.relax and (len(a.relax) > 2 or min(a.relax) <= 0):
        ap.error("--relax takes T and optionally TAU, both positive (s)")
    if a.relax:  # the core's relaxation ([relax]); the case's own end would stop the run that follows
        a.set = ["time.t_end=1e9", f"relax.time={a.relax[0]}", f"relax.damping_time={a.relax[1] if len(a.relax) > 1 else 0.3}",
                 f"relax.jitter={a.jitter or 1e-3}"] + a.set

    def build(h, name):
        sim = tank(h, name, a.size, a.set, a.span)
        return relaxed(sim) if a.relax else sim

    across = f" x {a.span} m across (3D)" if a.span else ""
    print(f"plain-Tait tank at rest, {a.size[0]} m x {a.size[1]} m{across}; omega in rad/s")
    if a.modes:
        print(f"{'h/dx':>5} {'boundary':>11} {'growth 1/s':>11} {'where':>9} {'acoustic':>9} {'fit':>5} {'theory':>8} "
              f"{'wall offset':>11} {'sloshing':>9} {'theory':>7} {'damping':>8}")
    for h in a.h:
        for name in a.boundary:
            if not a.modes:
                print(f"{h:>5} {name:>11}", flush=True)
                jittered_run(build(h, name), 0.0 if a.relax else a.jitter, a.run)
                continue
            sim = build(h, name)
            r = column_at_rest(sim)
            print(f"{h:>5} {name:>11} {r['growth']:>+11.3g} {str(r['where']):>9} {r['acoustic']:>9.2f} {r['acoustic_fit']:>5.3f} "
                  f"{r['acoustic_theory']:>8.2f} {r['wall_offset_dx']:>+9.2f}dx {r['slosh']:>9.3f} "
                  f"{r['slosh_theory']:>7.3f} {r['slosh_damping']:>8.3f}", flush=True)
            if a.run > 0:
                jittered_run(sim if a.relax else tank(h, name, a.size, a.set, a.span), 0.0 if a.relax else a.jitter,
                             a.run)


if __name__ == "__main__":
    main()
