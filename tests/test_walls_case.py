"""Finite walls from case.toml (``[[domain.walls]]``): clear errors for bad input, blocks
clipped by the walls, a tank given by a polygon alone, walls in the VTU output, and runs
in which no particle ever enters a wall: a water column falling onto a box obstacle in 2D
and 3D, and one collapsing into the foot of an L-shaped tank."""

from __future__ import annotations

import json

import meshio
import numpy as np
import pytest

from sphcore import cli
from sphcore.errors import CaseError
from sphcore.geometry.faces import box
from sphcore.run import runner
from sphcore.run.build import build
from sphcore.testing import case_with, write_case


def walls_case(wall, dim=2, domain=None, bmin=None, bmax=None, dx=0.02, t_end=0.002, plugins=("reflective",)):
    """A case with the finite wall ``wall`` (one [[domain.walls]] entry) beside the rest of
    ``domain`` (default: the unit box's min and max), and one block of water."""
    domain = {"min": [0.0, 0.0], "max": [1.0, 1.0]} if domain is None else domain
    return {
        "case": {"dim": dim},
        "domain": {**domain, "walls": [wall]},
        "blocks": [{"min": bmin or [0.0] * dim, "max": bmax or [0.4] * dim}],
        "particles": {"dx": dx},
        "time": {"t_end": t_end},
        "plugins": {"use": list(plugins)},
    }


def load(tmp_path, case):
    return runner.load(write_case(tmp_path / "c", case))


@pytest.mark.parametrize("wall, key, words", [
    ({"shape": "sphere"}, "domain.walls[0].shape", "one of"),
    ({"min": [0.5, 0.5], "max": [0.6, 0.6]}, "domain.walls[0].shape", "required"),
    ({"shape": "box", "min": [0.5, 0.5]}, "domain.walls[0].max", "required"),
    ({"shape": "box", "min": [0.5, 0.5], "max": [0.4, 0.6]}, "domain.walls[0].max", "above min"),
    ({"shape": "box", "min": [0.5, 0.5], "max": [0.6, 0.6], "points": [[0, 0]]},
     "domain.walls[0].points", "not used"),
    ({"shape": "polygon", "points": [[0.5, 0.5], [0.6, 0.5]]}, "domain.walls[0].points",
     "at least 3"),
    ({"shape": "polygon", "points": [[0.5, 0.5], [0.7, 0.7], [0.7, 0.5], [0.5, 0.7]]},
     "domain.walls[0].points", "cross"),
    ({"shape": "polyline", "points": [[0.5, 0.5], [0.7, 0.7]], "fluid": "inside"},
     "domain.walls[0].fluid", "both sides"),
    ({"shape": "mesh", "file": "nowhere.stl"}, "domain.walls[0].file", "nowhere.stl"),
    ({"shape": "box", "min": [0.5, 0.5], "max": [0.6, 0.6], "colour": "red"},
     "domain.walls[0].colour", ""),
])
def test_bad_walls_name_the_key(tmp_path, wall, key, words):
    with pytest.raises(CaseError) as err:
        load(tmp_path, walls_case(wall))
    assert err.value.key == key and words in err.value.expected and err.value.file.endswith("case.toml")


def test_bad_wall_exits_2_and_writes_nothing(tmp_path, capsys):
    d = write_case(tmp_path / "c", walls_case({"shape": "polygon", "points": [[0.5, 0.5]]}))
    before = sorted(p.name for p in d.iterdir())
    assert cli.main(["run", str(d)]) == 2
    assert "domain.walls[0].points" in capsys.readouterr().err
    assert sorted(p.name for p in d.iterdir()) == before


def test_a_mesh_that_is_not_closed_is_refused(tmp_path):
    d = tmp_path / "c"
    d.mkdir()
    tris = box([0.4, 0.4, 0.4], [0.6, 0.6, 0.6])[:-1]  # one triangle missing
    pts = tris.reshape(-1, 3)
    meshio.write(d / "open.stl", meshio.Mesh(pts, [("triangle", np.arange(len(pts)).reshape(-1, 3))]))
    case = walls_case({"shape": "mesh", "file": "open.stl"}, dim=3,
                      domain={"min": [0.0, 0.0, 0.0], "max": [1.0, 1.0, 1.0]}, dx=0.05)
    with pytest.raises(CaseError) as err:
        runner.load(write_case(d, case))
    assert "not closed" in err.value.expected and "open.stl" in err.value.expected


