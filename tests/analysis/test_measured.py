"""Measured B-scans: loading, gain/offset-free log statistics, and the measured departure.

The real sample ships with the package (``speckle.data.sample_path("pdms")``, MIT-licensed, see
``speckle/data/oct_mit_sample/README.md``), so these tests run on every clone.

Statistical tolerances are ``TOL_SE`` standard errors; for the measured image the standard
error of a moment comes from its spread over 16 blocks of 32 A-lines (speckle is correlated over
3-4 A-lines, so blocks are nearly independent; single pixels are not).
"""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from scipy import integrate, special, stats

import speckle
from speckle.analysis import measured
from speckle.data import sample_path as sample_file
from speckle.system.detection import add_floor, log_compress

TOL_SE = 3.0
ROI = {"depth": [95, 135], "x": [0, 512]}
#: load_measured is retired (issue 32): its own tests below check that it warns
pytestmark = pytest.mark.filterwarnings("ignore:load_measured is retired:FutureWarning")


@pytest.fixture(scope="module")
def sample_path():
    return sample_file("pdms")


@pytest.fixture(scope="module")
def roi(sample_path):
    image = speckle.io.load_image(
        sample_path, kind="log", dims=("depth", "x"), pixel_size=5.75, pitch=1.57
    )
    return image.isel(measured.roi_slices(ROI, image.shape))


@pytest.fixture(scope="module")
def comparison(roi):
    return measured.compare_measured(roi)


# --- theory of the log of fully developed speckle -----------------------------------------


def test_gumbel_numbers_from_polygamma():
    """Cumulants of ln E, E ~ Exp(1), are psi^(n-1)(1)."""
    k2, k3, k4 = (float(special.polygamma(n, 1.0)) for n in (1, 2, 3))
    assert k2 == pytest.approx(np.pi**2 / 6)
    assert k3 == pytest.approx(-2 * special.zeta(3.0))
    assert k4 == pytest.approx(np.pi**4 / 15)
    assert measured.GUMBEL_SKEWNESS == pytest.approx(k3 / k2**1.5, rel=1e-12)
    assert measured.GUMBEL_SKEWNESS == pytest.approx(-1.1395470994, rel=1e-9)
    assert measured.GUMBEL_EXCESS_KURTOSIS == pytest.approx(k4 / k2**2, rel=1e-12)
    mom = measured.log_speckle_moments(0.0)
    assert mom["mean"] == pytest.approx(-np.euler_gamma)


@pytest.mark.parametrize("floor", [0.0, 1e-3, 0.0091, 0.3])
def test_standardised_pdf_has_the_stated_moments(floor):
    """The density integrates to 1 with mean 0, variance 1 and the quadrature moments."""
    mom = measured.log_speckle_moments(floor)
    pdf = lambda z: float(measured.standardised_log_pdf(z, floor))  # noqa: E731
    lo = -np.inf if floor == 0 else (np.log(floor) - mom["mean"]) / np.sqrt(mom["variance"])
    m = [integrate.quad(lambda z, k=k: z**k * pdf(z), lo, 12, limit=200)[0] for k in range(5)]
    assert m[0] == pytest.approx(1.0, abs=1e-7)
    assert m[1] == pytest.approx(0.0, abs=1e-7)
    assert m[2] == pytest.approx(1.0, abs=1e-7)
    assert m[3] == pytest.approx(mom["skewness"], abs=1e-6)
    assert m[4] - 3 == pytest.approx(mom["excess_kurtosis"], abs=1e-6)


def test_floor_moments_tend_to_gumbel_and_rise_monotonically():
    tiny = measured.log_speckle_moments(1e-12)
    assert tiny["skewness"] == pytest.approx(measured.GUMBEL_SKEWNESS, abs=1e-6)
    assert tiny["excess_kurtosis"] == pytest.approx(2.4, abs=1e-5)
    skews = [measured.log_speckle_moments(b)["skewness"] for b in (1e-4, 1e-3, 1e-2, 0.1, 1.0)]
    assert np.all(np.diff(skews) > 0)


def _synthetic(values, n_alines=512):
    arr = np.asarray(values, dtype=float).reshape(-1, n_alines)
    return xr.DataArray(arr, dims=("depth", "x"), attrs={"scale": "log"})


