"""Wall motion in case.toml (sphcore.case.motion): what a case gives is what moves, and every
malformed motion is refused at load with exit 2, naming the file, the key and what was
expected, before anything is written."""

from __future__ import annotations

import math

import numpy as np
import pytest

from sphcore import cli
from sphcore.errors import CaseError
from sphcore.run import runner
from sphcore.testing import case_with, tiny_case, write_case

SWAY = {"type": "sine_translation", "axis": [1.0, 0.0], "amplitude": 0.02, "period": 1.0}
ROLL = {"type": "sine_rotation", "centre": [0.5, 0.0], "amplitude": 4.0, "period": 1.63}
PADDLE = {"shape": "box", "min": [0.6, 0.0], "max": [0.7, 0.3]}


def _load(tmp_path, changes, files=None):
    case_dir = write_case(tmp_path / "case", case_with(tiny_case(), changes))
    for name, text in (files or {}).items():
        (case_dir / name).write_text(text)
    return runner.load(case_dir)[0]


def test_the_tank_and_a_wall_move_as_given(tmp_path):
    case = _load(tmp_path, {"domain.motion": [ROLL, {**SWAY, "ramp": 0.5}],
                            "domain.walls": [{**PADDLE, "tank": True}, {**PADDLE, "min": [0.8, 0.0], "max": [0.9, 0.3],
                                                                        "motion": [SWAY]}]})
    tank, paddle = case.moving
    assert tank.name == "domain.motion" and tank.planes.tolist() == [0, 1, 2, 3] and tank.faces.tolist() == [0, 1, 2, 3]
    assert paddle.name == "domain.walls[1].motion" and paddle.planes.tolist() == [] and paddle.faces.tolist() == [4, 5, 6, 7]
    t = 0.3
    pose = tank.motion.pose(t)
    theta = math.radians(4.0) * math.sin(2 * math.pi * t / 1.63)
    assert math.atan2(pose.rotation[1, 0], pose.rotation[0, 0]) == pytest.approx(theta, abs=1e-15)
    ramp = (t / 0.5) ** 3 * (10 - 15 * t / 0.5 + 6 * (t / 0.5) ** 2)
    assert pose.shift[0] == pytest.approx(ramp * 0.02 * math.sin(2 * math.pi * t), abs=1e-15)
    assert paddle.motion.pose(t).shift[0] == pytest.approx(0.02 * math.sin(2 * math.pi * t), abs=1e-15)


def test_a_plane_with_a_motion_of_its_own_moves_alone(tmp_path):
    """A [[domain.planes]] entry with a motion (a piston) is its own group, named by its key;
    the tank's motion carries the other planes (the box's four first, then the entries)."""
    piston = {"normal": [1.0, 0.0], "point": [0.05, 0.0], "motion": [SWAY]}
    case = _load(tmp_path, {"domain.planes": [{"normal": [0.0, 1.0], "point": [0.0, 0.01]}, piston],
                            "domain.motion": [ROLL]})
    tank, own = case.moving
    assert own.name == "domain.planes[1].motion" and own.planes.tolist() == [5] and own.faces.tolist() == []
    assert tank.planes.tolist() == [0, 1, 2, 3, 4] and math.isinf(own.reach)
    assert own.motion.pose(0.25).shift[0] == pytest.approx(0.02, abs=1e-15)
    # without the tank's motion the other planes stay fixed: one group
    case = _load(tmp_path, {"domain.planes": [piston]})
    assert [g.name for g in case.moving] == ["domain.planes[0].motion"] and case.moving[0].planes.tolist() == [4]


def test_a_case_without_motion_has_no_moving_group(tmp_path):
    assert _load(tmp_path, {}).moving == ()


def test_a_samples_file_is_read_with_comments_a_header_and_any_separator(tmp_path):
    rows = "\n".join(f"{t:.3f}, {0.01 * math.sin(3 * t):.12f}" for t in np.linspace(0, 0.01, 11))
    case = _load(tmp_path, {"domain.motion": [{"type": "translation_file", "file": "paddle.csv", "axis": [1, 0]}]},
                 {"paddle.csv": "# measured paddle stroke\ntime,x\n" + rows.replace(", ", ";", 3) + "\n"})
    pose = case.moving[0].motion.pose(0.005)
    assert pose.shift[0] == pytest.approx(0.01 * math.sin(0.015), rel=1e-6) and pose.shift[1] == 0.0


