"""Dynamic-OCT contrasts on Dask-chunked series: lazy, and the numbers of the numpy path.

Every contrast is ``finish(pool(moments))``: per-pixel time averages (block-local once the time
dim is whole in each chunk), pooled over every pixel (``window=None``: a mean, exact up to
summation order) or by a boxcar (``window``: an overlap of ``window // 2`` pixels with the
numpy filter's edge mode, exact up to the running sums' start), then finished pixel by pixel.
So the chunked result equals the numpy one to rounding: checked at 1e-12 of the largest value
for 1, 2 and 4 chunks along ``x`` and for 2 x 2 chunks over ``(depth, x)``, pooled and
windowed, for an odd and an even window; and the result stays a Dask array until computed.
"""

from __future__ import annotations

import warnings

import dask.array as dsa
import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.analysis import dynamics as dy

T, Z, X = 6, 16, 12
RNG = np.random.default_rng(0)
FIELD = xr.DataArray(
    RNG.normal(size=(T, Z, X)) + 1j * RNG.normal(size=(T, Z, X)),
    dims=("time", "depth", "x"),
    coords={"time": np.arange(T) * 0.1, "depth": np.arange(Z) * 8.0, "x": np.arange(X) * 4.0},
)

CONTRASTS = {
    "g1": lambda f, w: dy.g1(f, lags=[0, 1, 3], window=w),
    "g2": lambda f, w: dy.g2(abs(f) ** 2, window=w),
    "doppler_phase": lambda f, w: dy.doppler_phase(f, lag=2, window=w),
    "speckle_variance": lambda f, w: dy.speckle_variance(f, window=w, ddof=1),
    "speckle_variance_log": lambda f, w: dy.speckle_variance(f, window=w, log=True),
    "liv": lambda f, w: dy.liv(abs(f) ** 2, window=w),
    "ssada": lambda f, w: dy.ssada(f, n_bands=3, window=w),
    "ocds": lambda f, w: dy.ocds(abs(f) ** 2, delays=(0.1, 0.4), window=w),
}
CHUNKS = [{"x": X}, {"x": X // 2}, {"x": X // 4}, {"depth": Z // 2, "x": X // 2}]


@pytest.mark.parametrize("window", [None, (3, 5), (4, 2)], ids=["pooled", "odd", "even"])
@pytest.mark.parametrize("name", list(CONTRASTS))
def test_chunked_equals_numpy_and_is_lazy(name, window):
    call = CONTRASTS[name]
    expected = call(FIELD, window)
    assert isinstance(expected.data, np.ndarray)  # numpy in, numpy out
    scale = float(np.max(np.abs(expected.values)))
    for chunks in CHUNKS:
        out = call(FIELD.chunk(chunks), window)
        assert hasattr(out.data, "dask"), (name, chunks)  # lazy until computed
        assert out.dims == expected.dims and out.shape == expected.shape
        np.testing.assert_allclose(
            out.values, expected.values, rtol=1e-12, atol=1e-12 * scale, err_msg=str(chunks)
        )
        for c in expected.coords:
            np.testing.assert_array_equal(out[c].values, expected[c].values)


def test_block_standard_error_is_lazy_and_equal():
    expected = dy.g1(FIELD, lags=[1, 2], blocks=3)
    out = dy.g1(FIELD.chunk({"x": 3}), lags=[1, 2], blocks=3)
    assert hasattr(out.g1_se.data, "dask")
    for var in ("g1", "g1_se"):
        np.testing.assert_allclose(out[var].values, expected[var].values, rtol=1e-12, atol=1e-15)


def test_a_series_chunked_in_time_is_rechunked_whole():
    expected = dy.liv(FIELD, window=(3, 3))
    out = dy.liv(FIELD.chunk({"time": 2, "x": 4}), window=(3, 3))
    np.testing.assert_allclose(out.values, expected.values, rtol=1e-12)


def test_no_answer_warns_when_computed():
    zero = xr.DataArray(np.zeros((3, 4), complex), dims=("time", "x"), coords={"time": [0, 1, 2.0]})
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # nothing is computed at the call
        out = dy.g1(zero.chunk({"x": 2}), lags=[1])
    with pytest.warns(RuntimeWarning, match="no signal"):
        assert np.isnan(out.values).all()


def test_bad_input_is_refused_at_the_call():
    bad = FIELD.copy()
    bad[0, 0, 0] = np.nan
    with pytest.raises(ValueError, match="NaN or infinite"):
        dy.g1(bad.chunk({"x": 4}))
    with pytest.raises(ValueError, match=">= 0"):
        dy.liv(-(abs(FIELD) ** 2).chunk({"x": 4}))


def test_numpy_cores_take_dask_arrays_lazily():
    """The ``*_array`` cores: a Dask array in, a Dask array out, the numpy numbers."""
    f = FIELD.values
    amplitudes = np.abs(np.stack([f, 2 * f[::-1]]))  # (band, time, depth, x)
    for core, arr, kw in [
        (dy.g1_array, f, {"lags": [1, 2], "window": (3, 3)}),
        (dy.g2_array, abs(f) ** 2, {"lags": [1], "window": None}),
        (dy.ssada_array, amplitudes, {"window": (2, 5)}),
        (dy.ssada_array, amplitudes, {"window": None}),
    ]:
        expected = core(arr, **kw)
        chunked = dsa.from_array(arr, chunks=(*arr.shape[:-2], 8, 4))
        out = core(chunked, **kw)
        assert hasattr(out, "dask")
        np.testing.assert_allclose(np.asarray(out), expected, rtol=1e-12, atol=1e-15)


@pytest.mark.parametrize("where", [(7, 3), (0, 0), (19, 19)], ids=["inside", "corner", "far"])
@pytest.mark.parametrize("window", [(3, 3), (4, 2), (3, 4)])
def test_a_pixel_without_answer_makes_nan_only_the_windows_that_hold_it(window, where):
    """One zero-intensity pixel (no logarithm): NaN exactly where the boxcar holds it.

    The boxcar of size ``w`` at output pixel ``c`` covers ``c - w//2 ... c - w//2 + w - 1``,
    so the NaN rows are ``r0 - w + 1 + w//2 ... r0 + w//2`` (the same for columns; at the
    edges too, the filter repeating the edge pixel). Elsewhere
    the map does not depend on that pixel: it equals the map of the series with any other
    value there. (Before, the running sums carried the NaN along the rest of each line: 324
    of 400 pixels of a 3 x 3 map.)
    """
    i = RNG.exponential(size=(5, 20, 20))
    r0, c0 = where
    i[:, r0, c0] = 0.0
    images = xr.DataArray(i, dims=("time", "depth", "x"))
    with pytest.warns(RuntimeWarning, match="zero intensity has no logarithm"):
        out = dy.liv(images, window=window).values
    (wz, wx), rows, cols = window, np.arange(20)[:, None], np.arange(20)[None, :]
    expected_nan = (
        (rows >= r0 - wz + 1 + wz // 2)
        & (rows <= r0 + wz // 2)
        & (cols >= c0 - wx + 1 + wx // 2)
        & (cols <= c0 + wx // 2)
    )
    np.testing.assert_array_equal(np.isnan(out), expected_nan)
    other = i.copy()
    other[:, r0, c0] = RNG.exponential(size=5)
    filled = dy.liv(images.copy(data=other), window=window).values
    np.testing.assert_allclose(out[~expected_nan], filled[~expected_nan], rtol=1e-12)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        chunked = dy.liv(images.chunk({"depth": 5, "x": 4}), window=window).values
    np.testing.assert_array_equal(np.isnan(chunked), expected_nan)
    np.testing.assert_allclose(chunked[~expected_nan], out[~expected_nan], rtol=1e-12)


def test_a_series_streamed_from_a_file_stays_out_of_memory(tmp_path):
    """The user's path: a series on disk, opened lazily in chunks, contrasts computed lazily."""
    path = tmp_path / "series.nc"
    speckle.to_netcdf(FIELD.to_dataset(name="field"), path)
    with xr.open_dataset(path, engine="netcdf4", auto_complex=True, chunks={}) as stored:
        ds = stored.chunk({"x": 4})  # three chunks of lines
        assert hasattr(ds.field.data, "dask")
        liv = dy.liv(ds, window=(3, 3))
        g1 = dy.g1(ds, lags=[1, 2])
        assert hasattr(liv.data, "dask") and hasattr(g1.data, "dask")
        np.testing.assert_allclose(liv.values, dy.liv(FIELD, window=(3, 3)).values, rtol=1e-12)
        np.testing.assert_allclose(g1.values, dy.g1(FIELD, lags=[1, 2]).values, rtol=1e-12)
