"""The ``probes`` plugin in runs: option errors, files and summary of a short run, restart,
the post-processing script; and the front gauge's choice of reference and wall height."""

from __future__ import annotations

import json
import math
import shutil
from pathlib import Path

import netCDF4
import numpy as np
import pytest
from conftest import make_sim, script, write_case, write_cut_netcdf

from sphcore import cli
from sphcore.errors import CaseError
from sphcore.run import runner
from sphcore.testing import case_with

ROOT = Path(__file__).resolve().parent.parent

# a 0.1 m x 0.1 m column (10 x 10 particles) in a 0.3 m tank: the water reaches the right
# wall at ~0.1 s; fixed dt = 2^-13 s so that a restart lands on the same steps
def tiny(tmp_path, name="tiny", t_end=0.15, every_dt=0.002, width=0.1, use=("reflective", "probes"), changes=None):
    """The case directory ``tmp_path``/``name``; ``changes``: more changes (case_with)."""
    case = {
        "case": {"dim": 2},
        "domain": {"min": [0.0, 0.0], "max": [0.3, 0.3]},
        "blocks": [{"min": [0.0, 0.0], "max": [width, 0.1]}],
        "particles": {"dx": 0.01},
        "time": {"t_end": t_end, "dt": 0.0001220703125},
        "plugins": {"use": list(use)},
        "front_gauge": {"wall_height": True},
        "probes": {
            "every_dt": every_dt,
            "pressure": [{"name": "right", "start": [0.3, 0.005], "end": [0.3, 0.015], "points": 3,
                          "reference": "lobovsky_2014_sensor2", "H": 0.1},
                         {"name": "back", "point": [0.0, 0.02], "mode": "particle"}],
            "depth": [{"name": "d1", "point": [0.05, 0.0]}],
        },
    }
    return write_case(tmp_path / name, case_with(case, changes or {}))


# ---------------------------------------------------------------------------- options


BAD = [
    (["probes.pressure=[{name = 'a', point = [0.5, 0.1]}]"], "probes.pressure[0].point", "outside the domain"),
    (["probes.pressure=[{name = 'a', start = [0.3, 0.1, 0.0], end = [0.3, 0.2]}]"], "probes.pressure[0].start",
     "2 components"),
    (["probes.pressure=[{name = 'a', start = [0.3, 0.1]}]"], "probes.pressure[0].end", "required"),
    (["probes.pressure=[{name = 'a', point = [0.3, 0.1], start = [0.3, 0.1], end = [0.3, 0.2]}]"],
     "probes.pressure[0].point", "not both"),
    (["probes.pressure=[{name = 'a', point = [0.3, 0.1], reference = 'buchner_1999', H = 0.1}]"],
     "probes.pressure[0].reference", "unknown reference"),
    (["probes.pressure=[{name = 'a', point = [0.3, 0.1], reference = 'buchner_2002_P1'}]"], "probes.pressure[0].H",
     "required"),
    (["probes.pressure=[{name = 'a', point = [0.3, 0.1], mode = 'ghost'}]"], "probes.pressure[0].mode", "one of"),
    (["probes.pressure=[{name = 'a b', point = [0.3, 0.1]}]"], "probes.pressure[0].name", "letters"),
    (["probes.pressure=[{name = 'a', point = [0.3, 0.1], colour = 1}]"], "probes.pressure[0].colour", "unknown key"),
    (["probes.depth=[{name = 'right', point = [0.1, 0.0]}]"], "probes.depth[0].name", "used twice"),
    (["probes.depth=[{name = 'x'}]"], "probes.depth[0].point", "required"),
    (["probes.pressure=[]", "probes.depth=[]"], "probes", "no probe"),
    (["probes.every_dt=-1.0"], "probes.every_dt", ">= 0"),
    (["probes.pressure=[{name = 'a', point = [0.3, 0.1], normal = [0.0, 0.0]}]"], "probes.pressure[0].normal",
     "nonzero"),
    (["probes.pressure=[{name = 'a', point = [0.3, 0.1], normal = [-1.0, 0.0, 0.0]}]"], "probes.pressure[0].normal",
     "2 components"),
    (["probes.pressure=[{name = 'a', point = [0.3, 0.1], mode = 'particle', normal = [-1.0, 0.0]}]"],
     "probes.pressure[0].normal", "wall-mode"),
]


