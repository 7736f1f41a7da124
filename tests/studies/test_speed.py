"""Speed/accuracy chart and failure map datasets (speckle.studies.speed) and their figures."""

from __future__ import annotations

import copy
import shutil

import numpy as np
import pytest
import xarray as xr
import yaml
from snakemake.exceptions import WorkflowError
from snakemake.utils import validate
from workflow_run import CI_CONFIG, IGNORE, snakemake

from speckle.figures.speed import pareto_front, plot_failure_map, plot_speed_accuracy

# private: the beam methods auto chooses from
from speckle.imaging._methods.beam_nufft import BEAM_AUTO_CANDIDATES
from speckle.imaging.beam import BEAM_METHODS
from speckle.studies.speed import (
    FAILURE_CASES,
    beam_speed_accuracy,
    failure_map,
    random_beam_scene,
    speed_accuracy,
)

BEAM_SIZES = [
    {"n_pixels": 32, "n_lines": 8, "density": 2, "waist_pitch": 2.0},
    {"n_pixels": 48, "n_lines": 6, "density": 1, "waist_pitch": 1.0},
]
BEAM_TOLS = [1e-2, 1e-6, 1e-9]
#: Source and timing of both test charts.
CHART_SOURCE = dict(
    pixel_size=8.0, k0_dk=10.0, shape="gaussian", fwhm_fraction=0.15, seed=3, repeat=1
)


@pytest.fixture(scope="module")
def chart():
    return speed_accuracy(
        [
            {"n_pixels": 32, "n_lines": 4, "density": 2},
            {"n_pixels": 48, "n_lines": 3, "density": 1},
        ],
        ["direct", "nufft", "nufft32", "finufft", "psf", "auto"],
        [1e-2, 1e-6, 1e-9],
        **CHART_SOURCE,
    )


@pytest.fixture(scope="module")
def beam_chart():
    return beam_speed_accuracy(
        BEAM_SIZES,
        ["direct", "nufft", "nufft32", "finufft", "auto"],
        BEAM_TOLS,
        **CHART_SOURCE,
    )


def test_chart_errors_within_knob(chart):
    assert dict(chart.sizes) == {"scene": 2, "method": 6, "tol": 3}
    err = chart["error"]
    ok = err.notnull()
    assert bool((err.where(ok, 0) <= chart["tol"]).all())
    # nufft32 refuses 1e-9 (below its float32 floor): NaN, not a wrong number
    assert bool(err.sel({"method": "nufft32", "tol": 1e-9}).isnull().all())
    assert bool((chart["time"].sel({"method": "direct"}) > 0).all())
    assert set(np.unique(chart["chosen"].values)) <= {"direct", "nufft", "nufft32", "psf"}


def test_pareto_front():
    t = np.array([1.0, 2.0, 3.0, 0.5, 4.0])
    e = np.array([1e-3, 1e-6, 1e-5, 1e-2, np.nan])
    assert pareto_front(t, e).tolist() == [3, 0, 1]


def test_failure_map_detects_each_failure():
    fm = failure_map(
        [32, 96],
        [1.0, 4.0],
        [0.0, 300.0],
        base={"n_pixels": 64, "density": 2.0, "k0_dk": 10.0},
        n_lines=4,
        pixel_size=8.0,
        fwhm_fraction=0.15,
        seed=5,
        dask={"scheduler": "synchronous"},
    )
    labels = [c[0] for c in FAILURE_CASES]
    assert fm["case"].values.tolist() == labels
    err, pred = fm["error_vs_k0_dk"], fm["predicted_vs_k0_dk"]
    naive = "float32 naive phase"
    # naive float32 phase: exact at k0 = 0, then > 1e-4 at k0/dk = 300, as predicted (x2)
    assert float(err.sel(case=naive, k0_dk=0.0)) < 1e-12
    assert float(err.sel(case=naive, k0_dk=300.0)) > 1e-4
    np.testing.assert_allclose(
        err.sel(case=naive, k0_dk=300.0), pred.sel(case=naive, k0_dk=300.0), rtol=1.0
    )
    # the safe float32 NUFFT does not care about k0
    assert float(err.sel(case="nufft32 tol=1e-5", k0_dk=300.0)) < 1e-5
    # truncated PSF: fails on a rectangular spectrum (~0.1), fine on a smooth one
    for axis in ("n_pixels", "density", "k0_dk"):
        e = fm[f"error_vs_{axis}"]
        assert bool((e.sel(case="psf hw=8 rectangular") > 0.05).all())
        assert bool((e.sel(case="psf hw=8 gaussian") < 1e-2).all())
        for case, _, tol in FAILURE_CASES[:2]:  # nufft at its tol, loose or tight
            assert bool((e.sel(case=case) <= tol).all())


