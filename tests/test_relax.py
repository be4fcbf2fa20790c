"""The relaxed start (``[relax]``, :mod:`sphcore.run.relax`): dynamic relaxation before t = 0.

Known answers: under plain Tait pressure the square lattice of a tank at rest is an unstable
equilibrium at h = 1.5 dx (``tests/test_rest_linearised.py``), so a run from it slides; the
relaxation settles the particles into a nearby arrangement that is an equilibrium of the
same equations, and the run from there stays put. The relaxation ends at rest, changes no
mass, keeps every particle inside, says what it did, and is done once: a restart continues
from its checkpoint. A case it cannot serve is refused before anything is written.
"""

from __future__ import annotations

import json

import numpy as np
import pytest
from conftest import script

from sphcore import cli
from sphcore.run import relax, runner
from sphcore.run.build import build
from sphcore.run.simulation import Simulation
from sphcore.testing import case_with, write_case

# cases/hydrostatic_tank cut to 20 x 20 particles, plain Tait pressure, h = 1.5 dx
TANK = {
    "case": {"dim": 2},
    "domain": {"min": [0.0, 0.0], "max": [0.4, 0.6]},
    "blocks": [{"min": [0.0, 0.0], "max": [0.4, 0.4]}],
    "particles": {"dx": 0.02},
    "fluid": {"nu": 1.0e-6},
    "kernel": {"h_over_dx": 1.5},
    "time": {"t_end": 5.0},
    "plugins": {"use": ["reflective", "wall_integral", "pressure_gauge"]},
    "reflective": {"cr": 0.0},
}


def run_tank(tmp_path, name, *sets):
    case_dir = write_case(tmp_path / name, TANK)
    runner.run(case_dir, output=tmp_path / f"{name}_out", overrides=list(sets), quiet=True)
    return json.loads((tmp_path / f"{name}_out" / "summary.json").read_text())


@pytest.mark.slow
def test_a_relaxed_tank_stays_at_rest_where_the_lattice_slides(tmp_path):
    """5 s of plain-Tait water with the wall model at h = 1.5 dx: from the lattice the
    particles slide by 0.28 dx (measured), from the relaxed start (10 s of damped motion)
    by 0.044 dx: an equilibrium of the scheme, not only of the continuum. The issue's
    displacement target (0.1 dx) holds for the relaxed start only. (Its pressure does not
    meet 2 %: 4.9 % on this tank, measured, in the layers under the free surface;
    docs/validation/hydrostatic_tank.md.) The relaxation had nearly come to rest: its
    last speed 0.0008 m/s (measured; 0.021 m/s where it does not settle, at h = 1.3 dx)."""
    dx = 0.02
    lattice = run_tank(tmp_path, "lattice")
    relaxed = run_tank(tmp_path, "relaxed", "relax.time=10")
    for s in (lattice, relaxed):
        assert s["status"] == "completed" and s["pressure_gauge"]["particles_lost"] == 0
    assert lattice["pressure_gauge"]["max_displacement_m"] > 0.15 * dx
    assert relaxed["pressure_gauge"]["max_displacement_m"] < 0.1 * dx
    r = relaxed["core"]["relax"]
    assert r["time_s"] == pytest.approx(10.0) and r["steps"] > 0
    assert r["max_move_dx"] > 0.1  # it did leave the lattice
    assert r["last_speed_m_s"] < 2e-3
    assert r["wall_time_s"] > 0.0


def test_the_relaxation_ends_at_rest_changes_no_mass_and_keeps_every_particle_inside(tmp_path):
    """The run's t = 0 after 0.5 s of relaxation: velocities zero, masses and ids those of
    the unrelaxed start (the hydrostatic start's), positions moved, all inside the tank's
    walls by at least the contact radius (to round-off), densities finite."""
    case_dir = write_case(tmp_path / "tank", TANK)
    plain = build(*runner.load(case_dir))
    sim = build(*runner.load(case_dir, ["relax.time=0.5"]))
    a, b = plain.state, sim.state
    oa, ob = np.argsort(a.id), np.argsort(b.id)
    assert np.array_equal(a.id[oa], b.id[ob])
    assert np.array_equal(a.m[oa], b.m[ob])
    assert np.all(b.vel == 0.0)
    assert np.abs(b.pos[ob] - a.pos[oa]).max() > 0.0
    assert np.all(np.isfinite(b.rho))
    walls = sim.ctx.walls
    clearance = b.pos @ walls.normals.T - walls.offsets  # distance into the fluid side of each plane
    assert clearance.min() >= b.radius.max() * (1 - 1e-9)
    assert sim.t == 0.0 and sim.step == 0
    assert sim.ctx.stats("core")["relax"]["steps"] > 0


def test_a_restart_does_not_relax_again(tmp_path, monkeypatch):
    """A finished relaxed run continued with --restart starts from its checkpoint: the
    relaxation is not run a second time, and its figures stay in the summary."""
    case_dir = write_case(tmp_path / "tank", TANK)
    out = tmp_path / "out"
    runner.run(case_dir, output=out, overrides=["relax.time=0.2"], t_end=0.01, quiet=True)

    def must_not_run(*args, **kwargs):
        raise AssertionError("relaxed again on restart")

    monkeypatch.setattr(relax, "settle", must_not_run)
    summary = runner.run(case_dir, output=out, overrides=["relax.time=0.2"], t_end=0.02, restart=True, quiet=True)
    assert summary["status"] == "completed" and summary["t"] == pytest.approx(0.02)
    assert summary["core"]["relax"]["time_s"] == pytest.approx(0.2)


