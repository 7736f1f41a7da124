"""Speed/accuracy chart and failure map datasets (speckle.imaging.speed) and their figures."""

from __future__ import annotations

import numpy as np
import pytest

from speckle.figures.speed import failure_map_figure, pareto_front, speed_accuracy_figure
from speckle.imaging.speed import FAILURE_CASES, failure_map, speed_accuracy


@pytest.fixture(scope="module")
def chart():
    return speed_accuracy(
        [
            {"n_pixels": 32, "n_lines": 4, "density": 2},
            {"n_pixels": 48, "n_lines": 3, "density": 1},
        ],
        ["direct", "nufft", "nufft32", "finufft", "psf", "auto"],
        [1e-2, 1e-6, 1e-9],
        pixel_size=8.0,
        k0_dk=10.0,
        shape="gaussian",
        fwhm_fraction=0.15,
        seed=3,
        repeat=1,
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


def test_figures_render(chart):
    fig = speed_accuracy_figure(chart)
    assert len(fig.axes) == 2
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
    assert len(failure_map_figure(fm).axes) == 3
