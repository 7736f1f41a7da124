"""Speckle statistics: histograms, fits, contrast, and the contrast theory against simulations.

Statistical tolerances are ``TOL_SE`` standard errors of the estimator. The contrast's standard
error comes from the spread of per-A-line moments (pixels of one A-line are correlated through
the shared scatterers and fixed count; A-lines are independent), by the delta method (see
:func:`speckle.analysis.statistics.contrast_standard_error`). With fixed seeds the tests are
deterministic; 4 SE would be exceeded by chance with probability 6e-5 per check.
"""

from __future__ import annotations

import itertools

import numpy as np
import pytest
import xarray as xr
from hypothesis import given
from hypothesis import strategies as st
from hypothesis.extra.numpy import arrays
from scipy import integrate, stats

import speckle
from speckle.analysis.statistics import (
    contrast_standard_error,
    contrast_theory,
    exponential_pdf,
    fit_exponential,
    fit_rayleigh,
    histogram,
    rayleigh_pdf,
    speckle_contrast,
    spectrum_moments,
)

TOL_SE = 4.0
N = 32  # small A-lines keep the direct method fast; the theory holds for any N
H = N * 8.0


def gaussian_source(n=N, k0_dk=10.0):
    return speckle.spectrum(n, n * 8.0, k0_dk=k0_dk, shape="gaussian", fwhm=0.5 * np.pi / 8.0)


def simulate(density, *, source, n_alines, amplitude="equal", count="fixed", seed=11):
    scene = speckle.random_scatterers(
        n_alines,
        density,
        n_pixels=source.attrs["n_pixels"],
        depth_range=source.attrs["depth_range"],
        seed=seed,
        amplitude=amplitude,
        count=count,
    )
    return speckle.bscan(scene, source)


# --- theory: exact identities ------------------------------------------------------------


@pytest.mark.parametrize("n", [2, 3, 16, 256])
def test_rectangular_moments_closed_form(n):
    mu2, mu4 = spectrum_moments(n)
    assert mu2 == n
    assert mu4 == pytest.approx((2 * n**3 + n) / 3, rel=1e-14)
    rho = 1.7
    expected = np.sqrt(1 + (2 * n**2 - 6 * n + 1) / (3 * n**2 * (round(rho * n) / n)))
    assert contrast_theory(rho, n) == pytest.approx(expected, rel=1e-14)


def test_mu4_is_the_period_average_of_the_fourth_power_of_the_kernel():
    """mu4 = <|g|^4> over z in one period, g(u) = sum S_n exp(2 pi i n u/H): exact on a grid of
    more than 4N points because |g|^4 is a trigonometric polynomial of degree < 2N."""
    s = np.asarray(gaussian_source(12))
    n = np.arange(12) - 6
    u = np.arange(64) / 64
    g = (s[None, :] * np.exp(2j * np.pi * n[None, :] * u[:, None])).sum(axis=1)
    mu2, mu4 = spectrum_moments(12, s)
    assert np.mean(np.abs(g) ** 2) == pytest.approx(mu2, rel=1e-12)
    assert np.mean(np.abs(g) ** 4) == pytest.approx(mu4, rel=1e-12)


def test_theory_limits_and_labels():
    rho = xr.DataArray([0.5, 4.0, 1e6], dims="density")
    c = contrast_theory(rho, 256)
    assert c.dims == ("density",) and c.name == "contrast_theory"
    assert c[-1] == pytest.approx(1.0, abs=1e-6)  # dense limit: fully developed speckle
    assert np.all(np.diff(c) < 0)
    # Poisson count adds the count fluctuation: C^2 larger by 2/M for the same mean count
    m = 0.5 * 256
    fixed, poisson = contrast_theory(0.5, 256), contrast_theory(0.5, 256, count="poisson")
    assert poisson**2 - fixed**2 == pytest.approx(2 / m, rel=1e-12)


# --- theory against seeded simulations -----------------------------------------------------

CASES = list(
    itertools.product(["rectangular", "gaussian"], ["equal", "rayleigh"], ["fixed", "poisson"])
)


@pytest.mark.slow
@pytest.mark.parametrize(("shape", "amplitude", "count"), CASES)
@pytest.mark.parametrize("density", [0.5, 2.0, 16.0])
def test_contrast_matches_theory(shape, amplitude, count, density):
    source = speckle.spectrum(N, H, k0_dk=10) if shape == "rectangular" else gaussian_source()
    n_alines = 1000 if density > 4 else 2000
    ds = simulate(density, source=source, n_alines=n_alines, amplitude=amplitude, count=count)
    c, se = contrast_standard_error(ds.intensity)
    theory = contrast_theory(density, N, source, amplitude=amplitude, count=count)
    assert abs(c - theory) < TOL_SE * se, (c, se, theory)
    if density < 4:  # the test has power: the departure from C = 1 is resolved
        assert abs(theory - 1.0) > 3 * TOL_SE * se


