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


def test_split_spectrum_refuses_a_kurtosis_below_one_and_takes_the_dense_limit():
    w = speckle.subband_windows(16, 2)
    with pytest.raises(ValueError, match="kurtosis"):
        speckle.split_spectrum_contrast(w, 4.0, kurtosis=0.5)  # E|a|^4 >= (E|a|^2)^2
    dense = speckle.split_spectrum_contrast(w, float("inf"))
    assert dense == pytest.approx(speckle.compounded_contrast(speckle.window_correlation(w)))
    with pytest.raises(ValueError, match="no power"):
        speckle.window_correlation(np.vstack([w[0], np.zeros(16)]))


def test_image_metrics_without_an_answer_warn():
    from speckle.analysis import image_quality as iq

    mask = np.ones(4, bool)
    with pytest.warns(RuntimeWarning, match="mean intensity in the mask is zero"):
        assert np.isnan(iq.contrast(np.zeros(4), mask))
    with pytest.warns(RuntimeWarning, match="all zero"):
        assert np.isnan(speckle.enl(np.zeros(4), mask))
    with pytest.warns(RuntimeWarning, match="constant"):
        assert speckle.enl(np.full(4, 2.0), mask) == np.inf  # no speckle: infinitely many looks
    img = np.array([1.0, 1.0, 3.0, 3.0])
    with pytest.warns(RuntimeWarning, match="constant and equal"):
        assert np.isnan(speckle.cnr(np.ones(4), mask, mask))
    with pytest.warns(RuntimeWarning, match="no noise"):
        assert speckle.cnr(img, img < 2, img > 2) == np.inf
    with pytest.warns(RuntimeWarning, match="outside the profile"):
        assert np.isnan(speckle.peak_fwhm([2.0, 1.5, 0.0, 0.0]))  # no left crossing


def test_fits_take_exact_zeros_refuse_all_zero_and_warn_without_chi2_dof():
    from speckle.analysis import statistics as st

    a = np.array([0.0, 1.0, 2.0, 3.0] * 10)  # an exact zero (8-bit data) in the sample
    fit = st.fit_rayleigh(a)
    assert float(fit["sigma"]) == pytest.approx(np.sqrt(np.mean(a**2) / 2), rel=1e-15)
    with pytest.raises(ValueError, match="intensity must hold a positive value"):
        st.fit_exponential(np.zeros(20))
    with pytest.warns(RuntimeWarning, match="0 degrees of freedom"):
        assert np.isnan(float(st.fit_exponential(np.arange(1.0, 11.0))["chi2_pvalue"]))


def test_contrast_standard_error_without_an_answer_warns():
    from speckle.analysis import statistics as st

    zero = xr.DataArray(np.zeros((4, 5)), dims=("depth", "aline"))
    with pytest.warns(RuntimeWarning, match="mean intensity is zero"):
        assert np.isnan(st.contrast_standard_error(zero)).all()
    with pytest.warns(RuntimeWarning, match="constant"):
        c, se = st.contrast_standard_error(zero + 1.0)
    assert c == 0.0 and np.isnan(se)


def test_compounded_contrast_refuses_what_is_not_a_correlation_matrix():
    with pytest.raises(ValueError, match="unit diagonal"):
        speckle.compounded_contrast(np.zeros((2, 2)))  # was 0.0: no speckle invented
    with pytest.raises(ValueError, match="unit diagonal"):
        speckle.compounded_contrast([[1.0, 2.0], [2.0, 1.0]])


def test_options_refused_by_name():
    from speckle.analysis import image_quality as iq
    from speckle.analysis import statistics as st

    with pytest.raises(TypeError, match="axis"):
        iq.bandlimited(np.ones((4, 4)), 2, axis="a")
    with pytest.raises(ValueError, match="axis"):
        iq.bandlimited(np.ones((4, 4)), 2, axis=2)
    img = xr.DataArray(np.ones((4, 5)), dims=("depth", "x"))
    with pytest.raises(TypeError, match="sample_dim"):
        st.contrast_standard_error(img, sample_dim="aline")
    series = xr.DataArray(np.ones((3, 8, 2), complex), dims=("time", "depth", "x"))
    with pytest.raises(ValueError, match="n_bands"):
        speckle.ssada(series, n_bands=9)  # more sub-bands than the A-line's 8 samples
