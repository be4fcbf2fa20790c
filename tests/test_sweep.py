"""``sph sweep``: grid expansion and value parsing, up-front validation, and real sweeps on
Dask whose sweep.nc must agree with every variant's own summary.json.

The real sweeps run a 10 x 10 block of water for a few milliseconds; each variant is a
fresh Python process (see sphcore/sweep/task.py), about 2-4 s on two cores.
"""

from __future__ import annotations

import importlib.util
import json
import math
import sys

import numpy as np
import pytest
from conftest import write_case

from sphcore import cli
from sphcore.errors import CaseError
from sphcore.sweep import command as sweep
from sphcore.sweep.grid import expand, fold, key_text, parse_key, parse_set, parse_vary, split_values
from sphcore.sweep.results import grid, pareto_mask

TINY = {
    "case": {"name": "tiny", "dim": 2},
    "domain": {"min": [0.0, 0.0], "max": [0.2, 0.2]},
    "blocks": [{"min": [0.0, 0.0], "max": [0.1, 0.1]}],
    "particles": {"dx": 0.01},
    "viscosity": {"alpha": 0.1},
    "time": {"t_end": 0.01},
    "plugins": {"use": ["reflective"]},
}


@pytest.fixture
def tiny(tmp_path):
    return write_case(tmp_path / "tiny", TINY)


# -- value parsing and the grid ------------------------------------------------------------

@pytest.mark.parametrize("text, items", [
    ("0.05,0.1,0.2", ["0.05", "0.1", "0.2"]),
    ('["ghost"],["reflective","ghost"]', ['["ghost"]', '["reflective","ghost"]']),
    ("[18, 36], [25, 50]", ["[18, 36]", "[25, 50]"]),
    ('{ min = [0, 0], count = [2, 3] },{ min = [1, 1], count = [4, 5] }',
     ["{ min = [0, 0], count = [2, 3] }", "{ min = [1, 1], count = [4, 5] }"]),
    ('"a,b",\'c,d\',"e\\",f"', ['"a,b"', "'c,d'", '"e\\",f"']),  # commas inside strings stay
    ("[[1, 2], [3, 4]],[[5]]", ["[[1, 2], [3, 4]]", "[[5]]"]),
    ("cubic_spline", ["cubic_spline"]),
])
def test_split_values_at_bracket_depth_zero(text, items):
    assert split_values(text) == items


@pytest.mark.parametrize("text, why", [("[1,2", "unclosed bracket"), ("1,2]", "unbalanced"),
                                       ('"a,b', "unclosed quote"), ("1,,2", "empty value"), ("1,", "empty value")])
def test_split_values_refuses_malformed_lists(text, why):
    with pytest.raises(CaseError, match=why) as e:
        split_values(text, "time.cfl")
    assert e.value.key == "time.cfl"


def test_values_are_read_like_set():
    axis = parse_vary('plugins.use=["ghost"],["reflective","ghost"]')
    assert axis.keys == ["plugins.use"] and axis.points == ((["ghost"],), (["reflective", "ghost"],))
    assert parse_vary("time.cfl=0.05,1,2e-1").points == ((0.05,), (1,), (0.2,))
    assert parse_vary("kernel.name=cubic_spline,wendland_c2").points == (("cubic_spline",), ("wendland_c2",))
    assert parse_vary("physics.sph=true,false").points == ((True,), (False,))
    assert parse_set("blocks[0].count=[18, 36]") == (("blocks", 0, "count"), [18, 36])


def test_linked_keys_take_one_array_per_variant():
    axis = parse_vary("particles.dx,time.t_end=[0.01,0.2],[0.005,0.1]")
    assert axis.keys == ["particles.dx", "time.t_end"]
    assert axis.points == ((0.01, 0.2), (0.005, 0.1))
    with pytest.raises(CaseError, match="one TOML array of 2 values") as e:
        parse_vary("particles.dx,time.t_end=[0.01,0.2],0.005")
    assert e.value.key == "particles.dx,time.t_end"


@pytest.mark.parametrize("text", ["blocks[0].count", "domain.planes[1].normal", "time.cfl", "a[0][1].b"])
def test_keys_with_indices_round_trip(text):
    assert key_text(parse_key(text)) == text


@pytest.mark.parametrize("text", ["cfl", "time.", "time..cfl", "blocks[x].count", "time.cfl ok", "blocks[0"])
def test_malformed_keys_are_named(text):
    with pytest.raises(CaseError) as e:
        parse_vary(f"{text}=1,2")
    assert e.value.key == text


def test_grid_is_the_cartesian_product_first_axis_slowest():
    axes = [parse_vary("time.cfl=0.1,0.2,0.4"), parse_vary('plugins.use=["ghost"],["reflective"]')]
    variants = expand(axes, ["viscosity.alpha=0.2"])
    assert [v.index for v in variants] == list(range(6))
    assert [(v.values["time.cfl"], v.values["plugins.use"]) for v in variants] == [
        (c, p) for c in (0.1, 0.2, 0.4) for p in (["ghost"], ["reflective"])]
    assert variants[3].name == "003_cfl=0.2_use=reflective"
    assert len({v.name for v in variants}) == 6
    assert variants[0].overrides[0] == (("viscosity", "alpha"), 0.2)  # --set first, then the variant
    assert expand([]) [0].name == "000"  # no --vary: the case itself
    with pytest.raises(CaseError, match="varied twice"):
        expand([parse_vary("time.cfl=1,2"), parse_vary("time.cfl=3")])


