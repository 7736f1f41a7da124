"""The decorrelation scan (Paramspace rows of Fig. 6's scene) and its stacking.

Physics: once the coherent term has gone (rectangular spectrum, strain beyond
1/(k0/delta_k + 1/2)), the intensity correlation left is the incoherent floor of Campbell's
theorem, which depends on the scatterer density only (about (2/3)/(rho + 2/3) at small strain).
Each point is checked against it within three standard errors of a Pearson coefficient over
``n`` independent speckle cells, (1 - r^2)/sqrt(n), with n = A-lines x N / 2 (a rectangular
spectrum's speckle is two pixels long, Lc = 2 H/N, and A-lines are independent).
"""

from __future__ import annotations

import numpy as np
import pytest
import yaml

from speckle.figures.deformation import plot_scan, scan_combine, scan_point_data
from speckle.io import open_dataset, to_netcdf

SCAN = {"n_alines": 32, "strain": {"start": 0.0, "stop": 0.2, "num": 2}}


@pytest.fixture(scope="module")
def cfg(repo_root):
    return yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())


@pytest.fixture(scope="module")
def points(cfg):
    rows = [(1.0, 10.0, "rectangular"), (4.0, 10.0, "rectangular"), (4.0, 3.0, "gaussian")]
    return [
        scan_point_data(cfg["source"], cfg["fig6"], SCAN, 3, density=rho, k0_dk=k, spectrum=sp)
        for rho, k, sp in rows
    ]


def test_point_dims_and_unit_correlation_at_zero_strain(points):
    ds = points[0]
    assert dict(ds.intensity_correlation.sizes) == {
        "density": 1,
        "k0_dk": 1,
        "spectrum": 1,
        "strain": 2,
    }
    assert float(ds.intensity_correlation.isel(strain=0).squeeze()) == pytest.approx(1.0, abs=1e-12)
    assert ds.attrs["density"] == 1.0 and ds.attrs["spectrum_shape"] == "rectangular"


@pytest.mark.parametrize("index", [0, 1])
def test_decorrelated_images_keep_the_density_floor(cfg, points, index):
    ds = points[index].isel(strain=-1).squeeze()
    floor = float(ds.incoherent_floor_theory)
    rho = float(ds.density)
    assert float(ds.intensity_correlation_theory) == pytest.approx(floor, abs=1e-3)  # gamma = 0
    n_cells = SCAN["n_alines"] * cfg["source"]["n_pixels"] / 2
    se = (1 - floor**2) / np.sqrt(n_cells)
    assert abs(float(ds.intensity_correlation) - floor) < 3 * se
    # the floor falls with density: (2/3)/(rho + 2/3) up to the 1 - s scaling at s = 0.2
    assert floor == pytest.approx((2 / 3) / (rho + 2 / 3), rel=0.15)


def test_combine_stacks_rows_and_marks_missing_combinations(points):
    ds = scan_combine(points)
    assert dict(ds.intensity_correlation.sizes) == {
        "density": 2,
        "k0_dk": 2,
        "spectrum": 2,
        "strain": 2,
    }
    for p in points:
        key = {d: p[d].item() for d in ("density", "k0_dk", "spectrum")}
        np.testing.assert_array_equal(
            ds.intensity_correlation.sel(key).values, p.intensity_correlation.squeeze().values
        )
    assert np.isnan(ds.intensity_correlation.sel(density=1.0, k0_dk=3.0, spectrum="gaussian")).all()
    assert "density" not in ds.attrs and "spectrum_shape" not in ds.attrs  # they differ by row
    assert ds.attrs["n_pixels"] == points[0].attrs["n_pixels"] and ds.attrs["scan_points"] == 3
    fig = plot_scan(ds)
    assert len(fig.axes) == 2  # one panel per (spectrum, k0_dk) pair that has rows


def test_combine_after_netcdf_round_trip_keeps_labels(points, tmp_path):
    """As in the pipeline: points written and read back, stacked, written and read again."""
    paths = []
    for i, p in enumerate(reversed(points)):  # "gaussian" (8 characters) first
        paths.append(tmp_path / f"p{i}.nc")
        to_netcdf(p, paths[-1])
    to_netcdf(scan_combine([open_dataset(path) for path in paths]), tmp_path / "scan.nc")
    ds = open_dataset(tmp_path / "scan.nc")
    assert sorted(ds.spectrum.values.tolist()) == ["gaussian", "rectangular"]
    np.testing.assert_array_equal(
        ds.intensity_correlation.sel(density=4.0, k0_dk=10.0, spectrum="rectangular").values,
        points[1].intensity_correlation.squeeze().values,
    )


def test_combine_needs_points():
    with pytest.raises(ValueError, match="points"):
        scan_combine([])