@pytest.mark.parametrize("overrides, key, words", BAD, ids=[b[1] + ":" + b[2] for b in BAD])
def test_bad_probe_options_are_case_errors_naming_the_key(tmp_path, overrides, key, words):
    case_dir = tiny(tmp_path)
    with pytest.raises(CaseError) as info:
        runner.load(case_dir, [o.replace("'", '"') for o in overrides])
    assert info.value.key == key and words in info.value.expected
    # a bad value given with --set is blamed on --set; a table made empty by two of them on the case
    assert info.value.file == ("--set" if key != "probes" else str(case_dir / "case.toml"))


def test_sph_run_with_a_bad_probe_prints_one_line_and_exits_2(tmp_path, capsys):
    case_dir = tiny(tmp_path)
    status = cli.main(["run", str(case_dir), "--set", 'probes.pressure=[{name = "a", point = [0.31, 0.1]}]'])
    err = capsys.readouterr().err
    assert status == 2 and len(err.strip().splitlines()) == 1
    assert "probes.pressure[0].point" in err and "--set" in err  # the option that gave the value
    assert not (case_dir / "output").exists()


# ---------------------------------------------------------------------------- a short run


@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory):
    """0.25 s of the tiny dam break with probes every 2 ms (and the front gauge's wall height)."""
    tmp = tmp_path_factory.mktemp("probes")
    case_dir = tiny(tmp, t_end=0.25, use=["reflective", "probes", "front_gauge"])
    summary = runner.run(case_dir, output=tmp / "out", quiet=True)
    return tmp / "out", summary


def test_short_run_writes_probes_nc_and_csv_with_units_and_the_summary(tiny_run):
    out, summary = tiny_run
    assert summary["status"] == "completed"
    with netCDF4.Dataset(out / "probes.nc") as ds:
        ds.set_auto_maskandscale(False)
        n = len(ds.dimensions["time"])
        assert len(ds.dimensions["probe"]) == 3 and ds.data_model == "NETCDF3_64BIT_DATA"
        # the restart's check for a header cut short names every variable the header writes
        from sphcore_plugins.probes.store import HEADER_VARS
        assert set(ds.variables) == HEADER_VARS
        assert ds["pressure"].shape == ds["depth"].shape == ds["dry"].shape == (n, 3)
        assert ds["pressure"].units == "Pa" and ds["depth"].units == "m" and ds["time"].units == "s"
        assert ds["probe_start"].units == ds["probe_end"].units == "m"
        assert netCDF4.chartostring(ds["probe_name"][:]).tolist() == ["right", "back", "d1"]
        np.testing.assert_array_equal(ds["probe_start"][0], [0.3, 0.005])
        np.testing.assert_array_equal(ds["probe_end"][1], [0.0, 0.02])
        t, p, d, dry = ds["time"][:], ds["pressure"][:], ds["depth"][:], ds["dry"][:]
        assert ds.getncattr("rho0") == 1000.0 and ds.getncattr("g") == pytest.approx(9.81)
    # every 2 ms from 0 to 0.25 s: 126 samples (the final one at t_end included)
    assert n == 126 == summary["probes"]["probes_samples"]
    assert t[0] == 0 and t[-1] == pytest.approx(0.25) and (np.diff(t) > 0).all()
    assert np.isnan(p[:, 2]).all() and np.isnan(d[:, :2]).all() and np.isfinite(p[:, :2]).all()
    # the right wall is dry until the front arrives, then wet; the column at rest at t = 0
    assert dry[0, 0] == 1 and p[0, 0] == 0 and dry[-1, 0] == 0
    assert abs(p[0, 1] - 1000 * 9.81 * (0.1 - 0.02)) < 0.02 * 1000 * 9.81 * 0.1
    assert abs(d[0, 2] - 0.1) < 0.005 and d[-1, 2] < d[0, 2]
    csv = np.genfromtxt(out / "probes.csv", delimiter=",", names=True)
    assert csv.dtype.names == ("time_s", "right_pa", "back_pa", "d1_m") and len(csv) == n
    np.testing.assert_allclose(csv["right_pa"], p[:, 0], rtol=1e-9)
    s = json.loads((out / "summary.json").read_text())["probes"]  # the plugin's figures, under its name
    i = int(np.argmax(p[:, 0]))
    assert s["probe_right_peak_pa"] == pytest.approx(p[i, 0]) and s["probe_right_peak_t_s"] == pytest.approx(t[i])
    assert s["probe_back_peak_pa"] > 0 and "probe_back_in_band_fraction" not in s
    for key in ("in_band_fraction", "peak_rhogH", "band_peak_lo_rhogH", "band_peak_hi_rhogH", "peak_in_band"):
        assert f"probe_right_{key}" in s
    # the run's peak lies in Lobovsky's window t/T in [2, 7]: the same peak in rho g H units
    assert 2 <= s["probe_right_peak_t_s"] * math.sqrt(9.81 / 0.1) <= 7
    assert s["probe_right_peak_rhogH"] == pytest.approx(s["probe_right_peak_pa"] / (1000 * 9.81 * 0.1), rel=1e-9)
    assert s["probe_d1_max_m"] == pytest.approx(d[:, 2].max())