def test_statistics_are_free_of_gain_and_offset():
    rng = np.random.default_rng(4)
    y = np.log(rng.exponential(size=512 * 64))
    a = measured.log_statistics(_synthetic(y))
    b = measured.log_statistics(_synthetic(21.85 * y + 120.0))
    for k in ("skewness", "excess_kurtosis", "skewness_se", "excess_kurtosis_se"):
        assert float(a[k]) == pytest.approx(float(b[k]), rel=1e-9, abs=1e-12)
    # and they agree with the fully developed law within their block standard errors
    assert abs(float(a.skewness) - measured.GUMBEL_SKEWNESS) < 4 * float(a.skewness_se)
    assert abs(float(a.excess_kurtosis) - 2.4) < 4 * float(a.excess_kurtosis_se)


def test_fit_floor_recovers_floor_gain_and_offset():
    rng = np.random.default_rng(6)
    b, g, c = 0.01, 21.0, 110.0
    data = _synthetic(g * np.log(rng.exponential(size=512 * 400) + b) + c)
    fit = measured.fit_floor(data)
    st_ = measured.log_statistics(data)
    # SE(b) from SE(skewness) through the slope d skew / d b of the floor law
    slope = (
        measured.log_speckle_moments(b * 1.01)["skewness"]
        - measured.log_speckle_moments(b * 0.99)["skewness"]
    ) / (0.02 * b)
    assert abs(float(fit.floor) - b) < 4 * float(st_.skewness_se) / slope
    assert float(fit.gain) == pytest.approx(g, rel=0.02)
    assert float(fit.offset) == pytest.approx(c, abs=0.05 * g)
    assert float(fit.skewness_model) == pytest.approx(float(st_.skewness), abs=1e-5)


def test_quantisation_and_log_compression_of_fully_developed_speckle():
    """8-bit rounding of g ln I + c barely moves skewness/kurtosis when nothing is clipped
    (Sheppard: variance + 1/12). g = 15 (< the measured 21.85) so that 8 bits hold the whole
    ~17 ln-unit spread of 32768 exponential samples, and quantisation is coarser than measured."""
    rng = np.random.default_rng(8)
    i = xr.DataArray(rng.exponential(size=(64, 512)), dims=("depth", "x"))
    d = log_compress(i, 15.0, 160.0)
    assert float(d.min()) > 0 and float(d.max()) < 255
    q = measured.log_statistics(d)
    exact = measured.log_statistics(np.log(i).assign_attrs(scale="log"))
    assert abs(float(q.skewness) - float(exact.skewness)) < 0.3 * float(exact.skewness_se)
    assert float(q.quantisation_variance_fraction) < 1e-3


# --- loading -------------------------------------------------------------------------------


def test_load_npy_png_and_labels(tmp_path):
    arr = np.arange(60, dtype=np.uint8).reshape(6, 10)
    np.save(tmp_path / "a.npy", arr)
    with pytest.warns(FutureWarning, match="load_measured is retired: .*load_image"):
        da = measured.load_measured(
            tmp_path / "a.npy", roi={"depth": [1, 5], "x": [2, None]}, pixel_size=5.75
        )
    assert da.dims == ("depth", "x") and da.shape == (4, 8)
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):
        old = measured.load_measured(tmp_path / "a.npy", roi={"depth": [1, 5], "aline": [2, None]})
    np.testing.assert_array_equal(old.values, da.values)
    np.testing.assert_array_equal(da.values, arr[1:5, 2:])
    np.testing.assert_allclose(da.depth, np.arange(1, 5) * 5.75)
    np.testing.assert_array_equal(da.column, np.arange(2, 10))
    assert da.attrs["clip_low"] == 0 and da.attrs["clip_high"] == 255
    assert da.attrs["scale"] == "log" and da.depth.attrs["units"] == "um"
    import matplotlib.image

    matplotlib.image.imsave(tmp_path / "a.png", np.repeat(arr[..., None], 3, axis=-1))
    png = measured.load_measured(tmp_path / "a.png", scale="linear")
    assert png.shape == (6, 10)
    np.testing.assert_allclose(png.values * 255, arr, atol=1e-4)  # grey RGB -> exact


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({"scale": "dB"}, ValueError, "scale"),
        ({"roi": {"y": [0, 2]}}, ValueError, "roi"),
        ({"roi": {"depth": [3]}}, ValueError, "roi"),
        ({"roi": {"depth": [-1, 3]}}, ValueError, "roi"),
        ({"roi": {"depth": [0, 1]}}, ValueError, "2x2"),
        ({"pixel_size": -1.0}, ValueError, "pixel_size"),
    ],
)
def test_load_bad_input(tmp_path, kwargs, exc, match):
    np.save(tmp_path / "a.npy", np.ones((4, 4)))
    with pytest.raises(exc, match=match):
        measured.load_measured(tmp_path / "a.npy", **kwargs)


