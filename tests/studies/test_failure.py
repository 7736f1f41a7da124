"""Failure-map scoring: the mean and standard error over seeds, and the vector method's error
floor at small strain against its Gaussian-speckle theory (``predicted_vector_floor``)."""

from __future__ import annotations

import numpy as np
import pytest

import speckle
from speckle.studies.failure import (
    mean_and_se,
    predicted_tracking_quantization,
    predicted_vector_floor,
)

N, PIXEL, LINES, LAG, WINDOW = 256, 8.0, 64, 3, (32, 4)
STRAIN = 1e-6  # deep in the linear regime: 2 k0 s H = 0.03 rad
N_SEEDS = 8


def test_mean_and_se_over_finite_repeats():
    v = np.array([[1.0, 2.0, 3.0, np.nan], [np.nan, np.nan, 5.0, np.nan], [np.nan] * 4])
    mean, se = mean_and_se(v)
    np.testing.assert_allclose(mean[:2], [2.0, 5.0])
    np.testing.assert_allclose(se[0], 1.0 / np.sqrt(3))  # std(ddof=1) = 1 over 3 repeats
    assert np.isnan(se[1]) and np.isnan(mean[2]) and np.isnan(se[2])


def _source():
    return speckle.spectrum(N, N * PIXEL, k0_dk=10.0, shape="gaussian", fwhm_fraction=0.5)


def _pair(seed: int, strain: float, warp: bool = False):
    """Noise-free pair at uniform compression. The scene fills [0, H) only (strain=0), so no
    scatterer is pulled in from below the image. ``warp``: the deformed image is the reference
    itself resampled where the material went (the envelopes stretched, no speckle change)."""
    scene = speckle.deformable_scene(LINES, 4.0, n_pixels=N, depth_range=N * PIXEL, seed=seed)
    a1, a2 = (
        speckle.bscan(speckle.displace(scene, lambda z, x, s=s: -s * z), _source())
        .field.transpose("depth", "x")
        .values
        for s in (0.0, strain)
    )
    if warp:
        q = np.arange(N, dtype=float)[:, None] * np.ones((1, LINES))
        a2 = speckle.analysis.resample_depth(a1, q / (1 - strain))
    return a1, a2


def test_tracker_window_edge_bias_matches_its_derivation():
    """A window moved by u whole pixels keeps W - u of its samples in the other image's window;
    the circular cross-correlation of the two windows is then ``(W - s) R(s - u)`` near the peak
    (W = 64 samples for 32 px at 2 samples per pixel), and ``R = exp(-beta^2 d^2/2)`` puts its
    maximum at ``d = -1/((W - u) beta^2)`` samples: a bias towards zero, ``beta^2 = -2 ln R(1)``
    from the image's own amplitude samples. Identical images (u = 0) have no bias. Tested at
    exact whole-pixel shifts (the deformed image a roll of the reference); within 15 %
    (the Gaussian form of R, and the ramp by which the bias grows in from u = 0)."""
    a1, _ = _pair(300, 1e-3)
    h = np.abs(speckle.analysis.oversample_depth(a1, 2))
    x = h - h.mean(axis=0)
    beta2 = -2 * np.log(np.mean(x[:-1] * x[1:]) / np.mean(x * x))
    same = speckle.analysis.track_array(a1, a1, window=(32, 4), step=(8, 4), lateral=False)
    np.testing.assert_array_equal(same["uz"][np.isfinite(same["uz"])], 0.0)
    for u in (2, 3):
        tr = speckle.analysis.track_array(
            a1, np.roll(a1, u, axis=0), window=(32, 4), step=(8, 4), lateral=False
        )
        bias = np.nanmean(tr["uz"][1:-1] - u)  # windows that wrap over the image edge left out
        expected = -1 / ((64 - 2 * u) * beta2) / 2  # samples -> pixels
        assert bias == pytest.approx(expected, rel=0.15), (u, bias, expected)