@pytest.mark.parametrize("extra, key", [
    ({"relax.time": 1.0}, "blocks[0].velocity"),
    ({"relax.time": -1.0}, "relax.time"),
    ({"relax": {"time": 1.0, "damping_time": 0.0}}, "relax.damping_time"),
    ({"relax.time": 1.0, "physics.sph": False}, "relax.time"),
])
def test_a_case_the_relaxation_cannot_serve_is_refused_and_nothing_is_written(tmp_path, capsys, extra, key):
    """Exit 2, one line naming the file and the key, no output directory: a block given a
    velocity (the relaxation ends at rest), a negative time, a zero damping time, no SPH."""
    velocity = {"blocks[0].velocity": [0.1, 0.0]} if "velocity" in key else {}
    case_dir = write_case(tmp_path / "bad", case_with(TANK, {**velocity, **extra}))
    assert cli.main(["run", str(case_dir), "--output", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert key in err and "case.toml" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_a_relaxation_that_would_take_too_many_steps_is_refused(tmp_path, capsys):
    """time.max_steps bounds the relaxation as it bounds the run: 100 s of relaxation at
    this tank's step is refused after its first step, exit 2, nothing written."""
    case_dir = write_case(tmp_path / "long", case_with(TANK, {"relax.time": 100.0}))
    code = cli.main(["run", str(case_dir), "--output", str(tmp_path / "out"), "--t-end", "0.001",
                     "--set", "time.max_steps=20000"])
    assert code == 2
    err = capsys.readouterr().err
    assert "relax.time" in err and "max_steps" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


COLUMN = case_with(TANK, {"blocks[0].max": [0.1, 0.3]})


def test_a_column_that_falls_while_relaxing_is_refused(tmp_path, capsys):
    """A dam-break column (0.1 m x 0.3 m in a 0.4 m tank) is not at rest in its container:
    its particles move more than 3 dx while relaxing, the relaxation stops and the case is
    refused, exit 2, naming the option and saying why, nothing written."""
    case_dir = write_case(tmp_path / "column", COLUMN)
    code = cli.main(["run", str(case_dir), "--output", str(tmp_path / "out"), "--set", "relax.time=2"])
    assert code == 2
    err = capsys.readouterr().err
    assert "--set" in err and "relax.time" in err and "not at rest" in err and "Traceback" not in err
    assert not (tmp_path / "out").exists()


def test_an_unstable_relaxation_is_refused_with_its_reason(tmp_path, capsys, monkeypatch):
    """An instability while relaxing (here made to happen at its 5th step) is a case error
    naming relax.time and the instability's message, exit 2, nothing written; the run's own
    steps are not affected by the patch (it raises only while relaxing)."""
    from sphcore.errors import Instability

    advance = Simulation.advance

    def failing(self):
        if self.relaxing and self.step == 5:
            raise Instability(self.step, self.t, 0, "density below bounds (made up by the test)")
        advance(self)

    monkeypatch.setattr(Simulation, "advance", failing)
    case_dir = write_case(tmp_path / "tank", case_with(TANK, {"relax.time": 0.1}))
    assert cli.main(["run", str(case_dir), "--output", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "relax.time" in err and "made up by the test" in err and "case.toml" in err
    assert not (tmp_path / "out").exists()


def test_sph_check_does_not_relax_and_says_so(tmp_path, capsys, monkeypatch):
    """sph check validates a case in seconds: it does not run the relaxation (which may take
    minutes), and says that sph run will."""

    def must_not_run(*args, **kwargs):
        raise AssertionError("sph check relaxed")

    monkeypatch.setattr(relax, "settle", must_not_run)
    case_dir = write_case(tmp_path / "tank", case_with(TANK, {"relax.time": 100.0}))
    assert cli.main(["check", str(case_dir)]) == 0
    out = capsys.readouterr().out
    assert "ok:" in out and "relax: 100 s of damped motion before t = 0, done by sph run" in out


def test_the_wall_model_pulls_the_top_corners_of_the_ghosts_equilibrium(tmp_path):
    """postprocessing/tank_cross_start.py on the 20 x 20 tank at h = 2 dx: the ghosts'
    own relaxed state is (nearly) at rest under the ghosts, while the wall model pulls its
    top corner particles towards the side wall (measured: -0.04 to -0.09 g on the 50 x 50
    tank) and leaves the middle column alone: the two boundaries disagree where the free
    surface meets a wall (docs/explanation/density_diffusion.md)."""
    mod = script("tank_cross_start")
    case_dir = write_case(tmp_path / "tank", TANK)
    own, columns, moved_own, _, _ = mod.cross_start(case_dir, "ghost", "ghost", 2.0, 3.0, 0.01)
    cross, _, moved, errors, t = mod.cross_start(case_dir, "ghost", "wall_integral", 2.0, 3.0, 0.01)
    assert columns[:6] == list(range(6)) and t == pytest.approx(0.01, rel=0.05)
    corner = np.abs(cross[:2, 0, 0]).max()  # horizontal, top two layers, the wall's column
    assert corner > 0.02  # in g
    assert corner > 10 * np.abs(own[:2, 0, 0]).max()
    assert np.abs(cross[:, -1, :]).max() < 1e-3  # the middle column feels no difference
    assert np.isfinite(errors).all() and moved < 0.1 and moved_own < 0.1
    assert mod.main(["--case", str(tmp_path / "none")]) == 2  # no case.toml: a message, not a traceback
    assert mod.main(["--case", str(case_dir), "--run-with", "nope", "--relax", "0.01", "--time", "0.01"]) == 2
    assert mod.main(["--case", str(case_dir), "--run-set", "nokey", "--relax", "0.01", "--time", "0.01"]) == 2