def test_scale_multiplies_a_files_values_so_an_angle_measured_the_other_way_round_turns_the_other_way(tmp_path):
    """rotation_file with scale = -1 turns by minus the file's angle (a flap whose measured angle
    is positive towards the water); translation_file with scale = 0.001 reads millimetres."""
    rows = "".join(f"{t:.3f} {2.0 * t:.6f}\n" for t in np.linspace(0, 0.01, 11))
    turned = {}
    for scale in (1.0, -1.0):
        case = _load(tmp_path, {"domain.motion": [{"type": "rotation_file", "file": "flap.dat", "centre": [0.0, 0.0],
                                                   "scale": scale}]}, {"flap.dat": rows})
        r = case.moving[0].motion.pose(0.005).rotation
        turned[scale] = math.degrees(math.atan2(r[1, 0], r[0, 0]))
    assert turned[1.0] == pytest.approx(0.01, rel=1e-9) and turned[-1.0] == pytest.approx(-turned[1.0], rel=1e-12)
    case = _load(tmp_path, {"domain.motion": [{"type": "translation_file", "file": "mm.dat", "axis": [1, 0],
                                               "scale": 0.001}]}, {"mm.dat": rows})
    assert case.moving[0].motion.pose(0.005).shift[0] == pytest.approx(1e-5, rel=1e-9)


def test_a_samples_file_that_is_a_pipe_or_a_device_is_refused_at_once(tmp_path):
    """A FIFO or a link to /dev/zero as the samples file: refused naming the key, no hang."""
    import os

    case_dir = write_case(tmp_path / "case", case_with(tiny_case(), {
        "domain.motion": [{"type": "translation_file", "file": "paddle.csv", "axis": [1, 0]}]}))
    os.mkfifo(case_dir / "paddle.csv")
    with pytest.raises(CaseError) as e:
        runner.load(case_dir)
    assert e.value.key == "domain.motion[0].file" and "not a regular file" in str(e.value)
    (case_dir / "paddle.csv").unlink()
    (case_dir / "paddle.csv").symlink_to("/dev/zero")
    with pytest.raises(CaseError) as e:
        runner.load(case_dir)
    assert e.value.key == "domain.motion[0].file" and "not a regular file" in str(e.value)


