"""The challenge's maps: the shipped official PNGs bit for bit, and the estimators' algebra."""

from __future__ import annotations

from pathlib import Path

import numpy as np
import pytest
import xarray as xr
from PIL import Image

import speckle

# private: the PNG colour table and the linearisation tables are checked against their sources
from speckle.synthoct.maps import _LUT, _linear_table

DATA = Path(speckle.__file__).parent / "data" / "synthoct"
SCANS = ("Exp1_Uniform_A", "Exp1_Uniform_B", "Exp2_Layers_A", "Exp2_Layers_B")


def _png(name: str) -> np.ndarray:
    return np.asarray(Image.open(DATA / f"Scan_{name}.png"))[..., 0]


@pytest.mark.parametrize("scan", SCANS)
def test_official_images_equal_the_published_map_pngs(scan):
    """Every pixel of the 12 published maps (RGBA grey PNGs of the processor) is reproduced."""
    maps = speckle.synthoct_maps(DATA / f"Scan_{scan}.png", images=True)
    for name in speckle.MAP_NAMES:
        np.testing.assert_array_equal(maps[name].values, _png(f"{scan}_{name}"), err_msg=name)


def test_gray_table_is_matplotlibs():
    """The PNG's levels come from matplotlib's ``gray`` colormap (24 levels one lower)."""
    import matplotlib

    v = np.linspace(0, 1, 20001, dtype=np.float32)
    expected = matplotlib.colormaps["gray"](v, bytes=True)[:, 0]
    scaled = v * np.float32(256)
    scaled[scaled == 256] = 255
    np.testing.assert_array_equal(_LUT[scaled.astype(int)], expected)
    assert np.count_nonzero(_LUT != np.arange(256)) == 24


def test_linearisation_tables():
    """Official: 10**(4 g/255) of float32 operands; physical: 10**(5.1 g/255) in double.

    The official exponent is float32 (three roundings of at most 2**-24 relative, on x <= 4),
    so I is off by at most ln(10) 4 x 3 x 2**-24 + 2**-24 = 1.7e-6 relative (derived).
    """
    g = np.arange(256)
    official = _linear_table(40.0, True)
    assert official.dtype == np.float32
    np.testing.assert_allclose(official, 10.0 ** (4 * g / 255), rtol=1.7e-6)
    np.testing.assert_allclose(_linear_table(51.0, False), 10.0 ** (5.1 * g / 255), rtol=1e-15)


def _ramp(n_depth=256, n_x=24) -> np.ndarray:
    """A scan falling one grey level per row: a geometric intensity ``I_i = I_0 r**i``."""
    return np.repeat((255 - np.arange(n_depth))[:, None], n_x, axis=1).astype(np.uint8)


@pytest.mark.parametrize(
    ("variant", "db", "rtol"), [("physical", 51.0, 1e-12), ("official", 40.0, 1e-4)]
)
def test_oac_of_a_geometric_decay(variant, db, rtol):
    """OAC_i = 1/(2h((1 - r**n)/(1 - r) - 1/2)), n = N - i rows from i to the bottom (derived).

    The last row is 1/h whatever the tissue (no tail below the image); far from the bottom the
    estimate is tanh(mu h)/h of the true mu = -ln(r)/(2h). float32 sums: rtol 1e-4 (official).
    """
    h = 6.0
    oac = speckle.synthoct_maps(_ramp(), variant=variant).OAC.values
    r = 10.0 ** (-db / 10 / 255)
    n = 256 - np.arange(256)
    intensity = 10 ** (db / 10 * (255 - np.arange(256)) / 255)
    # the processor's 1e-10 guard added to the sum (2e-10 relative at the bottom, I = 1)
    expected = intensity / (2 * h * (intensity * ((1 - r**n) / (1 - r) - 0.5) + 1e-10))
    np.testing.assert_allclose(oac, np.repeat(expected[:, None], 24, axis=1), rtol=rtol)
    assert oac[-1, 0] == pytest.approx(1 / h, rel=max(rtol, 3e-10))  # 1/h up to the guard
    mu = -np.log(r) / (2 * h)
    # the top row misses only the tail r**256 = 8e-6 (relative, 2 r**256 in mu)
    assert expected[0] == pytest.approx(np.tanh(mu * h) / h, rel=2 * r**256)


def test_official_oac_is_forty_over_fiftyone_of_the_physical():
    """The 40 dB linearisation raises I to the power 40/51: mu h -> (40/51) mu h (derived).

    Top row: OAC = tanh(mu h)/h up to its missing tail (2 r**256: 2e-4 at 40 dB), so the ratio
    is tanh(40/51 x)/tanh(x), x = ln(10) 5.1/255/2, which is
    40/51 (1 + x**2 (1 - (40/51)**2)/3) = 40/51 (1 + 7e-5).
    """
    official = float(speckle.synthoct_maps(_ramp()).OAC[0, 0])
    physical = float(speckle.synthoct_maps(_ramp(), variant="physical").OAC[0, 0])
    x = np.log(10) * 5.1 / 255 / 2
    assert official / physical == pytest.approx(np.tanh(40 / 51 * x) / np.tanh(x), rel=3e-4)
    assert np.tanh(40 / 51 * x) / np.tanh(x) == pytest.approx(
        40 / 51 * (1 + x**2 * (1 - (40 / 51) ** 2) / 3), rel=1e-6
    )  # O(x**4) = 3e-7


