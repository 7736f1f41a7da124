"""Digital speckle filters: every filter on linear and log data, their checks, Lee/Kuan/Frost."""

from __future__ import annotations

import numpy as np
import pytest

from speckle.analysis import filters as ds

RUNNABLE = [f for f in ds.FILTERS if ds.filter_available(f)]


@pytest.fixture(scope="module")
def speckle_image():
    rng = np.random.default_rng(1)
    return rng.exponential(1.0, (96, 96))  # fully developed speckle, one look


@pytest.mark.parametrize("domain", ds.DOMAINS)
@pytest.mark.parametrize("name", RUNNABLE)
def test_every_filter_lowers_the_contrast(speckle_image, name, domain):
    out = ds.despeckle(speckle_image, name, domain=domain)
    assert out.shape == speckle_image.shape and np.all(out >= 0) and np.all(np.isfinite(out))
    c_in = speckle_image.std() / speckle_image.mean()
    assert out.std() / out.mean() < 0.8 * c_in, name


@pytest.mark.parametrize("name", ["lee", "kuan", "frost", "median", "tv", "nlm", "bilateral"])
def test_a_constant_image_is_unchanged(name):
    img = np.full((32, 32), 3.0)
    np.testing.assert_allclose(ds.despeckle(img, name), img, rtol=1e-6)


def test_lee_is_the_local_mean_in_developed_speckle_and_keeps_structure(speckle_image):
    """In speckle whose local contrast exceeds C_u = 1 the gain k is ~0: the local mean."""
    import scipy.ndimage as ndi

    img = speckle_image * 0.25 + 0.0  # contrast unchanged by scale
    out = ds.lee(img, size=7, looks=1.0)
    mean = ndi.uniform_filter(img, 7, mode="reflect")
    frac = np.mean(np.isclose(out, mean, rtol=0.2))
    assert frac > 0.5
    # a step of 10x in mean with little speckle (100 looks) is kept: k ~ 1 at the edge
    rng = np.random.default_rng(0)
    step = np.where(np.arange(64)[None, :] < 32, 1.0, 10.0) * rng.gamma(100, 1 / 100, (64, 64))
    out = ds.lee(step, size=7, looks=100.0)
    assert out[:, 31].mean() < 2.0 and out[:, 32].mean() > 8.0


@pytest.mark.parametrize(
    "name,params,bad",
    [
        ("median", {"size": 4}, "size"),
        ("median", {"size": 41}, "size"),
        ("nlm", {"h": -1.0}, "h"),
        ("nlm", {"patch_size": 40}, "patch_size"),
        ("tv", {"weight": 0.0}, "weight"),
        ("wavelet", {"wavelet": "haar2"}, "wavelet"),
        ("bilateral", {"sigma_color": 2.0}, "sigma_color"),
        ("lee", {"looks": 0}, "looks"),
        ("frost", {"damping": -2}, "damping"),
        ("kuan", {"window": 3}, "window"),
    ],
)
def test_bad_parameters_are_named(speckle_image, name, params, bad):
    with pytest.raises(ValueError, match=bad):
        ds.despeckle(speckle_image, name, params)


def test_unknown_filter_and_domain_are_named(speckle_image):
    with pytest.raises(ValueError, match="filter"):
        ds.despeckle(speckle_image, "anisotropic")
    with pytest.raises(ValueError, match="domain"):
        ds.despeckle(speckle_image, "median", domain="sqrt")
    with pytest.raises(ValueError, match="intensity"):
        ds.despeckle(-speckle_image, "median")


def test_bm3d_is_optional(speckle_image):
    if ds.filter_available("bm3d"):
        assert ds.despeckle(speckle_image, "bm3d").shape == speckle_image.shape
    else:
        with pytest.raises(ImportError, match="non-commercial"):
            ds.despeckle(speckle_image, "bm3d")
