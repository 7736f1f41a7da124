"""Figs. 3 and 4 data builders: labelled sweep output, reproducibility, measured fallback."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from speckle.analysis.statistics import contrast_theory
from speckle.figures import histograms

SCENE = {"n_alines": 8, "k0_dk": 10.0, "seed": 3, "n_pixels": 32, "pixel_size": 8.0}


@pytest.fixture(scope="module")
def fig3():
    return histograms.density_histograms(
        [0.5, 4.0], dask={"scheduler": "threads", "n_workers": 2}, bins=20, **SCENE
    )


def test_density_sweep_dataset(fig3):
    assert fig3.amplitude_density.dims == ("density", "bin")
    np.testing.assert_allclose(fig3.density, [0.5, 4.0])
    assert float(fig3.rayleigh_sigma_shared) == float(fig3.rayleigh_sigma.sel(density=4.0))
    np.testing.assert_allclose(fig3.contrast_theory, contrast_theory(np.array([0.5, 4.0]), 32))
    area = (fig3.amplitude_density * (fig3.bin_upper - fig3.bin_lower)).sum("bin")
    assert np.all(area <= 1.0 + 1e-12) and np.all(area > 0.95)


def test_sweep_does_not_depend_on_the_scheduler(fig3):
    serial = histograms.density_histograms(
        [0.5, 4.0], dask={"scheduler": "synchronous"}, bins=20, **SCENE
    )
    xr.testing.assert_identical(serial.drop_attrs(), fig3.drop_attrs())


def test_fig4_without_measured_image_says_so():
    sim = histograms.simulated_panels(4.0, floor=0.01, bins=20, **SCENE)
    ds = histograms.fig4_dataset(sim, None, "not configured")
    assert ds.attrs["measured"] == "not available: not configured"
    assert "measured_skewness" not in ds
    # the floor adds 0.01 <I> and leaves Var I alone: contrast theory C/(1 + b)
    assert float(ds.sim_contrast_theory) == pytest.approx(contrast_theory(4.0, 32) / 1.01)
    fig = histograms.plot_fig4(ds)
    assert len(fig.axes) == 6
    assert (
        len(
            histograms.plot_density_histograms(
                histograms.density_histograms([4.0], bins=10, **SCENE)
            ).axes
        )
        == 3
    )
