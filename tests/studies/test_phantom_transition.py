"""The boundary's transition model with the layers' sparse-speckle offsets (issue 34)."""

from __future__ import annotations

import numpy as np
import pytest

import speckle

# private: the slab theory and the offsets it gives (private module _density)
from speckle.studies.phantom._density import log_offsets, slab_log_moments

# private: the transition model and its offsets are what is under test
from speckle.studies.phantom._shapes import TransitionModel

CFG = speckle.synthoct_config("2025")


@pytest.mark.parametrize("factor", [0.3, 1.0, 3.0])
def test_log_offsets_invert_the_slab_theory(factor):
    """``E ln(I/<I>)`` from ``var ln I`` is the slab theory's at the density of that variance
    (both from :func:`slab_log_moments`: the inversion's round trip, to the root's accuracy)."""
    density = factor * 255_000 / (3000.0 * 12.0 * 601 * 2.2)  # the 2025 config's mean density
    mean, variance = slab_log_moments(density, CFG)
    assert log_offsets([variance], CFG)[0] == pytest.approx(mean, abs=1e-6)


def test_log_offsets_dense_and_undetermined():
    """Fully developed speckle (``var ln I <= pi^2/6``) and NaN: ``-gamma``."""
    out = log_offsets([np.pi**2 / 6, 1.0, np.nan], CFG)
    np.testing.assert_allclose(out, -np.euler_gamma, rtol=0, atol=1e-12)


def test_transition_with_offsets():
    """Far from the boundary the model is each layer's own line, whatever the offsets; equal
    offsets change nothing (a common factor of the mean intensities); unequal ones mix the
    layers' mean intensities and add their intensity-weighted offsets."""
    model = TransitionModel(CFG.n_pixels)
    p = CFG.pixel_size
    z = np.arange(0, 60) * p
    t, s1, i1, s2, i2 = 30.3 * p, -0.01, -2.0, -0.02, 0.5
    plain = model.log_mean(z, t, s1, i1, s2, i2, p)
    same = model.log_mean(z, t, s1, i1, s2, i2, p, [-0.9, -0.9])
    np.testing.assert_allclose(same, plain, rtol=0, atol=1e-12)
    mixed = model.log_mean(z, t, s1, i1, s2, i2, p, [-1.4, -0.6])
    far_up, far_down = z < t - 20 * p, z > t + 20 * p
    np.testing.assert_allclose(mixed[far_up], (i1 + s1 * z)[far_up], rtol=0, atol=1e-6)
    np.testing.assert_allclose(mixed[far_down], (i2 + s2 * z)[far_down], rtol=0, atol=1e-6)
    # the mixed rows: the layers' mean intensities through the PSF's shares, plus the
    # intensity-weighted E ln(I/<I>)
    m1 = np.exp(i1 + s1 * z + 1.4) * model.cdf((t - z) / p, s1 * p)
    m2 = np.exp(i2 + s2 * z + 0.6) * (1 - model.cdf((t - z) / p, s2 * p))
    expected = np.log(m1 + m2) + (-1.4 * m1 - 0.6 * m2) / (m1 + m2)
    np.testing.assert_allclose(mixed, expected, rtol=0, atol=1e-9)


@pytest.mark.parametrize("offsets", [None, (-0.9, -0.6)])
def test_blocks_rss_is_log_means(offsets):
    """The blocks' misfit tables (computed per group of trial positions, the PSF's shares only
    near each) are, bit for bit, the least squares of :meth:`TransitionModel.log_mean` at the
    trial positions (all at once) with the levels from the rows more than 3 pixels away."""
    # private: the mixed rows the blocks' misfit tables use
    from speckle.studies.phantom._mixing import mixed_rows

    # private: the blocks' misfit tables and their constants are under test
    from speckle.studies.phantom._shapes import _LEVEL_ROWS, _blocks_rss

    model, mixing = TransitionModel(CFG.n_pixels), mixed_rows(CFG)
    p, s1, s2 = CFG.pixel_size, -0.01, -0.05
    z = np.arange(40, 100) * p
    rng = np.random.default_rng(3)
    mbs = np.where(z < 70.3 * p, 2.0 + s1 * z, -1.0 + s2 * z) + rng.normal(0, 0.3, (3, z.size))
    taus = np.arange(z[0], z[-1], p / 4)
    got = _blocks_rss(mbs, z, taus, s1, s2, p, model, offsets, mixing)
    above = z < taus[:, None] - _LEVEL_ROWS * p  # (taus, rows)
    below = z > taus[:, None] + _LEVEL_ROWS * p
    n1, n2 = above.sum(axis=1), below.sum(axis=1)
    ok = (n1 >= 2) & (n2 >= 2)
    assert np.all(got[:, ~ok] == np.inf)
    above, below, n1, n2 = above[ok], below[ok], n1[ok], n2[ok]
    for mb, row in zip(mbs, got, strict=True):
        i1 = np.where(above, mb - s1 * z, 0.0).sum(axis=1) / n1
        i2 = np.where(below, mb - s2 * z, 0.0).sum(axis=1) / n2
        t, i1, i2 = taus[ok, None], i1[:, None], i2[:, None]
        pred = model.log_mean(z, t, s1, i1, s2, i2, p, offsets, mixing)
        np.testing.assert_array_equal(row[ok], np.sum((mb - pred) ** 2, axis=1))