def test_wall_height_starts_at_the_column_height(tiny_run):
    out, summary = tiny_run
    csv = np.genfromtxt(out / "front.csv", delimiter=",", names=True)
    assert csv.dtype.names == ("t_s", "x_front_m", "eta_back_wall_m")
    assert abs(csv["eta_back_wall_m"][0] - 0.1) < 0.005  # dx / 2
    assert csv["eta_back_wall_m"][-1] < 0.09  # the column has fallen
    # a square column: no experiment applies, and the summary says why
    front = summary["front_gauge"]
    assert front["front_reference"].startswith("none: no reference applies")
    assert "rms_rel_err_martin_moyce_T3" not in front and "err_cruchaga_0.10s" not in front


def test_restart_trims_samples_after_the_checkpoint_and_continues_identically(tmp_path):
    """The part run stops at 40 steps; the full run's probes.nc (samples past the checkpoint
    included) is put in its place, as if the part run had written on before being killed. The
    restart drops those samples and writes the same ones again."""
    dt = 2.0**-13
    case_dir = tiny(tmp_path, t_end=80 * dt, every_dt=0.0)
    runner.run(case_dir, output=tmp_path / "full", quiet=True)
    runner.run(case_dir, output=tmp_path / "part", t_end=40 * dt, quiet=True)
    shutil.copy(tmp_path / "full" / "probes.nc", tmp_path / "part" / "probes.nc")
    rest = runner.run(case_dir, output=tmp_path / "part", restart=True, quiet=True)
    assert rest["status"] == "completed" and rest["segments"][-1]["steps"] == 40 and rest["steps"] == 80
    with netCDF4.Dataset(tmp_path / "full" / "probes.nc") as a, netCDF4.Dataset(tmp_path / "part" / "probes.nc") as b:
        for name in ("time", "step", "pressure", "depth", "dry"):
            np.testing.assert_array_equal(a[name][:], b[name][:])
        assert len(b.dimensions["time"]) == 81  # every step, 0..80, each once
    full = np.loadtxt(tmp_path / "full" / "probes.csv", delimiter=",", skiprows=1)
    part = np.loadtxt(tmp_path / "part" / "probes.csv", delimiter=",", skiprows=1)
    np.testing.assert_array_equal(full, part)


@pytest.mark.parametrize("cut", ["empty", "attributes only", "some variables"])
def test_a_probe_file_cut_while_its_header_was_written_is_written_anew(tmp_path, cut):
    """A run killed inside its first sample's header leaves probes.nc without samples: the
    restart treats it as absent (its first sample writes the file anew) instead of failing."""
    from sphcore_plugins.probes.store import FILE_NAME, ProbeFile

    def some_variables(ds):
        ds.createDimension("time", None)
        ds.createVariable("time", "f8", ("time",))
        ds.createVariable("step", "i8", ("time",))

    write_cut_netcdf(tmp_path / FILE_NAME, cut, some_variables if cut == "some variables" else None)
    assert ProbeFile(tmp_path).reopen(10) is None


def test_probes_without_output_directory_still_summarise(tmp_path):
    sim = make_sim(tiny(tmp_path, t_end=0.01))
    plugin = sim.pm.get_plugin("probes")
    sim.output()
    while not sim.done():
        sim.advance()
        sim.output()
    out = plugin.sph_summary(ctx=sim.ctx)
    assert out["probes_samples"] == len(plugin.times) >= 5 and "probe_back_peak_pa" in out


# ---------------------------------------------------------------------------- post-processing


def _postprocessing():
    return script("probes")


def test_postprocessing_plots_each_probe_and_prints_the_figures(tiny_run, capsys):
    out, summary = tiny_run
    before = {p.name: p.stat().st_mtime_ns for p in out.iterdir()}
    assert _postprocessing().main([str(out)]) == 0
    printed = capsys.readouterr().out
    for name in ("right", "back", "d1"):
        assert (out / f"probe_{name}.png").stat().st_size > 1000
    assert f"in_band_fraction             {summary['probes']['probe_right_in_band_fraction']:.4f}" in printed
    # nothing sph wrote was touched
    assert all(p.stat().st_mtime_ns == before[p.name] for p in out.iterdir() if p.name in before)


