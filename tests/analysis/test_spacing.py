"""Spacing (pixel size, A-line pitch) is read from coordinates only, never from attributes."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.scene.deformation import pixel_displacement

N, H = 32, 256.0  # pixels, depth_range (µm): p = 8 µm


@pytest.fixture(scope="module")
def img():
    src = speckle.spectrum(N, H, k0_dk=10)
    scene = speckle.random_scatterers(6, 4.0, n_pixels=N, depth_range=H, seed=3)
    return speckle.bscan(scene, src)


def test_compensate_takes_the_pixel_size_from_the_depth_coordinate(img):
    """``uz`` = one pixel ``p``: the compensated field is the field one pixel deeper,
    ``A(q + 1) exp(-2i k0 p)`` (band-limited interpolation is exact at integer shifts,
    periodic over ``N``). Attributes saying ``H = 2 H`` (pixel ``2p``, a half-pixel shift)
    are ignored: the coordinate rules."""
    p, field = H / N, img.field.transpose("depth", "x")
    wrong = img.assign_attrs(depth_range=2 * H, n_pixels=N // 2, pixel_size=2 * p)
    disp = pixel_displacement(lambda z, x: p + 0 * z, img.depth, img.x)
    out = speckle.compensate(wrong, disp).transpose("depth", "x")
    expected = np.roll(field.values, -1, axis=0) * np.exp(-2j * img.attrs["k0"] * p)
    np.testing.assert_allclose(out.values, expected, rtol=0, atol=1e-9 * np.abs(expected).max())


def test_compensate_takes_the_pitch_from_the_aline_coordinate(img):
    """``ux`` = one pitch: each pixel comes from the next A-line (NaN past the last one),
    whatever an ``aline_pitch`` attribute says."""
    field = img.field.transpose("depth", "x")
    pitch = float(img.x[1] - img.x[0])
    wrong = img.assign_attrs(aline_pitch=10 * pitch)
    disp = pixel_displacement(lambda z, x: (0 * z, pitch + 0 * z), img.depth, img.x)
    out = speckle.compensate(wrong, disp, carrier=False).transpose("depth", "x")
    # uz = 0 samples at the integer pixels: exact up to the FFT round trip (~N eps)
    scale = np.abs(field.values).max()
    np.testing.assert_allclose(out.values[:, :-1], field.values[:, 1:], rtol=0, atol=1e-12 * scale)
    assert np.all(np.isnan(out.values[:, -1]))


@pytest.mark.parametrize(
    ("change", "match"),
    [
        (lambda f: f.drop_vars("depth"), "'depth' coordinate missing"),
        (lambda f: f.drop_vars("x"), "'x' coordinate missing"),
        (
            lambda f: f.assign_coords(depth=f.depth.values**1.01),
            "coordinate 'depth' must be increasing and uniformly spaced",
        ),
    ],
)
def test_compensate_refuses_missing_or_non_uniform_coordinates(img, change, match):
    disp = xr.Dataset({"uz": xr.zeros_like(img.field.real)})
    with pytest.raises(ValueError, match=match):
        speckle.compensate(change(img), disp)


def _image(**coords):
    rng = np.random.default_rng(0)
    return xr.DataArray(
        rng.exponential(size=(48, 170)),
        dims=("depth", "x"),
        coords=coords,
        attrs={"kind": "intensity", "pixel_size": 5.0, "pitch": 4.0},
    )


@pytest.mark.parametrize(
    ("coords", "match"),
    [
        ({}, "no 'depth' coordinate"),
        ({"depth": np.arange(48) * 5.0}, "no 'x' coordinate"),
        (
            {"depth": ("depth", np.arange(48.0), {"units": "pixel"}), "x": np.arange(170) * 4.0},
            "coordinate 'depth' is in 'pixel', not µm",
        ),
        (
            {"depth": np.arange(48) * 5.0, "x": np.r_[0.0, np.arange(1, 170) * 4.0 + 1]},
            "coordinate 'x' must be increasing and uniformly spaced",
        ),
    ],
)
def test_fit_system_reads_the_spacing_from_coordinates_only(coords, match):
    """``pixel_size``/``pitch`` attributes do not stand in for the coordinates."""
    with pytest.raises(ValueError, match=match):
        speckle.fit_system(_image(**coords), region={"depth": [8, 48]}, noise_rows=[0, 8])


def test_fit_system_uses_the_coordinates_where_the_attributes_disagree():
    rng = np.random.default_rng(0)
    image = xr.DataArray(
        rng.exponential(size=(24, 20)),
        dims=("depth", "x"),
        coords={"depth": np.arange(24) * 5.0, "x": np.arange(20) * 4.0},
        attrs={"kind": "intensity", "pixel_size": 7.0, "pitch": 3.0},
    )
    fit = speckle.fit_system(
        image, region={"depth": [6, 24]}, noise_rows=[0, 6], max_lag=3, n_blocks=4
    )
    assert fit.parameters.attrs["pixel_size"] == pytest.approx(5.0, rel=1e-12)
    assert fit.parameters.attrs["pitch"] == pytest.approx(4.0, rel=1e-12)
