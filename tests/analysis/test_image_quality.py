"""Image-quality metrics on profiles and images with known answers."""

from __future__ import annotations

import numpy as np
import pytest
import scipy.special as sp

from speckle.analysis import image_quality as iq


def test_peak_fwhm_of_a_gaussian():
    x = np.arange(200) * 0.1
    s = 1.3
    y = np.exp(-((x - 10.0) ** 2) / (2 * s**2))
    assert iq.peak_fwhm(y, 0.1) == pytest.approx(2 * np.sqrt(2 * np.log(2)) * s, rel=1e-3)


def test_edge_width_of_an_error_function():
    x = np.arange(100.0)
    s = 2.5
    y = 1 + 3 * sp.ndtr((x - 47.3) / s)
    assert iq.edge_width(y) == pytest.approx(2.5631 * s, rel=1e-3)
    assert iq.EDGE_10_90 == pytest.approx(2.5631, abs=1e-4)


def test_bandlimited_interpolation_is_exact_for_eq4():
    n, k = 16, 8
    rng = np.random.default_rng(0)
    g = rng.standard_normal(n) + 1j * rng.standard_normal(n)
    idx = np.arange(n) - n // 2
    q = np.arange(n * k) / k
    exact = (g[None, :] * np.exp(-2j * np.pi * idx[None, :] * q[:, None] / n)).sum(1)
    np.testing.assert_allclose(iq.bandlimited(exact[::k], k), exact, atol=1e-12)


def test_contrast_enl_cnr_psnr_ssim():
    rng = np.random.default_rng(2)
    img = rng.exponential(1.0, (128, 128))
    mask = np.ones_like(img, bool)
    assert iq.enl(img, mask) == pytest.approx(1 / iq.contrast(img, mask) ** 2)
    db = iq.to_db(img, 1.0)
    a = np.zeros_like(mask)
    a[:64] = True
    shifted = db + np.where(a, 10.0, 0.0)
    diff = abs(10 + db[a].mean() - db[~a].mean())
    assert iq.cnr(shifted, a, ~a) == pytest.approx(diff / np.sqrt(db[a].var() + db[~a].var()))
    assert iq.ssim_db(db, db) == pytest.approx(1.0)
    assert iq.psnr_db(db + 0.4, db, db_top=50, db_range=100) == pytest.approx(
        20 * np.log10(100 / 0.4), rel=1e-9
    )
    with pytest.raises(ValueError, match="mask"):
        iq.contrast(img, mask[:3])