def test_labels_fall_back_to_full_keys_when_leaves_collide():
    variants = expand([parse_vary("reflective.cr=0,1"), parse_vary("ghost.cr=0.5")])
    assert variants[1].name == "001_reflective.cr=1_ghost.cr=0.5"


def test_fold_turns_indexed_keys_into_whole_array_overrides():
    raw = {"blocks": [{"min": [0, 0], "count": [36, 71]}, {"min": [1, 1], "max": [2, 2]}],
           "time": {"t_end": 1.0}}
    out = fold(raw, [(("time", "cfl"), 0.1), (("blocks", 0, "count"), [18, 36]), (("blocks", 1, "max"), [3, 3])])
    assert out[0] == (["time", "cfl"], 0.1)
    assert out[1] == (["blocks"], [{"min": [0, 0], "count": [18, 36]}, {"min": [1, 1], "max": [2, 2]}])
    assert out[2][1][0]["count"] == [18, 36] and out[2][1][1]["max"] == [3, 3]  # edits accumulate
    assert raw["blocks"][0]["count"] == [36, 71]  # the case as read is untouched
    with pytest.raises(CaseError, match="index 2 out of range: the case has 2 blocks entries") as e:
        fold(raw, [(("blocks", 2, "count"), [1, 1])])
    assert e.value.key == "blocks[2].count"
    with pytest.raises(CaseError, match="time is not an array of tables"):
        fold(raw, [(("time", 0, "x"), 1)])


def test_pareto_mask():
    cost = [1.0, 2.0, 3.0, 4.0, 2.5, math.nan]
    err = [0.5, 0.2, 0.3, 0.1, 0.2, 0.0]
    assert pareto_mask(cost, err).tolist() == [True, True, False, True, False, False]


# -- validation before anything runs ---------------------------------------------------------

@pytest.fixture
def no_run(monkeypatch):
    """Fail the test if a sweep gets as far as running anything."""
    def refuse(*a, **k):
        raise AssertionError("a variant ran")

    monkeypatch.setattr(sweep, "run", refuse)
    monkeypatch.setattr(sweep, "run_variant", refuse)


@pytest.mark.parametrize("vary, key", [
    ("viscosity.alpa=0.1,0.2", "viscosity.alpa"),
    ("tme.cfl=0.1,0.2", "tme"),
    ("time.cfl=0.2,-1", "time.cfl"),
    ("blocks[3].count=[2,2]", "blocks[3].count"),
    ("blocks[0].count=[2,2]", "blocks[0].count"),  # count and max together
    ("particles.dx=0.01,0.5", "blocks[0]"),  # no particle fits at that spacing
    ("time.cfl=[0.1,0.2", "time.cfl"),
])
def test_a_bad_variant_exits_2_naming_the_key_before_any_run(tiny, tmp_path, capsys, no_run, vary, key):
    out = tmp_path / "sweep_out"
    status = cli.main(["sweep", str(tiny), "--vary", "viscosity.alpha=0.1,0.2", "--vary", vary, "--output", str(out)])
    err = capsys.readouterr().err
    assert status == 2
    assert err.startswith("sph: error: ") and key in err, err
    assert not out.exists()


def test_dry_run_lists_valid_variants(tiny, capsys, no_run):
    assert cli.main(["sweep", str(tiny), "--vary", "time.cfl=0.1,0.2", "--vary", "blocks[0].max=[0.1,0.1],[0.05,0.1]",
                     "--dry-run"]) == 0
    out = capsys.readouterr().out
    assert "4 variants" in out and "003_cfl=0.2_max=0.05-0.1" in out


def test_missing_dask_names_the_extra(tiny, tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "distributed", None)  # import distributed -> ImportError
    status = cli.main(["sweep", str(tiny), "--vary", "time.cfl=0.1,0.2", "--output", str(tmp_path / "o")])
    assert status == 2
    assert 'pip install -e ".[sweep]"' in capsys.readouterr().err
    assert not (tmp_path / "o").exists()


# -- real sweeps -------------------------------------------------------------------------------

def _assert_matches_summaries(ds, out):
    """Every variable of sweep.nc equals the variant's own summary.json (NaN where absent)."""
    numeric = [k for k in ds.data_vars if k not in ("status", "message", "task_wall_s")]
    for i, name in enumerate(ds["variant"].values):
        s = json.loads((out / name / "summary.json").read_text())
        flat = {}
        for key, value in s.items():  # plugin figures and counters are flattened to table.key
            flat.update({f"{key}.{k}": v for k, v in value.items()} if isinstance(value, dict) else {key: value})
        assert ds["status"].values[i] == s["status"] and ds["message"].values[i] == s["message"]
        for k in numeric:
            want = flat.get(k, math.nan)
            got = float(ds[k].values[i])
            assert (math.isnan(got) and math.isnan(want)) or got == want, (name, k, got, want)
        assert not [k for k, v in flat.items() if isinstance(v, (int, float)) and k not in ds]