@pytest.mark.parametrize("variant", ["official", "physical"])
def test_contrast_of_a_checkerboard(variant):
    """Two levels in a checkerboard: every 20x20 window holds 200 of each, SC = |I1-I2|/(I1+I2)."""
    i, j = np.indices((64, 80))
    scan = np.where((i + j) % 2, 200, 100).astype(np.uint8)
    maps = speckle.synthoct_maps(scan, variant=variant)
    db = 40.0 if variant == "official" else 51.0
    i1, i2 = 10 ** (db / 10 * 100 / 255), 10 ** (db / 10 * 200 / 255)
    np.testing.assert_allclose(maps.SC.values, (i2 - i1) / (i2 + i1), rtol=1e-5)
    assert np.all(maps.RSC.values > 0)


def test_constant_scan_has_zero_contrast():
    maps = speckle.synthoct_maps(np.full((40, 40), 128, np.uint8))
    assert np.all(maps.SC.values == 0)


def test_physical_images_keep_the_stated_limits():
    """SC = 2.75 on the limits 0.5..5 is level floor(256 x 0.5) = 128 (physical: no re-stretch)."""
    i, j = np.indices((64, 80))
    scan = np.where((i + j) % 2, 200, 100).astype(np.uint8)
    values = speckle.synthoct_maps(scan, variant="physical")
    images = speckle.synthoct_maps(scan, variant="physical", images=True)
    sc = float(values.SC[30, 30])
    assert int(images.SC[30, 30]) == _LUT[int(256 * (sc - 0.5) / 4.5)]
    official = speckle.synthoct_maps(scan, images=True)
    assert np.all(official.SC.values == 0)  # constant map: imsave's stretch gives level 0


def test_inputs_agree_and_dataarray_keeps_coordinates():
    path = DATA / "Scan_Exp2_Layers_B.png"
    grey = _png("Exp2_Layers_B")
    da = xr.DataArray(
        grey, dims=("depth", "x"), coords={"depth": 3.0 * np.arange(256), "x": np.arange(512.0)}
    )
    a = speckle.synthoct_maps(path)
    b = speckle.synthoct_maps(grey)
    c = speckle.synthoct_maps(da)
    xr.testing.assert_equal(a, b)
    np.testing.assert_array_equal(a.OAC.values, c.OAC.values)  # official: 6 µm whatever
    assert c.depth.values[1] == 3.0
    d = speckle.synthoct_maps(da, variant="physical")
    assert d.attrs["pixel_size_um"] == 3.0
    assert a.OAC.attrs["units"] == "1/um" and a.SC.attrs["units"] == "1"
    assert a.depth.values[1] == 6.0 and a.x.values[0] == -1536.0


@pytest.mark.parametrize(
    ("kwargs", "error", "word"),
    [
        ({"scan": np.zeros((40, 40), np.uint16)}, TypeError, "scan"),
        ({"scan": np.zeros((40, 40))}, TypeError, "scan"),
        ({"scan": np.zeros((0, 40), np.uint8)}, ValueError, "scan"),
        ({"scan": np.zeros((4, 40, 3), np.uint8)}, ValueError, "scan"),
        ({"scan": [[1, 2], [3, 4]]}, TypeError, "scan"),
        ({"scan": "no_such.png"}, ValueError, "scan"),
        ({"scan": np.zeros((15, 40), np.uint8)}, ValueError, "window"),
        ({"variant": "exact"}, ValueError, "variant"),
        ({"window": 1}, ValueError, "window"),
        ({"dynamic_range": 0.0}, ValueError, "dynamic_range"),
        ({"pixel_size": -6.0}, ValueError, "pixel_size"),
        ({"images": "yes"}, TypeError, "images"),
    ],
)
def test_bad_input_is_refused(kwargs, error, word):
    kwargs = {"scan": np.zeros((40, 40), np.uint8), **kwargs}
    with pytest.raises(error, match=word):
        speckle.synthoct_maps(**kwargs)


def test_colour_png_is_refused(tmp_path):
    rgb = np.zeros((30, 30, 3), np.uint8)
    rgb[..., 0] = 9
    Image.fromarray(rgb).save(tmp_path / "c.png")
    with pytest.raises(ValueError, match="colour"):
        speckle.synthoct_maps(tmp_path / "c.png")
    Image.fromarray(np.zeros((30, 30), np.uint16)).save(tmp_path / "w.png")
    with pytest.raises(TypeError, match="8-bit"):
        speckle.synthoct_maps(tmp_path / "w.png")