def test_postprocessing_prints_window_means_on_request(tiny_run, capsys):
    """--windows 0.5: the Lobovsky probe's window means over [2, 7] (ten rows), the same
    numbers as figures.window_means; a width that is not > 0 is refused with exit 2."""
    from sphcore_plugins.gauges import reference
    from sphcore_plugins.probes import figures

    out, _ = tiny_run
    assert _postprocessing().main([str(out), "--windows", "0.5"]) == 0
    printed = capsys.readouterr().out
    data = _postprocessing().read(out / "probes.nc")
    probe = next(p for p in data["probes"] if p["name"] == "right")
    tau = data["t"] * math.sqrt(data["g"] / probe["H"])
    rows = figures.window_means(tau, probe["values"] / (data["rho0"] * data["g"] * probe["H"]),
                                reference.series(probe["reference"]), "lobovsky", 0.5)
    assert [r[0] for r in rows] == pytest.approx(np.arange(2.0, 7.0, 0.5))
    assert f"{rows[0][0]:8.3f} {rows[0][1]:9.3f} {rows[0][2]:11.3f}" in printed
    assert _postprocessing().main([str(out), "--windows", "-1"]) == 2
    assert "--windows" in capsys.readouterr().err


@pytest.mark.parametrize("what", ["missing", "no_probes"])
def test_postprocessing_on_a_bad_path_prints_one_line_and_exits_2(tmp_path, capsys, what):
    path = tmp_path / "nothing" if what == "missing" else tmp_path
    assert _postprocessing().main([str(path)]) == 2
    captured = capsys.readouterr()
    assert len(captured.err.strip().splitlines()) == 1 and "Traceback" not in captured.err
    assert str(path) in captured.err


# ---------------------------------------------------------------------------- front gauge reference


def _front(tmp_path, width, reference, name="f"):
    case_dir = tiny(tmp_path, name=name, width=width, use=["front_gauge"],
                    changes={"front_gauge": {"reference": reference}, "domain.max": [0.3, 0.5]})
    return runner.load(case_dir)[1].get_plugin("front_gauge")


def test_front_gauge_auto_on_a_square_column_compares_with_nothing(tmp_path):
    gauge = _front(tmp_path, 0.1, "auto")
    assert gauge.references == () and "ratio 1" in gauge.reference_note


def test_front_gauge_refuses_martin_moyce_on_a_square_column(tmp_path):
    with pytest.raises(CaseError) as info:
        _front(tmp_path, 0.1, "martin_moyce_n2")
    assert info.value.key == "front_gauge.reference" and "twice as high" in info.value.expected


def test_front_gauge_auto_on_a_tall_column_and_on_the_seed_case(tmp_path):
    assert _front(tmp_path, 0.05, "auto").references == ("martin_moyce_n2",)
    with pytest.raises(CaseError) as info:
        _front(tmp_path, 0.05, "cruchaga", name="g")
    assert info.value.key == "front_gauge.reference"
    gauge = runner.load(ROOT / "cases" / "dam_break")[1].get_plugin("front_gauge")
    assert gauge.references == ("martin_moyce_n2", "cruchaga")


# ---------------------------------------------------------------------------- the shipped cases


@pytest.mark.parametrize("case, sensors", [
    ("dam_break_buchner", {"P1": 0.160, "P2": 0.584}),
    ("dam_break_lobovsky", {"sensor2": 0.015}),
])
def test_pressure_cases_put_their_sensors_on_the_downstream_wall_at_the_published_heights(case, sensors):
    from sphcore_plugins.gauges import reference

    case_, pm = runner.load(ROOT / "cases" / case)
    probes = {p.name: p for p in pm.get_plugin("probes").probes}
    wall = case_.config["domain"]["max"][0]
    for name, height in sensors.items():
        p = probes[name]
        assert p.mode == "wall" and (p.points[:, 0] == wall).all()
        assert p.points[:, 1].mean() == pytest.approx(height, abs=1e-9)
        series = reference.SERIES[p.reference]
        assert series.sensor_height_m == pytest.approx(height) and p.height == series.height_m
    # the column is H high and t_end reaches the end of the experiment's record
    block = case_.config["blocks"][0]
    assert block["max"][1] - block["min"][1] == pytest.approx(p.height)
    assert case_.config["time"]["t_end"] * math.sqrt(9.81 / p.height) >= 6.5


