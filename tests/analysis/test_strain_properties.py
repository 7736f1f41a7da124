"""Property test of the strain group: malformed inputs give a TypeError or ValueError naming a
parameter, or an answer of the input's shape (finite or NaN where there is no estimate); never
another exception or a hang."""

import warnings

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

import speckle

N, LINES, PIXEL = 64, 8, 8.0
NAMES = (
    "window",
    "min_quality",
    "wrap_check",
    "align",
    "lag",
    "max_bias",
    "method",
    "k0",
    "pixel_size",
    "track_window",
    "step",
    "upsample",
    "oversample",
    "options",
)


@pytest.fixture(scope="module")
def pair():
    src = speckle.spectrum(N, N * PIXEL, k0_dk=10, shape="gaussian", fwhm=0.5 * np.pi / PIXEL)
    scene = speckle.deformable_scene(
        LINES, 4.0, n_pixels=N, depth_range=N * PIXEL, seed=2, strain=1e-3
    )
    b = speckle.bscan(speckle.uniaxial_strain(scene, [0.0, 1e-3]), src)
    f = b.field.transpose("strain", "depth", "aline").values
    return f[0], f[1], float(src.attrs["k0"])


junk = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(-5, 200),
    st.floats(allow_nan=True, allow_infinity=True),
    st.text(max_size=4),
    st.tuples(st.integers(-3, 100), st.integers(-3, 100)),
    st.lists(st.integers(0, 40), max_size=3),
)
OPTION = {
    "vector": ("min_quality", "wrap_check", "align", "lag", "max_bias"),
    "wls": ("min_quality", "align", "lag", "max_bias"),
    "tracking": ("track_window", "step", "upsample", "oversample"),
    "correlation": ("track_window", "step", "upsample", "oversample"),
}


@given(
    method=st.sampled_from(["vector", "wls", "tracking", "correlation", "bogus"]),
    window=junk,
    option=st.integers(0, 4),
    value=junk,
    k0=st.one_of(st.just(None), junk),
)
def test_estimate_strain_refuses_or_answers(pair, method, window, option, value, k0):
    ref, dfm, k = pair
    kw = {"window": window}
    names = OPTION.get(method, ("lag",))
    kw[names[option % len(names)]] = value
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # an all-NaN answer warns (tested elsewhere)
        try:
            out = speckle.estimate_strain(
                ref, dfm, k0=k if k0 is None else k0, pixel_size=PIXEL, method=method, **kw
            )
        except (TypeError, ValueError) as err:
            assert any(name in str(err) for name in NAMES), str(err)
            return
    assert out.shape == ref.shape
    assert not np.isinf(out).any()


@given(window=junk, path=st.one_of(st.none(), st.integers(), st.booleans()), progress=junk)
def test_accumulate_strain_refuses_or_answers(pair, window, path, progress):
    ref, dfm, k = pair
    frames = np.stack([ref, dfm])
    try:
        out = speckle.accumulate_strain(
            frames, k0=k, pixel_size=PIXEL, window=window, path=path, progress=progress
        )
    except (TypeError, ValueError) as err:
        assert any(n in str(err) for n in ("window", "path", "progress")), str(err)
        return
    assert out["accumulated"].shape == (1, N, LINES)
