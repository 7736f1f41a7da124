"""Light source: wavenumber grid, spectrum shapes and k0/delta_k."""

from __future__ import annotations

import numpy as np
import pytest

import speckle
from speckle.system.source import k0_from_wavelength, spectral_index, spectrum, wavelength_from_k0


def test_wavenumber_grid_and_attrs():
    s = spectrum(256, 2048.0, k0_dk=10)
    dk = 256 * np.pi / 2048.0
    assert s.dims == ("wavenumber",) and s.sizes["wavenumber"] == 256
    np.testing.assert_allclose(np.diff(s.wavenumber), np.pi / 2048.0)
    assert s.n.values[0] == -128 and s.n.values[-1] == 127
    assert s.attrs["k0"] == pytest.approx(10 * dk) and s.attrs["k0_dk"] == pytest.approx(10)
    assert s.wavenumber.attrs["units"] == "rad/um"
    np.testing.assert_array_equal(s.values, 1.0)


def test_coherence_length_over_wavelength_equals_k0_over_delta_k():
    """Lc = 2 pi / delta_k and lambda0 = 2 pi / k0, so Lc/lambda0 = k0/delta_k."""
    s = spectrum(256, 2048.0, wavelength=1.0)
    lc = 2 * np.pi / s.attrs["delta_k"]
    assert lc / 1.0 == pytest.approx(s.attrs["k0_dk"])
    assert lc == pytest.approx(2 * 2048.0 / 256)  # two pixels


def test_wavelength_and_refractive_index():
    assert k0_from_wavelength(1.3, 1.4) == pytest.approx(2 * np.pi * 1.4 / 1.3)
    assert wavelength_from_k0(k0_from_wavelength(0.84, 1.38), 1.38) == pytest.approx(0.84)
    s = spectrum(64, 512.0, wavelength=1.3, refractive_index=1.4)
    assert s.attrs["k0"] == pytest.approx(2 * np.pi * 1.4 / 1.3)


def test_gaussian_fwhm():
    fwhm = 0.2
    s = spectrum(512, 2048.0, k0=5.0, shape="gaussian", fwhm=fwhm)
    k = s.wavenumber.values
    assert s.values.max() == pytest.approx(1.0)
    half = k[s.values >= 0.5]
    # the half-maximum width on the grid is within one spectral step of the FWHM
    assert abs((half[-1] - half[0]) - fwhm) <= 2 * np.pi / 2048.0


def test_user_array_and_index_order():
    w = np.linspace(0, 1, 16)
    s = spectrum(16, 100.0, k0=1.0, shape="array", weights=w)
    np.testing.assert_array_equal(s.values, w)
    np.testing.assert_array_equal(spectral_index(5), [-2, -1, 0, 1, 2])
    np.testing.assert_array_equal(spectral_index(4), [-2, -1, 0, 1])


@pytest.mark.parametrize(
    ("kwargs", "exc", "match"),
    [
        ({}, ValueError, "exactly one"),
        ({"k0": 1.0, "k0_dk": 2.0}, ValueError, "exactly one"),
        ({"k0": -1.0}, ValueError, "k0"),
        ({"k0_dk": np.nan}, ValueError, "k0_dk"),
        ({"wavelength": 0.0}, ValueError, "wavelength"),
        ({"k0": 1.0, "shape": "triangle"}, ValueError, "shape"),
        ({"k0": 1.0, "shape": "gaussian"}, ValueError, "fwhm"),
        ({"k0": 1.0, "shape": "gaussian", "fwhm": -1.0}, ValueError, "fwhm"),
        ({"k0": 1.0, "shape": "array"}, ValueError, "weights"),
        ({"k0": 1.0, "shape": "array", "weights": np.ones(3)}, ValueError, "n_pixels=8"),
        ({"k0": 1.0, "shape": "array", "weights": np.zeros(8)}, ValueError, "zero"),
        ({"k0": 1.0, "fwhm": 1.0}, ValueError, "rectangular"),
    ],
)
def test_bad_source_input(kwargs, exc, match):
    with pytest.raises(exc, match=match):
        spectrum(8, 64.0, **kwargs)


def test_delta_k_validation():
    with pytest.raises(ValueError, match="n_pixels"):
        speckle.delta_k(1, 10.0)
    with pytest.raises(ValueError, match="depth"):
        speckle.delta_k(10, -1.0)
