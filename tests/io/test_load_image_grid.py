"""speckle.load_image(k0=): a loaded image carries its grid, so strain needs no ``k0=``.

The user's path: a measured complex pair saved to a file, loaded once with the scanner's ``k0``,
then passed to ``estimate_strain``/``accumulate_strain`` without ``k0``. Exact check: the same
numbers, bit for bit, as the explicit call on the numpy values (the grid changes where ``k0``
comes from, never the arithmetic). A file that stores ``k0`` (a package-made image written to
NetCDF) gives it; a different ``k0=`` is refused.
"""

from __future__ import annotations

import numpy as np
import pytest

import speckle
from speckle.conventions import grid

N, H = 64, 512.0  # pixels, depth range (µm): pixel 8 µm


@pytest.fixture(scope="module")
def pair(compressed_pair):
    """A 0 and 0.4 % compression of one scene (N x 16 px over H), as a (frame, depth, x) field."""
    src, img = compressed_pair
    return float(src.attrs["k0"]), img.field.rename(strain="frame")


def test_loaded_with_k0_strain_without_k0_equals_the_explicit_call(pair, tmp_path):
    k0, field = pair
    np.save(tmp_path / "pair.npy", field.values)
    frames = speckle.load_image(
        tmp_path / "pair.npy",
        kind="complex",
        pixel_size=H / N,
        pitch=4.0,
        dims=("frame", "depth", "x"),
        k0=k0,
    )
    assert frames.attrs["k0"] == k0 and frames.attrs["k0_units"] == "rad/um"
    assert grid(frames[0]).k0 == k0 and grid(frames[0]).pixel_size == H / N
    kw = {"k0": k0, "pixel_size": H / N}
    ref, dfm = field.values
    read = speckle.estimate_strain(frames[0], frames[1], window=(16, 4))
    np.testing.assert_array_equal(
        read.values, speckle.estimate_strain(ref, dfm, window=(16, 4), **kw)
    )
    assert 0.003 < float(np.nanmedian(read)) < 0.005  # the applied 4e-3 (window noise)
    acc = speckle.accumulate_strain(frames, window=(16, 4))
    explicit = speckle.accumulate_strain(field.values, window=(16, 4), **kw)
    for var in ("interframe", "accumulated"):
        np.testing.assert_array_equal(acc[var].values, explicit[var])


@pytest.mark.parametrize(
    ("bad", "error"),
    [
        (0.0, ValueError),
        (-1.0, ValueError),
        (np.nan, ValueError),
        (np.inf, ValueError),
        ("10", TypeError),
        (True, TypeError),
    ],
)
def test_bad_k0_is_refused_naming_it_before_the_file_is_read(bad, error, tmp_path):
    with pytest.raises(error, match="k0"):
        speckle.load_image(tmp_path / "absent.npy", kind="complex", k0=bad)


def test_a_file_storing_k0_gives_it_and_refuses_a_different_one(pair, tmp_path):
    k0, field = pair
    path = tmp_path / "pair.nc"
    field.to_dataset(name="field").to_netcdf(path, engine="netcdf4", auto_complex=True)
    frames = speckle.load_image(path, kind="complex")  # dims and µm coordinates from the file
    g = grid(frames)
    assert (g.k0, g.n_pixels, g.depth_range, g.pixel_size) == (k0, N, H, H / N)
    same = speckle.load_image(path, kind="complex", k0=k0 * (1 + 1e-12))  # agrees within 1e-9
    assert same.attrs["k0"] == k0  # the file's value is kept
    with pytest.raises(ValueError, match=r"k0 = 1\.0 rad/µm contradicts the k0 = .* stored in"):
        speckle.load_image(path, kind="complex", k0=1.0)
    read = speckle.estimate_strain(frames[0], frames[1], window=(16, 4))
    explicit = speckle.estimate_strain(*field.values, window=(16, 4), k0=k0, pixel_size=H / N)
    np.testing.assert_array_equal(read.values, explicit)


def test_without_k0_a_measured_image_has_no_grid_attributes(pair, tmp_path):
    _, field = pair
    np.save(tmp_path / "one.npy", field.values[0])
    image = speckle.load_image(
        tmp_path / "one.npy", kind="complex", pixel_size=8.0, pitch=4.0, dims=("depth", "x")
    )
    assert not {"k0", "k0_units", "n_pixels", "depth_range"} & set(image.attrs)


def test_a_file_storing_a_bad_k0_is_refused_naming_it(pair, tmp_path):
    _, field = pair
    path = tmp_path / "bad.nc"
    field.assign_attrs(k0=-1.0).to_dataset(name="field").to_netcdf(
        path, engine="netcdf4", auto_complex=True
    )
    with pytest.raises(ValueError, match=r"k0 stored in bad\.nc"):
        speckle.load_image(path, kind="complex")