def test_blocks_are_clipped_by_walls_and_check_counts_them(tmp_path, capsys):
    # a box obstacle inside the block: particles in it or within a radius of it are not made
    case, pm = load(tmp_path, walls_case({"shape": "box", "min": [0.1, 0.0], "max": [0.2, 0.1]}))
    sim = build(case, pm, None)
    st = sim.state
    assert st.n + st.removed_by_walls == 400
    # lattice centres 0.01, 0.03, ...; removed: closer than r = 0.01 to the box [0.1, 0.2] x
    # [0, 0.1], i.e. x in (0.09, 0.21), y < 0.11: 5 x 5 (those at exactly r are kept)
    assert st.removed_by_walls == 25
    assert np.all(case.faces.distances(st.pos) >= 0.01 * (1 - 1e-9)) and case.faces.in_fluid(st.pos).all()
    assert cli.main(["check", str(tmp_path / "c")]) == 0
    assert "4 wall faces (25 particles of the blocks not created" in capsys.readouterr().out


def test_a_tank_given_by_a_mesh_alone(tmp_path):
    # no planes: an L-shaped 2D tank from a polygon with fluid inside
    wall = {"shape": "polygon", "fluid": "inside",
            "points": [[0, 0], [1, 0], [1, 0.3], [0.4, 0.3], [0.4, 1], [0, 1]]}
    case, pm = load(tmp_path, walls_case(wall, domain={}, bmin=[0.0, 0.0], bmax=[0.4, 0.6], t_end=0.3,
                                         plugins=["reflective"]))
    assert case.planes.count == 0 and case.faces.count == 6
    sim = build(case, pm, None)
    n0 = sim.state.n
    while not sim.done():
        sim.advance()
        st = sim.state
        assert np.all(case.faces.distances(st.pos) >= st.radius * (1 - 1e-9))
        assert case.faces.in_fluid(st.pos).all()
    assert sim.state.n == n0 and np.isfinite(sim.state.vel).all()
    # the column collapsed into the foot of the L
    assert sim.state.pos[:, 0].max() > 0.5


@pytest.mark.parametrize("dim", [2, 3])
def test_water_falls_onto_a_box_obstacle_and_stays_out_of_it(tmp_path, dim):
    lo, hi = [0.3] + [0.0] * (dim - 1), [0.5] + [0.15] * (dim - 1)
    if dim == 3:
        lo[1], hi[1] = 0.05, 0.25
    wall = {"shape": "box", "min": lo, "max": hi}
    domain = {"min": [0.0, 0.0], "max": [1.0, 1.0]} if dim == 2 else {"min": [0.0, 0.0, 0.0], "max": [1.0, 0.3, 1.0]}
    bmin = [0.25, 0.3] if dim == 2 else [0.25, 0.0, 0.3]
    bmax = [0.55, 0.6] if dim == 2 else [0.55, 0.3, 0.6]
    case, pm = load(tmp_path, walls_case(wall, dim=dim, domain=domain, bmin=bmin, bmax=bmax,
                                         dx=0.02 if dim == 2 else 0.03, t_end=0.35 if dim == 2 else 0.25))
    sim = build(case, pm, None)
    n0 = sim.state.n
    e = "z" if dim == 3 else "y"
    while not sim.done():
        sim.advance()
        st = sim.state
        assert np.all(case.faces.distances(st.pos) >= st.radius * (1 - 1e-9)), e
        assert case.faces.in_fluid(st.pos).all()
    st = sim.state
    assert st.n == n0 and np.isfinite(st.vel).all() and np.isfinite(st.rho).all()
    # the water hit the top of the box and flowed off both sides
    assert st.pos[:, 0].min() < 0.3 and st.pos[:, 0].max() > 0.5


def test_walls_are_written_for_paraview(tmp_path):
    case = walls_case({"shape": "polygon", "points": [[0.6, 0.0], [0.8, 0.0], [0.7, 0.2]]},
                      plugins=["reflective", "vtu"])
    d = write_case(tmp_path / "c", case)
    assert cli.main(["run", str(d), "--progress", "off"]) == 0
    mesh = meshio.read(d / "output" / "c_walls.vtu")
    assert mesh.cells[0].type == "line" and len(mesh.cells[0].data) == 3
    normals = mesh.cell_data["normal"][0]
    # an obstacle: normals point out of the triangle, into the fluid
    centre = np.array([0.7, 0.2 / 3, 0.0])
    mids = mesh.points[mesh.cells[0].data].mean(axis=1)
    assert np.all(np.einsum("ij,ij->i", mids - centre, normals) > 0)
    summary = json.loads((d / "output" / "summary.json").read_text())
    assert summary["reflective"]["guard_returns"] == 0