def test_wall_sensors_read_the_fluid_in_front_of_the_face_they_sit_on(tmp_path):
    """The face normal (into the fluid) is found from the wall plane or obstacle face the
    sensor lies on; a given normal is normalised; a sensor off every wall, or a particle-mode
    one, has none (it reads every particle around it)."""
    case_, pm = runner.load(ROOT / "cases" / "dam_break_obstacle_3d")
    probes = {p.name: p for p in pm.get_plugin("probes").probes}
    for name in ("P1", "P2", "P3", "P4"):  # on the box's face turned towards the water
        np.testing.assert_array_equal(probes[name].face_n, [1.0, 0.0, 0.0])
    case_, pm = runner.load(ROOT / "cases" / "dam_break_buchner")
    np.testing.assert_array_equal(pm.get_plugin("probes").probes[0].face_n, [-1.0, 0.0])  # the right wall
    case_dir = tiny(tmp_path)
    probes = {p.name: p for p in runner.load(case_dir)[1].get_plugin("probes").probes}
    np.testing.assert_array_equal(probes["right"].face_n, [-1.0, 0.0])
    assert probes["back"].face_n is None  # particle mode
    over = ["probes.pressure=[{name = 'mid', point = [0.15, 0.1]}, {name = 'n', point = [0.15, 0.1], "
            "normal = [3.0, 4.0]}]"]
    probes = {p.name: p for p in runner.load(case_dir, [o.replace("'", '"') for o in over])[1]
              .get_plugin("probes").probes}
    assert probes["mid"].face_n is None
    np.testing.assert_allclose(probes["n"].face_n, [0.6, 0.8], rtol=0, atol=1e-15)


def test_peer_series_scores_the_experiment_itself_as_exact(tmp_path, capsys):
    """Buchner's P1 points, written as a peer's series in s and Pa (CSV and JSON), score
    MAE 0 and a first rise equal to the experiment's; a bad key or file exits 2."""
    from sphcore_plugins.gauges import reference

    exp = reference.series("buchner_2002_P1")
    H, rho, g = 0.6, 1000.0, 9.81
    t, p = exp[:, 0] / np.sqrt(g / H), exp[:, 1] * rho * g * H
    csv = tmp_path / "peer.csv"
    csv.write_text("time_s,p_pa\n" + "\n".join(f"{float(a)!r},{float(b)!r}" for a, b in zip(t, p)))
    js = tmp_path / "peer.json"
    js.write_text(json.dumps({"P1": {"time": t.tolist(), "values": p.tolist()}}))
    peer = script("peer_series")
    for args in ([str(csv)], [str(js), "--key", "P1"]):
        assert peer.main(args + ["--reference", "buchner_2002_P1", "--H", "0.6"]) == 0
        out = dict(line.split(" = ") for line in capsys.readouterr().out.splitlines())
        assert float(out["mae_rhogH"]) < 1e-9
        assert abs(float(out["rise_dtau"])) < 1e-9
    assert peer.main([str(js), "--key", "nope", "--reference", "buchner_2002_P1", "--H", "0.6"]) == 2
    assert peer.main([str(tmp_path / "none.csv"), "--reference", "buchner_2002_P1", "--H", "0.6"]) == 2


def test_peer_series_reads_a_named_column_of_a_dimensionless_file(tmp_path, capsys):
    """A digitised figure (t sqrt(g/H), p/(rho g H), several curves side by side): --column
    picks one, --scaled reads the dimensionless form; the experiment scores 0, the
    experiment raised by 0.1 rho g H scores an MAE and offset of 0.1; a column the header
    does not name exits 2."""
    from sphcore_plugins.gauges import reference

    exp = reference.series("buchner_2002_P1")
    f = tmp_path / "figure.csv"
    f.write_text("time,exp,raised\n" + "\n".join(f"{a!r},{b!r},{b + 0.1!r}" for a, b in exp.tolist()))
    peer = script("peer_series")
    common = ["--reference", "buchner_2002_P1", "--H", "0.6", "--scaled"]
    for column, expected in (("exp", 0.0), ("raised", 0.1)):
        assert peer.main([str(f), "--column", column] + common) == 0
        out = dict(line.split(" = ") for line in capsys.readouterr().out.splitlines())
        assert abs(float(out["mae_rhogH"]) - expected) < 1e-9
        assert abs(float(out["offset_rhogH"]) - expected) < 1e-9
    assert peer.main([str(f), "--column", "nope"] + common) == 2
    assert "--column nope" in capsys.readouterr().err