@pytest.mark.slow
def test_contrast_versus_density_sweep():
    source = speckle.spectrum(N, H, k0_dk=10)
    for density in [0.5, 1.0, 4.0, 8.0]:
        ds = simulate(density, source=source, n_alines=1500, seed=3)
        c, se = contrast_standard_error(ds.intensity)
        assert abs(c - contrast_theory(density, N)) < TOL_SE * se, density


@pytest.mark.slow
def test_intensity_statistics_independent_of_k0():
    """Same scatterers, k0/dk = 1 and 10: same mean intensity and contrast within error."""
    scene = speckle.random_scatterers(2000, 4.0, n_pixels=N, depth_range=H, seed=21)
    out = {}
    for ratio in (1.0, 10.0):
        ds = speckle.bscan(scene, speckle.spectrum(N, H, k0_dk=ratio))
        line_means = ds.intensity.mean("depth")
        out[ratio] = (
            *contrast_standard_error(ds.intensity),
            float(line_means.mean()),
            float(line_means.std()) / np.sqrt(line_means.size),
        )
    (c1, se1, m1, sm1), (c10, se10, m10, sm10) = out[1.0], out[10.0]
    # the two estimates share scatterers (positively correlated), so the independent-sum
    # standard error sqrt(se1^2 + se10^2) is conservative
    assert abs(c1 - c10) < TOL_SE * np.hypot(se1, se10)
    assert abs(m1 - m10) < TOL_SE * np.hypot(sm1, sm10)
    expected = speckle.expected_intensity(4.0, N, None)
    for c, se, m, sm in out.values():
        assert abs(c - contrast_theory(4.0, N)) < TOL_SE * se
        assert abs(m - expected) < TOL_SE * sm


@pytest.mark.slow
def test_fits_at_high_density():
    """Rayleigh sigma^2 and exponential mean equal <I>/2 and <I> (speckle.expected_intensity)."""
    ds = simulate(16.0, source=speckle.spectrum(N, H, k0_dk=10), n_alines=1000, seed=5)
    expected = speckle.expected_intensity(16.0, N, None)
    line_means = ds.intensity.mean("depth")
    se_mean = float(line_means.std()) / np.sqrt(line_means.size)  # lines are independent
    ray, exp_ = fit_rayleigh(ds.amplitude), fit_exponential(ds.intensity)
    assert abs(float(ray.sigma) ** 2 - expected / 2) < TOL_SE * se_mean / 2
    assert abs(float(exp_["mean"]) - expected) < TOL_SE * se_mean
    # the MLEs are the moment identities exactly
    assert float(ray.sigma) ** 2 == pytest.approx(float((ds.intensity).mean()) / 2, rel=1e-6)
    assert float(exp_["mean"]) == pytest.approx(float(ds.intensity.mean()), rel=1e-6)
    # at density 16 the amplitude law is much closer to Rayleigh than at density 0.5
    sparse = simulate(0.5, source=speckle.spectrum(N, H, k0_dk=10), n_alines=1000, seed=5)
    assert float(fit_rayleigh(sparse.amplitude).ks_statistic) > 5 * float(ray.ks_statistic)


# --- fits, histograms and pdfs on exact samples ---------------------------------------------


def test_fits_recover_known_parameters():
    rng = np.random.default_rng(2)
    n, sigma = 200_000, 3.0
    amp = stats.rayleigh.rvs(scale=sigma, size=n, random_state=rng)
    fit = fit_rayleigh(amp)
    # MLE sigma^2 = <x^2>/2 has Var = sigma^4/n, so SE(sigma) = sigma/(2 sqrt(n))
    assert abs(float(fit.sigma) - sigma) < TOL_SE * sigma / (2 * np.sqrt(n))
    # chi-square ~ chi2(dof): mean dof, std sqrt(2 dof)
    assert float(fit.chi2) < fit.chi2_dof + TOL_SE * np.sqrt(2 * fit.chi2_dof)
    # KS statistic of n exact samples is O(1/sqrt(n)) (Kolmogorov: P(sqrt(n) D > 1.95) = 1e-3)
    assert float(fit.ks_statistic) < 1.95 / np.sqrt(n)
    inten = rng.exponential(2.5, size=n)
    efit = fit_exponential(inten)
    assert abs(float(efit["mean"]) - 2.5) < TOL_SE * 2.5 / np.sqrt(n)
    assert efit.attrs["model"] == "exponential" and "anti-conservative" in efit.attrs["note"]