def test_beam_chart_layout_and_units(beam_chart):
    ds = beam_chart
    assert dict(ds.sizes) == {"scene": 2, "method": 5, "tol": 3}
    assert ds["method"].values.tolist() == ["direct", "nufft", "nufft32", "finufft", "auto"]
    assert ds["tol"].values.tolist() == BEAM_TOLS
    for key in ("n_pixels", "n_lines", "density", "waist_pitch"):
        assert ds[key].values.tolist() == [sz[key] for sz in BEAM_SIZES]
    # round(density * N * L) scatterers in each shared scene
    assert ds["n_scatterers"].values.tolist() == [2 * 32 * 8, 1 * 48 * 6]
    units = {"time": "s", "error": "1", "rate": "1/s", "density": "1/(pixel line)"}
    assert {k: ds[k].attrs["units"] for k in units} == units
    assert ds["waist_pitch"].attrs["units"] == "1"
    assert ds.attrs["pitch_um"] == ds.attrs["pixel_size_um"] == 8.0
    assert "all lines" in ds.attrs["reference"]
    np.testing.assert_allclose(ds["rate"], ds["n_scatterers"] / ds["time"])


def test_beam_chart_errors_within_tol(beam_chart):
    err = beam_chart["error"]
    # the exact reference: error 0 at every tol, timed
    assert bool((err.sel({"method": "direct"}) == 0).all())
    assert bool((beam_chart["time"].sel({"method": "direct"}) > 0).all())
    # tol bounds the relative l2 error of every fast method where it runs
    fast = err.drop_sel({"method": "direct"})
    assert bool((fast.where(fast.notnull(), 0) <= fast["tol"]).all())
    # nufft, finufft and auto run at every tol; nufft32 refuses 1e-9 (float32 floor): NaN
    assert bool(err.sel({"method": ["nufft", "finufft", "auto"]}).notnull().all())
    assert bool(err.sel({"method": "nufft32", "tol": 1e-9}).isnull().all())
    assert bool(err.sel({"method": "nufft32", "tol": 1e-2}).notnull().all())
    # auto runs the method it chooses: the same B-scan, so the same error
    for i in range(beam_chart.sizes["scene"]):
        for tol in BEAM_TOLS:
            pick = str(beam_chart["chosen"].sel(tol=tol).values[i])
            assert pick in BEAM_AUTO_CANDIDATES
            sc = err.isel(scene=i).sel(tol=tol)
            assert float(sc.sel({"method": "auto"})) == float(sc.sel({"method": pick}))


def test_random_beam_scene_is_the_documented_scene():
    z, x, a, lines, depth = random_beam_scene(16, 5, 3.0, pitch=4.0, pixel_size=8.0, seed=7)
    assert depth == 16 * 8.0
    assert z.shape == x.shape == a.shape == (3 * 16 * 5,)
    np.testing.assert_array_equal(lines, 4.0 * np.arange(5))
    assert z.min() >= 0 and z.max() < depth
    assert x.min() >= -2.0 and x.max() < 4.0 * 4.5
    again = random_beam_scene(16, 5, 3.0, pitch=4.0, pixel_size=8.0, seed=7)
    for u, v in zip((z, x, a), again[:3], strict=True):
        np.testing.assert_array_equal(u, v)
    other = random_beam_scene(16, 5, 3.0, pitch=4.0, pixel_size=8.0, seed=8)
    assert not np.array_equal(z, other[0])