needs_dask = pytest.mark.skipif(importlib.util.find_spec("distributed") is None,
                                reason='needs Dask: pip install -e ".[test]" (or ".[sweep]")')


@needs_dask
def test_sweep_on_a_local_process_cluster(tiny, tmp_path, capsys):
    """2 x 2 variants on 2 worker processes; density bound 1.0001 rho0 with SPH on is unstable
    at the first step (hydrostatic start), and must be recorded while the others complete."""
    import xarray as xr

    out = tmp_path / "sw"
    status = cli.main(["sweep", str(tiny), "--vary", "physics.sph=true,false", "--vary", "checks.rho_max=1.5,1.0001",
                       "--set", 'plugins.use=["reflective","pressure_gauge"]', "--workers", "2",
                       "--output", str(out), "--progress", "log"])
    cap = capsys.readouterr()
    assert status == 0, cap.err
    ds = xr.open_dataset(out / "sweep.nc").load()
    assert ds.attrs["cluster"] == "local cluster of 2 worker processes, 1 thread each"
    assert ds["physics.sph"].values.tolist() == [True, True, False, False]
    assert ds["checks.rho_max"].values.tolist() == [1.5, 1.0001, 1.5, 1.0001]
    assert ds["status"].values.tolist() == ["completed", "unstable", "completed", "completed"]
    assert "density above the upper bound" in ds["message"].values[1]
    assert ds["t"].values[0] == pytest.approx(0.01) and ds["t"].values[1] < 0.01
    _assert_matches_summaries(ds, out)
    assert ds.attrs["error_key"] == "pressure_gauge.pressure_max_layer_err"
    assert (out / "pareto.png").stat().st_size > 1000
    g = grid(ds)
    assert g["status"].dims == ("physics.sph", "checks.rho_max")
    assert g["status"].sel({"physics.sph": True, "checks.rho_max": 1.0001}).item() == "unstable"
    assert "[sweep] 4/4" in cap.err and "unstable" in cap.out  # progress lines, then the table


@needs_dask
def test_sweep_in_process_cluster_with_linked_and_indexed_keys(tiny, tmp_path):
    """Threads instead of processes (the variant still runs in its own process); a linked
    pair (dx with the block's corner) and a key inside an array of tables."""
    out = tmp_path / "sw"
    p = sweep.plan(tiny, ["particles.dx,blocks[0].max=[0.02,[0.1,0.06]],[0.01,[0.05,0.05]]"],
                   ["physics.sph=false", "time.dt=0.001"], t_end=0.005)
    ds = sweep.run(p, out, workers=2, processes=False, progress="off")
    assert ds["status"].values.tolist() == ["completed", "completed"]
    assert ds["n_particles"].values.tolist() == [5 * 3, 5 * 5]
    assert ds["blocks[0].max"].values.tolist() == ["[0.1, 0.06]", "[0.05, 0.05]"]
    assert ds["steps"].values.tolist() == [5, 5]
    assert "pareto.png" not in {f.name for f in out.iterdir()}  # no error key in this case's summary
    _assert_matches_summaries(ds, out)
    # a second sweep into the same directory needs --overwrite
    with pytest.raises(Exception, match="--overwrite"):
        sweep.run(p, out, workers=1, processes=False, progress="off")
    np.testing.assert_array_equal(sweep.run(p, out, workers=1, processes=False, progress="off",
                                            overwrite=True)["n_particles"].values, [15, 25])


@needs_dask
def test_sweep_on_a_given_scheduler(tiny, tmp_path, capsys):
    """--scheduler ADDRESS: the sweep uses that cluster and leaves it running."""
    import xarray as xr
    from distributed import Client, LocalCluster

    out = tmp_path / "sw"
    with LocalCluster(n_workers=1, threads_per_worker=1, processes=False, dashboard_address=None) as cluster:
        address = cluster.scheduler_address
        assert cli.main(["sweep", str(tiny), "--vary", "time.dt=0.001,0.0005", "--set", "physics.sph=false",
                         "--scheduler", address, "--workers", "2", "--output", str(out)]) == 2
        assert "--workers" in capsys.readouterr().err and not out.exists()
        assert cli.main(["sweep", str(tiny), "--vary", "time.dt=0.001,0.0005", "--set", "physics.sph=false",
                         "--scheduler", address, "--output", str(out), "--progress", "off"]) == 0
        with Client(address) as client:  # still up
            assert len(client.scheduler_info()["workers"]) == 1
    ds = xr.open_dataset(out / "sweep.nc")
    assert ds.attrs["cluster"] == f"scheduler {address}"
    assert ds["steps"].values.tolist() == [10, 20]