def test_histogram_density_and_labels():
    rng = np.random.default_rng(0)
    values = xr.DataArray(
        rng.normal(size=(50, 40)), dims=("depth", "x"), name="amplitude", attrs={"units": "1"}
    )
    h = histogram(values, 30, range=(-5.0, 5.0))
    counts, edges = np.histogram(values.values, bins=30, range=(-5, 5))
    np.testing.assert_allclose(h.values, counts / (values.size * np.diff(edges)))
    np.testing.assert_allclose(h.bin_lower, edges[:-1])
    np.testing.assert_allclose(h.bin_upper, edges[1:])
    np.testing.assert_allclose(h.bin, 0.5 * (edges[1:] + edges[:-1]))
    assert float((h * (h.bin_upper - h.bin_lower)).sum()) == pytest.approx(1.0)
    assert h.dims == ("bin",) and h.attrs["count"] == 2000 and h.attrs["outside"] == 0
    explicit = histogram(values, edges)
    xr.testing.assert_allclose(explicit, h)


@given(
    arrays(np.float64, st.integers(2, 200), elements=st.floats(-1e6, 1e6, allow_nan=False)),
    st.integers(1, 50),
)
def test_histogram_area_is_one(values, bins):
    h = histogram(values, bins)
    area = float((h * (h.bin_upper - h.bin_lower)).sum())
    assert area == pytest.approx(1.0, rel=1e-9)


def test_pdfs_are_normalised_and_keep_labels():
    assert integrate.quad(lambda x: rayleigh_pdf(x, 1.7), 0, np.inf)[0] == pytest.approx(1.0)
    assert integrate.quad(lambda x: exponential_pdf(x, 0.3), 0, np.inf)[0] == pytest.approx(1.0)
    x = xr.DataArray([0.0, 1.0, 2.0], dims="bin")
    r = rayleigh_pdf(x, 1.0)
    assert isinstance(r, xr.DataArray) and r.dims == ("bin",)
    np.testing.assert_allclose(r, x * np.exp(-(x**2) / 2))
    np.testing.assert_allclose(exponential_pdf(x, 2.0), np.exp(-x / 2) / 2)


@given(st.floats(1e-3, 1e3))
def test_contrast_is_scale_free(scale):
    rng = np.random.default_rng(1)
    i = xr.DataArray(rng.exponential(size=(20, 30)), dims=("depth", "x"))
    assert float(speckle_contrast(i * scale)) == pytest.approx(float(speckle_contrast(i)))


def test_speckle_contrast_values_and_dims():
    i = xr.DataArray([[1.0, 3.0], [2.0, 2.0]], dims=("depth", "x"))
    assert float(speckle_contrast(i)) == pytest.approx(np.sqrt(0.5) / 2)
    per_line = speckle_contrast(i, dim="depth")
    np.testing.assert_allclose(per_line, [0.5 / 1.5, 0.5 / 2.5])
    assert speckle_contrast(np.array([1.0, 3.0])) == pytest.approx(0.5)


# --- bad input ------------------------------------------------------------------------------


@pytest.mark.parametrize(
    ("call", "exc", "match"),
    [
        (lambda: contrast_theory(-1.0, 256), ValueError, "density"),
        (lambda: contrast_theory(0.001, 256), ValueError, "density"),
        (lambda: contrast_theory(1.0, 1), ValueError, "n_pixels"),
        (lambda: contrast_theory(1.0, 256, amplitude="gamma"), ValueError, "amplitude"),
        (lambda: contrast_theory(1.0, 256, count="binomial"), ValueError, "count"),
        (lambda: contrast_theory(1.0, 256, np.ones(10)), ValueError, "spectrum"),
        (lambda: contrast_theory(np.nan, 256), ValueError, "density"),
        (lambda: histogram([1.0, np.nan], 3), ValueError, "values"),
        (lambda: histogram([1.0, 2.0], 0), ValueError, "bins"),
        (lambda: histogram([1.0, 2.0], [1.0, 1.0]), ValueError, "bins"),
        (lambda: histogram([1.0], 3), ValueError, "values"),
        (lambda: fit_rayleigh([-1.0, 1.0, 2.0]), ValueError, "amplitude"),
        (lambda: fit_exponential(["a", "b"]), TypeError, "intensity"),
        (lambda: rayleigh_pdf(1.0, 0.0), ValueError, "sigma"),
        (lambda: exponential_pdf(1.0, -2.0), ValueError, "mean"),
        (lambda: speckle_contrast(np.ones(3), dim="depth"), TypeError, "dim"),
        (
            lambda: contrast_standard_error(xr.DataArray(np.ones((3, 3)), dims=("a", "b"))),
            TypeError,
            "x",
        ),
    ],
)
def test_bad_input(call, exc, match):
    with pytest.raises(exc, match=match):
        call()