def test_schema_beam_section(repo_root):
    """The schema lists the registered beam methods and refuses bad beam scenes by key."""
    path = repo_root / "workflow/schemas/config.schema.yaml"
    schema = yaml.safe_load(path.read_text())
    beam = schema["properties"]["speed_accuracy"]["properties"]["beam"]
    assert sorted(beam["properties"]["methods"]["items"]["enum"]) == sorted(BEAM_METHODS)
    cfg = yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())
    validate(copy.deepcopy(cfg), str(path))
    size = cfg["speed_accuracy"]["beam"]["sizes"][0]
    for key, value in (("waist_pitch", 0), ("density", -1.0), ("n_lines", 0)):
        bad = copy.deepcopy(cfg)
        bad["speed_accuracy"]["beam"]["sizes"][0] = {**size, key: value}
        with pytest.raises(WorkflowError, match=key):
            validate(bad, str(path))
    bad = copy.deepcopy(cfg)
    bad["speed_accuracy"]["beam"]["methods"] = ["psf"]  # an A-scan method only
    with pytest.raises(WorkflowError, match="psf"):
        validate(bad, str(path))


def test_figures_render(chart, beam_chart):
    fig = plot_speed_accuracy(chart)
    assert len(fig.axes) == 2
    # a second row: one panel per beam scene
    assert len(plot_speed_accuracy(chart, beam_chart).axes) == 4
    one = beam_chart.isel(scene=[0])
    assert len(plot_speed_accuracy(chart, one).axes) == 3
    fm = failure_map(
        [32],
        [1.0],
        [1.0],
        base={"n_pixels": 32, "density": 1.0, "k0_dk": 1.0},
        n_lines=1,
        pixel_size=8.0,
        fwhm_fraction=0.15,
        seed=1,
        dask={"scheduler": "synchronous"},
    )
    assert len(plot_failure_map(fm).axes) == 3


@pytest.mark.pipeline
@pytest.mark.slow
def test_rule_writes_the_beam_chart(tmp_path, repo_root):
    """The rule, through Snakemake on the CI config: the beam chart exists, opens, is right."""
    repo = tmp_path / "repo"
    shutil.copytree(repo_root, repo, ignore=IGNORE)
    (repo / "out.yaml").write_text(yaml.safe_dump({"results": "results_speed"}))
    target = "results_speed/speed/beam_speed_accuracy.nc"
    snakemake(repo, target, "--cores", "2", "--configfile", CI_CONFIG, "out.yaml")
    results = repo / "results_speed" / "speed"
    assert (results / "speed_accuracy.png").stat().st_size > 0
    ci = yaml.safe_load((repo / CI_CONFIG).read_text())["speed_accuracy"]
    default = yaml.safe_load((repo / "workflow/config/config.yaml").read_text())
    with xr.open_dataset(results / "beam_speed_accuracy.nc", engine="netcdf4") as ds:
        assert ds.sizes["scene"] == len(ci["beam"]["sizes"])
        assert ds["method"].values.tolist() == default["speed_accuracy"]["beam"]["methods"]
        assert ds["tol"].values.tolist() == ci["tols"]
        assert ds["n_lines"].values.tolist() == [s["n_lines"] for s in ci["beam"]["sizes"]]
        err = ds["error"].load()
        assert bool((err.where(err.notnull(), 0) <= ds["tol"]).all())
        assert bool((err.sel({"method": "direct"}) == 0).all())
    with xr.open_dataset(results / "speed_accuracy.nc", engine="netcdf4") as ds:
        assert ds.sizes["scene"] == len(ci["sizes"])
