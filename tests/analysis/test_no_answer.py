"""Estimators and metrics with no answer return NaN and say why (issue 36), in the modules
statistics, dynamics, sparse, filters, image_quality and compounding."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import speckle


def test_contrast_of_zero_intensity_is_nan_with_a_warning():
    with pytest.warns(RuntimeWarning, match="mean intensity is zero"):
        assert np.isnan(speckle.speckle_contrast(np.zeros(4)))
    img = xr.DataArray(np.vstack([np.zeros(4), [1.0, 3.0, 1.0, 3.0]]), dims=("depth", "x"))
    with pytest.warns(RuntimeWarning, match="in 1 place"):
        c = speckle.speckle_contrast(img, dim="x")
    assert np.isnan(c[0]) and float(c[1]) == pytest.approx(0.5)


def test_rectangular_spectrum_moments_are_the_closed_form():
    from speckle.analysis.statistics import spectrum_moments

    n = 7
    s = np.ones(n)
    assert spectrum_moments(n) == (float(n), float(np.sum(np.convolve(s, s) ** 2)))
    assert spectrum_moments(10**12)[0] == 1e12  # nothing allocated
