"""Boundaries of fit_phantom (issue 34): the transition model, ramps merged, no spurious layers."""

from __future__ import annotations

import functools

import numpy as np
import pytest
from scipy import optimize

import speckle
from speckle.studies.phantom._fit import _fit_levels  # private: the flat fit alone (the ramp)
from speckle.studies.phantom._shapes import (
    TransitionModel,  # private: the model under test
    _contrast_rss,  # private: the contrast's change-point misfit under test
    _joint,  # private: the joint search under test
)
from speckle.studies.phantom.loop import fit_profiles
from speckle.studies.phantom.patients import patient_table, profiles
from speckle.synthoct import _scan  # private: the scanner's Hann spectrum (the reference)

REDUCED = speckle.synthoct_config("reduced")


@functools.cache
def fine_psf(n_pixels):
    """The Hann intensity PSF on a midpoint grid of 1/1024 pixel over +-12 pixels."""
    spectrum = _scan.hann_spectrum(n_pixels)
    n = np.arange(n_pixels) - n_pixels // 2
    u = (np.arange(-12 * 1024, 12 * 1024) + 0.5) / 1024
    w = np.abs(np.exp(-2j * np.pi * np.outer(u, n) / n_pixels) @ spectrum) ** 2
    return u, w / w.sum()


def exact_rows(n_pixels, q, t, layers):
    """``ln`` of the rows' mean intensity at rows ``q`` (pixels) for a boundary at ``t``: the
    Hann intensity PSF ``|sum_n S_n e^{-2 pi i n u/N}|^2`` summed directly on a midpoint grid
    of 1/1024 pixel over +-12 pixels (the step within half a sample), layers ``exp(i + s z)``
    of scatterers normalised so that each alone gives rows ``exp(i + s z_q)``."""
    u, w = fine_psf(n_pixels)
    z = q[:, None] + u[None, :]
    (s1, i1), (s2, i2) = layers
    upper = np.exp(i1 + s1 * z) / np.sum(w * np.exp(s1 * u))
    lower = np.exp(i2 + s2 * z) / np.sum(w * np.exp(s2 * u))
    return np.log(np.sum(w * np.where(z < t, upper, lower), axis=1))


@pytest.mark.parametrize("n_pixels", [256, 601])
@pytest.mark.parametrize(
    "s1, s2, step", [(0.0, 0.0, 2.0), (-0.1, -0.1, -2.0), (-0.01, -0.3, 2.0), (-0.3, -0.01, -2.0)]
)
def test_transition_model_places_the_boundary(n_pixels, s1, s2, step):
    """The boundary fitted to the exact rows (the fit's 4 transition rows, its layers' lines
    known) lies within 0.003 pixel of the truth for slopes of ln I up to 0.3 per pixel (2 mu p
    of a strongly attenuating layer), where the PSF's plain cumulative weight put it 1/16
    pixel high and ignoring the layers' tilt under the PSF moves it by s sigma^2 (0.1 pixel at
    s = 0.3; sigma^2 = 0.336 pixel^2). The reference's grid places the step within 1/2048
    pixel, the model's linear interpolation of G on 1/64 pixel errs by ~ (1/64)^2/8 of G''
    (< 1e-4 of the step): 0.003 pixel holds both with a margin."""
    model = TransitionModel(n_pixels)
    for t in (50.0, 50.3, 50.5):
        q = np.arange(49.0, 53.0)
        i2 = s1 * t - s2 * t + step
        rows = exact_rows(n_pixels, q, t, [(s1, 0.0), (s2, i2)])

        def misfit(tt, q=q, rows=rows, i2=i2):
            return float(np.sum((model.log_mean(q, tt, s1, 0.0, s2, i2, 1.0) - rows) ** 2))

        got = optimize.minimize_scalar(misfit, bounds=(48.0, 54.0), method="bounded",
                                       options={"xatol": 1e-7}).x  # fmt: skip
        assert abs(got - t) < 3e-3, (t, got)


def test_transition_model_cumulative():
    """G(v; 0) is the PSF's cumulative intensity: 1/2 at 0, symmetric, and the Hann PSF's
    variance sigma^2 = int v^2 dG = 0.336 pixel^2 (the s sigma^2 shift's scale)."""
    model = TransitionModel(256)
    v = np.linspace(-6, 6, 97)
    g = model.cdf(v)
    assert model.cdf(0.0) == pytest.approx(0.5, abs=1e-12)
    np.testing.assert_allclose(g + g[::-1], 1.0, atol=1e-12)
    variance = float(np.sum(model.w * model.u**2) / np.sum(model.w))
    assert variance == pytest.approx(0.336, abs=0.001)
    # two equal layers are one: the rows follow the line whatever the boundary
    z = np.arange(40.0, 60.0)
    np.testing.assert_allclose(model.log_mean(z, 50.3, -0.2, 1.0, -0.2, 1.0, 1.0), 1.0 - 0.2 * z,
                               atol=1e-12)  # fmt: skip


def two_layers(tilt, curvature, seed, ratio):
    coefficients = np.array([[REDUCED.depth_range / 3, tilt, curvature]])
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    table, _ = patient_table(REDUCED, coefficients, np.ones(2), np.array([0.2, 0.2 * ratio]),
                             None, rng)  # fmt: skip
    return speckle.synthoct_scan(table, REDUCED).values, coefficients