@pytest.mark.slow
def test_tracking_error_above_1e3_is_not_decorrelation():
    """The tracking method's strain error at displacements of about half a pixel is nearly all
    there on a pure warp of the reference (stretched envelopes, no speckle change; paired on
    the same scenes): over 80 % of its mean square comes from the window estimates' own error
    at that displacement (the edge bias above and its spread), not from the speckle's
    decorrelation. At 1e-2 (2.6 px) the decorrelation adds a larger share."""
    kw = {"k0": float(_source().attrs["k0"]), "pixel_size": PIXEL, "method": "tracking"}

    def mean_square(strain, warp):
        out = []
        for i in range(4):
            est = speckle.estimate_strain(*_pair(400 + i, strain, warp), window=WINDOW, **kw)
            out.append(np.nanmean(((est - strain) / strain) ** 2))
        return np.array(out)

    real, warped = mean_square(2e-3, False), mean_square(2e-3, True)
    assert np.mean(warped) > 0.8 * np.mean(real)
    real, warped = mean_square(1e-2, False), mean_square(1e-2, True)
    assert np.mean(warped) < 0.8 * np.mean(real)


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"lag": 0, "window": WINDOW}, "lag"),
        ({"lag": LAG, "window": (1, 4)}, r"window\[0\]"),
        ({"lag": LAG, "window": (32, 0)}, r"window\[1\]"),
        ({"lag": LAG, "window": 32}, "window"),
        ({"lag": LAG, "window": WINDOW, "oversample": 1}, "oversample"),
    ],
)
def test_predicted_floor_refuses_bad_input(kw, match):
    with pytest.raises((TypeError, ValueError), match=match):
        predicted_vector_floor(_source(), **kw)


def test_predicted_floor_needs_a_spectrum():
    with pytest.raises(TypeError, match="spectrum"):
        predicted_vector_floor(np.ones(N), lag=LAG, window=WINDOW)


def _relative_errors(seed: int, window=WINDOW) -> np.ndarray:
    """(estimate - s)/s of the unaligned vector method on a noise-free compressed pair."""
    a1, a2 = _pair(seed, STRAIN)
    est = speckle.estimate_strain(
        a1,
        a2,
        k0=float(_source().attrs["k0"]),
        pixel_size=PIXEL,
        window=window,
        lag=LAG,
        align=False,
    )
    return (est - STRAIN) / STRAIN