def test_load_bad_files(tmp_path):
    with pytest.raises(FileNotFoundError):
        measured.load_measured(tmp_path / "missing.npy")
    np.save(tmp_path / "cube.npy", np.ones((2, 2, 2)))
    with pytest.raises(ValueError, match="2-D"):
        measured.load_measured(tmp_path / "cube.npy")
    np.save(tmp_path / "zeros.npy", np.zeros((4, 4)))
    lin = measured.load_measured(tmp_path / "zeros.npy", scale="linear")
    with pytest.raises(ValueError, match="> 0"):
        measured.log_intensity(lin)
    with pytest.raises(TypeError, match="load_measured"):
        measured.log_intensity(np.ones((3, 3)))
    with pytest.raises(ValueError, match="floor"):
        measured.log_speckle_moments(-0.1)


# --- the real sample -------------------------------------------------------------------------


def test_sample_roi_as_documented(roi):
    assert roi.shape == (40, 512) and roi.attrs["dtype"] == "uint8"
    np.testing.assert_allclose(roi.depth[[0, -1]], [95 * 5.75, 134 * 5.75])  # rows 95..134


def test_measured_departs_from_fully_developed_speckle(comparison):
    c = comparison
    assert abs(float(c.skewness) - measured.GUMBEL_SKEWNESS) > 5 * float(c.skewness_se)
    assert abs(float(c.excess_kurtosis) - 2.4) > 5 * float(c.excess_kurtosis_se)
    # the pure law fitted by its moments would put ~55 pixels at the 8-bit zero; none are
    # there (Poisson P(0 | 55) ~ 1e-24, conservative even for a few correlated pixels per grain)
    assert int(c.low_clip_count) == 0 and float(c.low_clip_count_pure) > 30


def test_departure_is_not_trend_quantisation_clipping_or_oversampling(roi, comparison):
    c = comparison
    # depth attenuation: the linear trend carries < 1 % of the variance and removing each
    # row's mean changes the moments by far less than their standard errors
    assert float(c.depth_trend_variance_fraction) < 0.01
    assert abs(float(c.skewness_detrended) - float(c.skewness)) < 0.1 * float(c.skewness_se)
    assert abs(float(c.excess_kurtosis_detrended) - float(c.excess_kurtosis)) < 0.1 * float(
        c.excess_kurtosis_se
    )
    # quantisation (Sheppard: + 1/12 of a level^2) and clipping are negligible in the ROI
    assert float(c.quantisation_variance_fraction) < 1e-3 and float(c.clipped_fraction) == 0
    # lateral oversampling correlates neighbours but does not change the marginal law: every
    # 4th A-line gives the same moments within the subsample's standard error
    sub = measured.log_statistics(roi.isel(x=slice(None, None, 4)), n_blocks=8)
    assert abs(float(sub.skewness) - float(c.skewness)) < TOL_SE * float(sub.skewness_se)
    assert abs(float(sub.excess_kurtosis) - float(c.excess_kurtosis)) < TOL_SE * float(
        sub.excess_kurtosis_se
    )


def test_intensity_floor_explains_the_departure(comparison):
    c = comparison
    # skewness fitted; excess kurtosis predicted within TOL_SE of the measured value
    assert 0.005 < float(c.floor) < 0.015
    assert abs(float(c.excess_kurtosis_model) - float(c.excess_kurtosis)) < TOL_SE * float(
        c.excess_kurtosis_se
    )
    # and the whole standardised histogram moves closer (KS distance halves)
    assert float(c.ks_floor) < 0.6 * float(c.ks_pure)