def test_a_probe_inside_an_obstacle_is_refused_one_on_its_face_is_not(tmp_path):
    wall = {"shape": "box", "min": [0.6, 0.0], "max": [0.8, 0.2]}
    for point, ok in (([0.7, 0.1], False), ([0.6, 0.1], True), ([0.5, 0.1], True)):
        case = case_with(walls_case(wall, plugins=["reflective", "probes"]),
                         {"probes.pressure": [{"name": "P", "point": point}]})
        d = write_case(tmp_path / f"c{point[0]}", case)
        if ok:
            runner.load(d)
        else:
            with pytest.raises(CaseError) as err:
                runner.load(d)
            assert err.value.key == "probes.pressure[0].point" and "inside a solid wall" in err.value.expected


@pytest.mark.slow
def test_the_wall_model_holds_a_tank_with_a_step_at_rest(tmp_path):
    # water 1 m deep at rest over a box step 0.2 m high on the floor, plain Tait pressure
    # (no modified pressure), delta = 0.1: with the wall model on planes and faces the
    # hydrostatic pressure holds to 3.2 % and no particle moves a grid spacing in 1 s
    # (measured; reflective walls alone: 49 % and 5.6 dx)
    case = walls_case({"shape": "box", "min": [0.4, 0.0], "max": [0.6, 0.2]},
                      domain={"min": [0.0, 0.0], "max": [1.0, 1.2]}, bmin=[0.0, 0.0], bmax=[1.0, 1.0],
                      t_end=1.0, plugins=["reflective", "wall_integral", "pressure_gauge"])
    case = case_with(case, {"physics.modified_pressure": False, "density_diffusion": {"delta": 0.1, "hydrostatic": True},
                            "viscosity.alpha": 0.1, "reflective.cr": 0.0})
    d = write_case(tmp_path / "c", case)
    assert cli.main(["run", str(d), "--progress", "off"]) == 0
    gauge = json.loads((d / "output" / "summary.json").read_text())["pressure_gauge"]
    assert gauge["particles_lost"] == 0
    assert gauge["pressure_max_layer_err"] < 0.05
    assert gauge["max_displacement_m"] < 0.02 * 1.5


def test_ghosts_refuse_finite_walls_and_say_what_to_use(tmp_path):
    case = walls_case({"shape": "box", "min": [0.6, 0.0], "max": [0.8, 0.2]}, plugins=["reflective", "ghost"])
    with pytest.raises(CaseError) as err:
        load(tmp_path, case)
    assert err.value.key == "domain.walls" and "mirrors across wall planes only" in err.value.expected
    assert "wall_integral" in err.value.expected


def test_a_block_with_clip_leaves_out_the_particles_beyond_a_sloping_plane(tmp_path):
    """Water over a beach: a 1:2 slope through the block. Without clip the first particle
    beyond the plane is an error naming the block; with it, exactly the lattice's particles
    at least a radius inside every plane are made, and a run from them keeps them inside."""
    from sphcore.testing import tiny_case

    beach = {"normal": [-0.5, 1.0], "point": [0.1, 0.0]}  # inside: above y = (x - 0.1) / 2
    raw = case_with(tiny_case(), {"domain.planes": [beach], "blocks[0].max": [0.4, 0.1],
                                  "plugins.use": ["reflective"], "time.t_end": 0.02})
    with pytest.raises(CaseError) as err:
        build(*load(tmp_path / "a", raw), None)
    assert err.value.key == "blocks[0]" and "outside wall plane 4" in err.value.expected
    case, pm = load(tmp_path / "b", case_with(raw, {"blocks[0].clip": True}))
    sim = build(case, pm, None)
    x = (np.arange(20) + 0.5) * 0.02
    y = (np.arange(5) + 0.5) * 0.02
    gx, gy = np.meshgrid(x, y, indexing="ij")
    n = np.array([-0.5, 1.0]) / np.hypot(0.5, 1.0)
    expect = int(((gx - 0.1) * n[0] + gy * n[1] >= 0.01 * (1 - 1e-9)).sum())
    assert 0 < sim.state.n == expect < 100 and sim.state.removed_by_walls == 100 - expect
    while not sim.done():
        sim.advance()
        assert np.all(case.planes.distances(sim.state.pos) >= sim.state.radius[:, None] * (1 - 1e-9))


def test_a_clipped_block_wholly_beyond_a_plane_is_refused_naming_its_clip(tmp_path, capsys):
    from sphcore.testing import tiny_case

    raw = case_with(tiny_case(), {"domain.planes": [{"normal": [0.0, 1.0], "point": [0.0, 0.5]}],
                                  "blocks[0].clip": True, "plugins.use": ["reflective"]})
    with pytest.raises(CaseError) as err:
        build(*load(tmp_path, raw), None)
    assert err.value.key == "blocks[0].clip" and "beyond a wall plane" in err.value.expected
    case_dir = tmp_path / "c"
    assert cli.main(["check", str(case_dir)]) == 2 and not (case_dir / "output").exists()
    assert "blocks[0].clip" in capsys.readouterr().err