@pytest.mark.slow
@pytest.mark.parametrize("window", [WINDOW, (32, 16)])
def test_small_strain_floor_matches_the_gaussian_theory(window):
    """Noise-free, s -> 0: the error is linear in s, its relative rms a floor. The theory (first
    order in s, Gaussian moments, periodic depth kernel) predicts the mean square per row; the
    measured mean square over the answered pixels, averaged over seeds, agrees within three
    standard errors of that mean, over the whole image and separately in the top eighth (the
    periodic-depth leakage of the bottom scatterers' side lobes) and below it (the envelope
    shift, growing with depth).

    The leakage is a bias, the same on every A-line: averaging more A-lines does not shrink it.
    A theory without it (variance / window A-lines only) read 1.8x low in mean square in the top
    eighth at 4 A-lines and 4x low at 16; the 16-A-line window checks that the bias is there."""
    pred = predicted_vector_floor(_source(), lag=LAG, window=window)
    bands = {"all": slice(0, N), "top": slice(0, N // 8), "below": slice(N // 8, N)}
    measured = {k: [] for k in bands}
    for seed in range(N_SEEDS):
        err = _relative_errors(100 + seed, window)
        assert np.isfinite(err).any(axis=1).sum() == np.isfinite(pred).sum()  # same rows
        for k, rows in bands.items():
            measured[k].append(np.nanmean(err[rows] ** 2))
    for k, rows in bands.items():
        mean, se = mean_and_se(np.array(measured[k]))
        expected = np.nanmean(pred[rows] ** 2)
        assert abs(mean - expected) < 3 * se, (k, mean, se, expected)
    # the leakage makes the top rows several times worse than the rows below
    assert np.nanmean(pred[bands["top"]] ** 2) > 4 * np.nanmean(pred[bands["below"]] ** 2)


def _wls_band_mean_squares(seed: int, strain: float) -> tuple[float, float]:
    """Mean square of (estimate - s)/s of unaligned ``wls`` in the top eighth and below it."""
    a1, a2 = _pair(seed, strain)
    k0 = float(_source().attrs["k0"])
    est = speckle.estimate_strain(
        a1, a2, k0=k0, pixel_size=PIXEL, window=WINDOW, method="wls", align=False
    )
    err = (est - strain) / strain
    return float(np.nanmean(err[: N // 8] ** 2)), float(np.nanmean(err[N // 8 :] ** 2))


@pytest.mark.slow
def test_wls_small_strain_excess_is_the_top_rows_leakage():
    """``wls`` reads worse at s -> 0 than at 1e-3 for the vector method's reasons: below the top
    eighth its error is linear in s (the same relative floor at 1e-6 and 1e-5, paired on the
    same scenes), and the excess is in the top eighth (the wrapped side lobes: an error linear
    in s only while 2 k0 s H << 1, 0.03 rad at 1e-6, bounded above, so its share of the strain
    falls once 2 k0 s H = 16 rad at 1e-3)."""
    small, mid, large = (
        np.array([_wls_band_mean_squares(200 + seed, s) for seed in range(4)])
        for s in (STRAIN, 1e-5, 1e-3)
    )
    diff_mean, diff_se = mean_and_se(small[:, 1] - mid[:, 1])  # same scenes: paired
    below_small = small[:, 1].mean()
    assert abs(diff_mean) < 3 * diff_se
    assert small[:, 0].mean() > 4 * below_small  # leakage rows, as the vector theory's
    assert large[:, 0].mean() < small[:, 0].mean() / 4


def test_tracking_reads_zero_below_half_its_registration_grid():
    """The tracker's displacement lies on a 1/40-px grid: when the largest displacement of the
    compression (s * depth) is below half a step, every window reads 0, so the strain is exactly
    0 (error/strain 1, as the model of the grid alone predicts)."""
    n, s = 128, 5e-5  # 0.0064 px at the bottom < 1/80 px
    scene = speckle.deformable_scene(8, 4.0, n_pixels=n, depth_range=n * PIXEL, seed=3)
    src = speckle.spectrum(n, n * PIXEL, k0_dk=10.0, shape="gaussian", fwhm_fraction=0.5)
    a1, a2 = (
        speckle.bscan(speckle.displace(scene, lambda z, x, s=v: -s * z), src)
        .field.transpose("depth", "x")
        .values
        for v in (0.0, s)
    )
    est = speckle.estimate_strain(
        a1, a2, k0=float(src.attrs["k0"]), pixel_size=PIXEL, method="tracking"
    )
    assert np.isfinite(est).any()
    np.testing.assert_array_equal(est[np.isfinite(est)], 0.0)
    assert predicted_tracking_quantization(s, n) == pytest.approx(1.0, abs=1e-12)
    # above the threshold the rounded displacement is a staircase: spikes of the slope fit
    assert predicted_tracking_quantization(1e-4, 512) > 1.5


@pytest.mark.parametrize(
    "kw, match",
    [
        ({"strain": 0.0, "n_pixels": 512}, "strain"),
        ({"strain": 1e-4, "n_pixels": 64}, "n_pixels"),
        ({"strain": 1e-4, "n_pixels": 512, "window": 1}, "window"),
        ({"strain": 1e-4, "n_pixels": 512, "grid": 0.0}, "grid"),
    ],
)
def test_tracking_quantization_refuses_bad_input(kw, match):
    with pytest.raises((TypeError, ValueError), match=match):
        predicted_tracking_quantization(**kw)