def test_simulated_scene_with_floor_reproduces_measured_moments(comparison):
    """Dense simulated speckle + the fitted floor + 8-bit log compression at the fitted gain
    and offset matches the measured skewness and kurtosis within the combined standard error."""
    n = 32
    scene = speckle.random_scatterers(800, 16.0, n_pixels=n, depth_range=n * 8.0, seed=13)
    ds = speckle.bscan(scene, speckle.spectrum(n, n * 8.0, k0_dk=10), normalise="expected")
    i = add_floor(ds.intensity, float(comparison.floor), mean_intensity=1.0)
    sim = measured.log_statistics(log_compress(i, float(comparison.gain), float(comparison.offset)))
    for k in ("skewness", "excess_kurtosis"):
        se = np.hypot(float(sim[f"{k}_se"]), float(comparison[f"{k}_se"]))
        assert abs(float(sim[k]) - float(comparison[k])) < TOL_SE * se, k
    # without the floor the same scene keeps the fully developed values
    pure = measured.log_statistics(np.log(ds.intensity).assign_attrs(scale="log"))
    assert abs(float(pure.skewness) - measured.GUMBEL_SKEWNESS) < 4 * float(pure.skewness_se)


def test_compare_records_what_was_compared(comparison):
    assert "standardised log-intensity" in comparison.attrs["compared"]
    assert comparison.attrs["scale"] == "log"


def test_low_density_matches_moments_but_not_the_histogram(roi, comparison):
    """The model's own partially developed speckle (N_sc/N ~ 0.7) reproduces the measured
    skewness, but its standardised log histogram is further from the data than even the pure
    law, while the floor law is closest. Two-sample KS on equally quantised samples."""
    n, g = 256, float(comparison.gain)
    scene = speckle.random_scatterers(160, 0.7, n_pixels=n, depth_range=n * 8.0, seed=17)
    ds = speckle.bscan(scene, speckle.spectrum(n, n * 8.0, k0_dk=10))
    rng = np.random.default_rng(17)
    samples = {
        "low_density": np.log(ds.intensity.values.ravel()),
        "pure": np.log(rng.exponential(size=roi.size)),
        "floor": np.log(rng.exponential(size=roi.size) + float(comparison.floor)),
    }
    data = measured.standardise(roi).values.ravel()
    ks = {}
    for name, y in samples.items():
        q = np.round(g * y)  # quantised like the 8-bit data
        ks[name] = stats.ks_2samp((q - q.mean()) / q.std(), data).statistic
    low = measured.log_statistics(
        xr.DataArray(
            samples["low_density"].reshape(n, -1), dims=("depth", "x"), attrs={"scale": "log"}
        )
    )
    se = np.hypot(float(low.skewness_se), float(comparison.skewness_se))
    assert abs(float(low.skewness) - float(comparison.skewness)) < TOL_SE * se
    assert ks["floor"] < ks["pure"] < ks["low_density"]


def test_additive_detector_noise_does_not_explain_the_departure(sample_path, comparison):
    """Detector noise adds a circular complex Gaussian to the field, so speckle + noise stays
    exponential: the log moments keep their fully developed values. The air rows 5:50 put the
    noise at ~-11 dB of the ROI's mean speckle intensity; the fitted floor is ~9 dB lower."""
    air = measured.log_statistics(measured.load_measured(sample_path, roi={"depth": [5, 50]}))
    g, c = float(comparison.gain), float(comparison.offset)
    noise = np.exp((float(air["mean"]) - c) / g + np.euler_gamma)  # <I_n>/<I_roi>
    assert 0.03 < noise < 0.2 and noise > 5 * float(comparison.floor)
    n = 32
    scene = speckle.random_scatterers(800, 16.0, n_pixels=n, depth_range=n * 8.0, seed=19)
    field = speckle.bscan(scene, speckle.spectrum(n, n * 8.0, k0_dk=10), normalise="expected")
    rng = np.random.default_rng(19)
    shape = field.field.shape
    w = np.sqrt(noise / 2) * (rng.normal(size=shape) + 1j * rng.normal(size=shape))
    noisy = measured.log_statistics(np.log(abs(field.field + w) ** 2).assign_attrs(scale="log"))
    assert abs(float(noisy.skewness) - measured.GUMBEL_SKEWNESS) < 4 * float(noisy.skewness_se)
    assert abs(float(noisy.excess_kurtosis) - 2.4) < 4 * float(noisy.excess_kurtosis_se)