GOOD_SERIES = "0 0\n0.001 0.1\n0.003 0.2\n0.01 0.1\n"
#: (changes, files, the key named, words of the message)
BAD = {
    "plane motion without type": ({"domain.planes": [{"normal": [1.0, 0.0], "point": [0.0, 0.0],
                                                      "motion": [{"amplitude": 1.0}]}]}, None,
                                  "domain.planes[0].motion[0].type", "required"),
    "no type": ({"domain.motion": [{"amplitude": 1.0}]}, None, "domain.motion[0].type", "required"),
    "unknown type": ({"domain.motion": [{**SWAY, "type": "wobble"}]}, None, "domain.motion[0].type", "expected"),
    "unknown key": ({"domain.motion": [{**SWAY, "speed": 1.0}]}, None, "domain.motion[0].speed", "unknown key"),
    "key of another type": ({"domain.motion": [{**SWAY, "centre": [0, 0]}]}, None, "domain.motion[0].centre",
                            "not used"),
    "missing amplitude": ({"domain.motion": [{k: v for k, v in SWAY.items() if k != "amplitude"}]}, None,
                          "domain.motion[0].amplitude", "required"),
    "period zero": ({"domain.motion": [{**SWAY, "period": 0.0}]}, None, "domain.motion[0].period", "positive"),
    "period and frequency": ({"domain.motion": [{**SWAY, "frequency": 1.0}]}, None, "domain.motion[0].period",
                             "either"),
    "axis of zero length": ({"domain.motion": [{**SWAY, "axis": [0.0, 0.0]}]}, None, "domain.motion[0].axis",
                            "non-zero length"),
    "axis of three numbers in 2D": ({"domain.motion": [{**SWAY, "axis": [1.0, 0.0, 0.0]}]}, None,
                                    "domain.motion[0].axis", "2 numbers"),
    "two rotations": ({"domain.motion": [ROLL, ROLL]}, None, "domain.motion[1].type", "at most one rotation"),
    "starts displaced": ({"domain.motion": [{**SWAY, "phase": 90.0}]}, None, "domain.motion", "start where"),
    "tank and own motion": ({"domain.walls": [{**PADDLE, "tank": True, "motion": [SWAY]}]}, None,
                            "domain.walls[0].motion", "no motion of its own"),
    "wall motion not a list of tables": ({"domain.walls": [{**PADDLE, "motion": 3}]}, None, "domain.walls[0].motion",
                                         "list of tables"),
    "missing file": ({"domain.motion": [{"type": "rotation_file", "file": "roll.dat", "centre": [0.5, 0]}]}, None,
                     "domain.motion[0].file", "no such file"),
    "one row": ({"domain.motion": [{"type": "rotation_file", "file": "roll.dat", "centre": [0.5, 0]}]},
                {"roll.dat": "0 0\n"}, "domain.motion[0].file", "at least two rows"),
    "time not increasing": ({"domain.motion": [{"type": "rotation_file", "file": "roll.dat", "centre": [0.5, 0]}]},
                            {"roll.dat": "0 0\n0.005 1\n0.005 2\n0.01 0\n"}, "domain.motion[0].file",
                            "time must increase"),
    "NaN": ({"domain.motion": [{"type": "rotation_file", "file": "roll.dat", "centre": [0.5, 0]}]},
            {"roll.dat": "0 0\n0.005 nan\n0.01 0\n"}, "domain.motion[0].file", "not finite"),
    "text in the data": ({"domain.motion": [{"type": "rotation_file", "file": "roll.dat", "centre": [0.5, 0]}]},
                         {"roll.dat": "0 0\n0.005 one\n0.01 0\n"}, "domain.motion[0].file", "expected numbers"),
    "columns": ({"domain.motion": [{"type": "rotation_file", "file": "roll.dat", "centre": [0.5, 0]}]},
                {"roll.dat": "0 0 1\n0.01 0 1\n"}, "domain.motion[0].file", "expected 2 columns"),
    "too short for the run": ({"domain.motion": [{"type": "rotation_file", "file": "roll.dat", "centre": [0.5, 0]}],
                               "time.t_end": 0.5}, {"roll.dat": GOOD_SERIES}, "domain.motion[0].file", "covers"),
    "one column without axis": ({"domain.motion": [{"type": "translation_file", "file": "x.dat"}]},
                                {"x.dat": GOOD_SERIES}, "domain.motion[0].axis", "required"),
}


@pytest.mark.parametrize("name", sorted(BAD))
def test_bad_motion_is_refused_naming_the_key(tmp_path, name):
    changes, files, key, words = BAD[name]
    with pytest.raises(CaseError) as err:
        _load(tmp_path, changes, files)
    assert err.value.key == key, str(err.value)
    assert words in str(err.value)


def test_bad_motion_exits_2_and_writes_nothing(tmp_path, capsys):
    case_dir = write_case(tmp_path / "case", case_with(tiny_case(), {"domain.motion": [{**SWAY, "period": 0.0}]}))
    out = tmp_path / "out"
    assert cli.main(["run", str(case_dir), "--output", str(out)]) == 2
    err = capsys.readouterr().err
    assert "case.toml" in err and "domain.motion[0].period" in err
    assert not out.exists()


def test_a_plugin_that_does_not_move_its_walls_is_refused(tmp_path, capsys):
    """A boundary plugin written for fixed walls is not run on moving ones; a writer is."""
    case_dir = write_case(tmp_path / "case", case_with(tiny_case(), {"domain.motion": [SWAY],
                                                                    "plugins.use": ["free_surface", "vtu"]}))
    assert cli.main(["run", str(case_dir), "--output", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err
    assert "free_surface" in err and "domain.motion" in err and "moving walls" in err
