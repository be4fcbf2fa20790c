"""sphcore.testing, the test helpers of plugin authors: a case as data (tiny_case, case_with),
written as TOML that reads back as the same case, and given as a dict or as text alike."""

from __future__ import annotations

import datetime
import math

try:
    import tomllib
except ModuleNotFoundError:  # Python < 3.11
    import tomli as tomllib

import pytest

from sphcore.errors import CaseError
from sphcore.testing import TINY_CASE, case_toml, case_with, context, run_case, tiny_case, write_case

#: every kind of value the tests' cases hold, and the corners of TOML's syntax
EVERY_KIND = {
    "title": 'a "quoted" name \\ with a backslash',
    "lines": "one\ntwo\tand a tab, \x01 \x7f, é and 😀",
    "floats": [1e-6, 0.015625, 2.0**-13, 1e300, 5e-324, -0.0, 0.1 + 0.2],
    "special": [math.inf, -math.inf],
    "ints": [0, -3, 2**63 - 1],
    "flags": [True, False],
    "empty": [],
    "nested": [[0, 0], [1, 0.3], []],
    "inline": [{"name": "a", "point": [0.5, 0.1]}, 2],
    "when": datetime.datetime(2024, 1, 2, 3, 4, 5, tzinfo=datetime.timezone.utc),
    "day": datetime.date(2024, 1, 2),
    "domain": {
        "min": [0.0, 0.0],
        "walls": [{"shape": "box", "min": [0.3, 0.0], "motion": {"kind": "sine", "axes": [{"a": 1.0}]}},
                  {"shape": "polygon", "points": [[0, 0], [1, 0], [1, 1]]}],
    },
    "blocks": [{"min": [0.0, 0.0], "count": [4, 3], "kind": "sphere"}, {"min": [1.0, 1.0], "max": [2.0, 2.0]}],
    "probes": {"every_dt": 0.001, "pressure": [{"name": "P1", "point": [0.1, 0.0]}], "depth": [{"name": "H2"}]},
    "a.dotted key": {"and spaces": 1, "": "empty key"},
    "empty_table": {},
}


#: a case with probes (arrays of tables in a table), a finite wall and a plugin's table
PROBED = case_with(tiny_case(), {
    "domain.walls": [{"shape": "polygon", "points": [[0.6, 0.0], [0.8, 0.0], [0.7, 0.2]]}],
    "plugins.use": ["reflective", "probes"], "physics": {"sph": True, "gravity": [0.0, -9.81]},
    "probes": {"every_dt": 0.001, "pressure": [{"name": "P1", "point": [1.0, 0.05], "reference": "lobovsky_2014_sensor2",
                                                "H": 0.1}], "depth": [{"name": "H2", "point": [0.1, 0.0]}]},
    "reflective.cr": 0.0,
})


@pytest.mark.parametrize("case", [tiny_case(), PROBED, EVERY_KIND], ids=["tiny", "probed", "every-kind"])
def test_the_toml_written_reads_back_as_the_same_case(case):
    text = case_toml(case)
    back = tomllib.loads(text)
    assert back == case
    assert repr(back) == repr(case)  # the types too: 1 is not 1.0, True is not 1, -0.0 keeps its sign


def test_nan_is_written_as_toml_nan():
    assert math.isnan(tomllib.loads(case_toml({"x": {"v": math.nan}}))["x"]["v"])


def test_a_value_toml_cannot_hold_is_refused_naming_it():
    with pytest.raises(TypeError, match=r"time\.dt: None"):
        case_toml({"time": {"dt": None}})
    with pytest.raises(TypeError, match=r"blocks\.min\[1\]"):
        case_toml({"blocks": [{"min": [0.0, object()]}]})


def test_tiny_case_is_tiny_case_text_and_new_on_every_call():
    assert tiny_case() == tomllib.loads(TINY_CASE)
    case = tiny_case()
    case["time"]["t_end"] = 1.0
    assert tiny_case()["time"]["t_end"] == 0.002


def test_case_with_sets_replaces_and_removes_keys_and_leaves_the_base_alone():
    base = tiny_case()
    case = case_with(base, {
        "time.t_end": 0.01,  # a key
        "time.dt": 1e-4,  # a new key in a table
        "fluid.nu": 1e-6,  # a new table
        "blocks[0].count": [4, 3],  # in an entry of an array of tables
        "blocks[0].max": None,  # removed
        "domain": {"planes": [{"normal": [0.0, 1.0], "point": [0.0, 0.0]}]},  # a whole table
        "plugins.use": ["reflective"],
    })
    assert case == {
        "case": {"dim": 2},
        "domain": {"planes": [{"normal": [0.0, 1.0], "point": [0.0, 0.0]}]},
        "blocks": [{"min": [0.0, 0.0], "count": [4, 3]}],
        "particles": {"dx": 0.02},
        "time": {"t_end": 0.01, "dt": 1e-4},
        "plugins": {"use": ["reflective"]},
        "fluid": {"nu": 1e-6},
    }
    assert base == tiny_case()
    case["blocks"][0]["count"].append(5)
    assert "count" not in base["blocks"][0]
    # whole arrays, array entries and tables removed; text parsed first
    two = case_with(TINY_CASE, {"blocks": [*base["blocks"], {"min": [0.5, 0.5], "max": [0.6, 0.6]}]})
    assert len(two["blocks"]) == 2
    assert case_with(two, {"blocks[0]": None})["blocks"] == [{"min": [0.5, 0.5], "max": [0.6, 0.6]}]
    assert "domain" not in case_with(base, {"domain": None})


def test_case_with_refuses_a_key_that_does_not_fit_the_case():
    with pytest.raises(CaseError, match=r"case_with: blocks\[3\]\.max: index 3 out of range"):
        case_with(tiny_case(), {"blocks[3].max": [0.1, 0.1]})
    with pytest.raises(CaseError, match="not a table"):
        case_with(tiny_case(), {"time.t_end.x": 1.0})
    with pytest.raises(CaseError, match="case_with"):
        case_with(tiny_case(), {"time..t_end": 1.0})


def test_a_case_is_written_from_a_dict_or_from_text(tmp_path):
    text = "# a comment, kept\n" + TINY_CASE
    assert (write_case(tmp_path / "text", text) / "case.toml").read_text() == text
    assert (write_case(tmp_path / "old_keyword", text=text) / "case.toml").read_text() == text
    written = (write_case(tmp_path / "dict", tiny_case()) / "case.toml").read_text()
    assert written == case_toml(tiny_case()) and tomllib.loads(written) == tiny_case()
    # plugins and tables, on a text or a dict alike
    for i, case in enumerate((TINY_CASE, tiny_case())):
        d = write_case(tmp_path / f"with{i}", case, plugins=["reflective"], tables={"time": {"dt": 1e-4}})
        assert tomllib.loads((d / "case.toml").read_text()) == case_with(
            tiny_case(), {"plugins.use": ["reflective"], "time.dt": 1e-4})


def test_run_case_and_context_take_a_dict(tmp_path):
    summary = run_case(tmp_path, case_with(tiny_case(), {"time.t_end": 0.001}), plugins=["reflective"])
    assert summary["status"] == "completed" and summary["t"] == 0.001
    ctx = context(case_with(tiny_case(), {"blocks[0].max": [0.1, 0.1]}))
    assert ctx.state.n == 25 and ctx.case.config["time"]["t_end"] == 0.002
    assert context(TINY_CASE).state.n == context(tiny_case()).state.n == 100
