"""Detection chain: intensity floor and log compression (exact identities)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

from speckle.system.detection import add_floor, log_compress


@pytest.fixture
def intensity():
    rng = np.random.default_rng(0)
    return xr.DataArray(
        rng.exponential(2.0, size=(8, 16)), dims=("depth", "aline"), attrs={"units": "1"}
    )


def test_floor_adds_a_constant_and_keeps_variance(intensity):
    out = add_floor(intensity, 0.01, mean_intensity=2.0)
    np.testing.assert_allclose(out - intensity, 0.02)
    assert float(out.std()) == pytest.approx(float(intensity.std()))
    assert out.attrs["floor"] == 0.01 and out.attrs["units"] == "1"
    default = add_floor(intensity, 0.5)  # relative to the sample mean
    np.testing.assert_allclose(default - intensity, 0.5 * float(intensity.mean()))
    xr.testing.assert_identical(add_floor(intensity, 0.0).drop_attrs(), intensity.drop_attrs())


def test_log_compress_is_gain_log_plus_offset(intensity):
    exact = log_compress(intensity, 20.0, 100.0, bits=None)
    np.testing.assert_allclose(exact, 20.0 * np.log(intensity) + 100.0)
    q = log_compress(intensity, 20.0, 100.0)
    assert np.all(q == np.round(q)) and float(q.min()) >= 0 and float(q.max()) <= 255
    inside = (exact > 0.5) & (exact < 254.5)
    assert float(abs(q - exact).where(inside).max()) <= 0.5
    zero = log_compress(xr.DataArray([0.0, 1.0]), 10.0, 5.0)
    np.testing.assert_array_equal(zero, [0.0, 5.0])  # log(0) -> the low clip
    assert q.attrs["scale"] == "log"


@pytest.mark.parametrize(
    ("call", "match"),
    [
        (lambda i: add_floor(i, -0.1), "floor"),
        (lambda i: add_floor(i, 0.1, mean_intensity=0.0), "mean_intensity"),
        (lambda i: add_floor(np.ones(3), 0.1), "DataArray"),
        (lambda i: log_compress(i, 0.0, 1.0), "gain"),
        (lambda i: log_compress(i, 1.0, np.nan), "offset"),
        (lambda i: log_compress(i, 1.0, 1.0, bits=0), "bits"),
    ],
)
def test_bad_input(intensity, call, match):
    with pytest.raises((ValueError, TypeError), match=match):
        call(intensity)


def test_log_expand_inverts_log_compress(intensity):
    from speckle.system.detection import log_expand

    g, c = 20.0, 100.0
    exact = log_expand(log_compress(intensity, g, c, bits=None), g, c)
    np.testing.assert_allclose(exact, intensity, rtol=1e-13)
    q = log_compress(intensity, g, c)  # 8-bit: rounding error <= 1/2 level inside the clip range
    inside = (q > 0) & (q < 255)
    rel = abs(log_expand(q, g, c) / intensity - 1).where(inside)
    assert float(rel.max()) <= np.exp(0.5 / g) - 1 + 1e-12
    with pytest.raises(ValueError, match="gain"):
        log_expand(q, 0.0, c)