@pytest.mark.parametrize(
    "seed, ratio, flat_layers, shapes",
    [(5, 4.0, 2, ("tilted", "curved")), (6, 0.25, 3, ("tilted",))],
)
def test_tilted_ramp_is_one_boundary(seed, ratio, flat_layers, shapes):
    """A steep tilt (0.15: 106 µm, 18 pixels, across the fitted lines) is fitted as one
    tilted boundary: two layers, the boundary within a pixel on every fitted line. The flat
    fit sees the dimming sweep as a ramp between two boundaries (three layers), not the
    brightening one (4 times brighter below: a segment rising with depth is no layer's).
    There (seed 5) the shapes' BIC takes curved, its curvature -1.5e-5 +- 4.1e-5 /µm (the
    Wald of ``(b, c)`` together: ``b^2/(var b (1 - rho^2))`` where they correlate; the nested
    Wald of ``c`` alone, tried, placed 159 against 163 of 170 challenge boundaries within a
    pixel): its curvature within 2 SE of 0. The dimming sweep (seed 6) stays tilted."""
    scan, coefficients = two_layers(0.15, 0.0, seed, ratio)
    central = np.abs(REDUCED.line_positions) <= REDUCED.x_max / 2 - 3 * REDUCED.beam_radius
    assert _fit_levels(scan[:, central], REDUCED, 5, 16).sizes["layer"] == flat_layers
    layers = speckle.fit_phantom(scan, REDUCED).layers
    assert layers.sizes["layer"] == 2 and str(layers.shape.values[1]) in shapes
    if str(layers.shape.values[1]) == "curved":
        assert abs(float(layers.top_curvature[1])) <= 2 * float(layers.top_curvature_se[1])
    x = REDUCED.line_positions[central]
    got = fit_profiles(layers, x, REDUCED.x_max)[1]
    assert np.max(np.abs(got - profiles(coefficients, x, REDUCED.x_max)[0])) < REDUCED.pixel_size


@pytest.mark.parametrize("d", [1, 2, 3])
def test_joint_search_reaches_the_exact_shape(d):
    """The blocks' misfits ``(tau - t_b)^2`` with every ``t_b`` on the quarter-pixel grid
    and on a flat, tilted or curved shape: their interpolated sum is 0 at that shape only
    (each term's interpolant vanishes at its node alone), so the search (its tolerance 1e-9
    pixel at the blocks' edge) ends on the shape's coefficients, from a start 2 pixels off
    at the edge, within 1e-6 pixel there (the blocks within 3e-6 pixel: misfit below
    16 step 3e-6 p)."""
    p, step, x_max = 2.0, 0.5, 960.0
    taus = 100.0 + step * np.arange(160)
    xb = (np.arange(16) - 7.5) * 60.0
    half = x_max / 2
    basis = np.column_stack([np.ones(16), xb, xb**2 - x_max**2 / 12])
    # b x_b and c x_b^2 differ by whole grid steps between blocks; a puts them on the nodes
    theta = np.array([taus[80], step / 60.0, 2 * step / 3600.0])[:d]
    u0 = (basis[0, :d] @ theta - taus[0]) / step
    theta[0] -= (u0 - np.rint(u0)) * step
    t_b = basis[:, :d] @ theta
    assert np.allclose((t_b - taus[0]) / step, np.rint((t_b - taus[0]) / step), atol=1e-9)
    rss = (taus[None, :] - t_b[:, None]) ** 2
    steps = np.array([p, p / half, p / half**2])
    start = theta + 2 * steps[:d]
    got, misfit = _joint(rss, taus, basis, start, steps)
    assert np.max(np.abs((got - theta) / steps[:d])) < 1e-6
    # each block's interpolant rises by step |delta| for a shift delta off its node
    assert misfit < 16 * step * 3e-6 * p


def test_contrast_change_point_is_the_two_level_least_squares():
    """The contrast's misfit at each trial position is the least squares of one level above
    and one below (brute force: the two sides' sums of squared deviations), inf where a side
    has fewer than 2 rows; least at the step of a noiseless profile."""
    rng = np.random.default_rng(3)
    z = np.arange(40) * 2.2
    lv = rng.normal(size=z.size) + np.where(z > 50.0, 1.5, 0.0)
    taus = np.arange(-3.0, 90.0, 0.55)
    got = _contrast_rss(lv, z, taus)
    for tau, value in zip(taus, got, strict=True):
        above, below = lv[z < tau], lv[z >= tau]
        if min(above.size, below.size) < 2:
            assert value == np.inf
        else:
            want = np.sum((above - above.mean()) ** 2) + np.sum((below - below.mean()) ** 2)
            assert value == pytest.approx(want, rel=1e-9, abs=1e-9)
    step = np.where(z > 50.0, 1.5, 0.0)
    clean = _contrast_rss(step, z, taus)
    assert np.min(clean) == pytest.approx(0.0, abs=1e-9)
    assert np.all((taus[clean < 1e-9] > z[z <= 50.0][-1]) & (taus[clean < 1e-9] <= 52.8))
