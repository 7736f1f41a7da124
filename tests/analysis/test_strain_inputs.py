"""Issue 21's strain cases, each refused with the parameter named (or warned), and the one
meaning of ``window`` (an int is a square window everywhere)."""

import numpy as np
import pytest
import xarray as xr

import speckle

N, LINES, PIXEL = 128, 16, 8.0


@pytest.fixture(scope="module")
def pair():
    src = speckle.spectrum(N, N * PIXEL, k0_dk=10, shape="gaussian", fwhm=0.5 * np.pi / PIXEL)
    scene = speckle.deformable_scene(
        LINES, 4.0, n_pixels=N, depth_range=N * PIXEL, seed=4, strain=1e-3
    )
    b = speckle.bscan(speckle.uniaxial_strain(scene, [0.0, 1e-3]), src)
    f = b.field.transpose("strain", "depth", "x").values
    return f[0], f[1], {"k0": float(src.attrs["k0"]), "pixel_size": PIXEL}


def test_min_quality_string_is_a_type_error(pair):
    ref, dfm, kw = pair
    with pytest.raises(TypeError, match="min_quality"):
        speckle.estimate_strain(ref, dfm, min_quality="0.5", **kw)


@pytest.mark.parametrize("value", [2.0, -0.1])
def test_min_quality_outside_0_1_is_refused(pair, value):
    ref, dfm, kw = pair
    with pytest.raises(ValueError, match=r"min_quality must be in \[0, 1\]"):
        speckle.estimate_strain(ref, dfm, min_quality=value, **kw)


@pytest.mark.parametrize("value", ["no", "False", 0, 1])
def test_wrap_check_takes_booleans_only(pair, value):
    ref, dfm, kw = pair
    with pytest.raises(TypeError, match="wrap_check"):
        speckle.estimate_strain(ref, dfm, wrap_check=value, **kw)


def test_align_string_other_than_auto_is_refused(pair):
    ref, dfm, kw = pair
    with pytest.raises(ValueError, match="align"):
        speckle.estimate_strain(ref, dfm, align="yes", **kw)


def test_all_nan_result_warns_with_the_reason(pair):
    ref, dfm, kw = pair
    # a correlated pair refused by the option alone: the advice is the option, nothing else
    why = r"below min_quality=1; highest 0\.9\d+; try a lower min_quality \(the default is 0\.5\)$"
    with pytest.warns(UserWarning, match=why):
        out = speckle.estimate_strain(ref, dfm, min_quality=1.0, **kw)
    assert np.isnan(out).all()


def test_nan_pixels_are_counted(pair):
    ref, dfm, kw = pair
    bad = ref.copy()
    bad[3, 4] = bad[7, 1] = np.nan
    with pytest.raises(ValueError, match="reference holds 2 NaN or infinite pixels"):
        speckle.estimate_strain(bad, dfm, **kw)


def test_window_int_is_square_everywhere(pair):
    ref, dfm, kw = pair
    e = speckle.estimate_strain(ref, dfm, window=8, **kw)
    assert e.shape == ref.shape
    # the same window as the explicit pair, the same numbers
    np.testing.assert_array_equal(e, speckle.estimate_strain(ref, dfm, window=(8, 8), **kw))
    tr = speckle.analysis.track_array(ref, dfm, window=8, step=8)
    assert tr["uz"].shape == (N // 8, LINES // 8)
    with pytest.raises(ValueError, match="larger than the image"):
        speckle.estimate_strain(ref, dfm, window=32, **kw)  # (32, 32) > 16 A-lines


def test_pixel_size_read_from_the_depth_coordinate_and_a_disagreeing_one_refused(pair):
    ref, dfm, kw = pair
    p = kw["pixel_size"]
    dims = ("depth", "x")
    coords = {"depth": (np.arange(ref.shape[0]) + 0.5) * p}
    a, b = (xr.DataArray(x, dims=dims, coords=coords) for x in (ref, dfm))
    read = speckle.estimate_strain(a, b, k0=kw["k0"])
    np.testing.assert_array_equal(read.values, speckle.estimate_strain(ref, dfm, **kw))
    with pytest.raises(ValueError, match=r"pixel_size=4.0 disagrees with reference's coord"):
        speckle.estimate_strain(a, b, k0=kw["k0"], pixel_size=4.0)
    with pytest.raises(ValueError, match="needs pixel_size"):
        speckle.estimate_strain(ref, dfm, k0=kw["k0"])
    u = speckle.estimate_displacement(a, b, k0=kw["k0"])
    np.testing.assert_array_equal(u.values, speckle.estimate_displacement(ref, dfm, **kw))


@pytest.fixture(scope="module")
def scenes():
    """Two unrelated scenes and a 1 % compression of the first (256 x 32 px, R = 10)."""
    n, lines, p = 256, 32, 8.0
    src = speckle.spectrum(n, n * p, k0_dk=10, shape="gaussian", fwhm=0.5 * np.pi / p)

    def pair(seed):
        sc = speckle.deformable_scene(
            lines, 4.0, n_pixels=n, depth_range=n * p, seed=seed, strain=0.01
        )
        b = speckle.bscan(speckle.uniaxial_strain(sc, [0.0, 0.01]), src)
        return b.field.transpose("strain", "depth", "x").values

    a, b = pair(1), pair(2)
    return a[0], b[0], a[1], {"k0": float(src.attrs["k0"]), "pixel_size": p}


@pytest.mark.parametrize("window", [(64, 1), (32, 1), (64, 8)])
def test_tracking_has_no_answer_on_unrelated_scenes_for_any_window_width(scenes, window):
    # the chance level of the window (TRACK_FALSE_RATE = 1 % of windows by chance) keeps narrow
    # windows quiet on unrelated scenes (0.1 alone let 32 % (16 x 1) to 2 % (32 x 1) answer)
    # and answers a real 1 % compression on most pixels the window covers, at the right strain
    ref, other, compressed, kw = scenes
    tw = window[0]
    est = {}
    for name, b in (("unrelated", other), ("real", compressed)):
        s = speckle.estimate_strain(
            ref, b, method="tracking", window=(64, window[1]), track_window=tw, **kw
        )
        est[name] = s
    assert np.isfinite(est["unrelated"]).mean() <= 0.02
    assert np.isfinite(est["real"]).mean() >= 0.35
    assert np.nanmedian(est["real"]) == pytest.approx(0.01, rel=0.05)


def test_single_line_displacement_has_no_answer_on_unrelated_scenes(scenes):
    # issue 36: the default (one A-line) tracking windows answered 58 % of unrelated pixels
    ref, other, compressed, kw = scenes
    assert np.isfinite(speckle.estimate_displacement(ref, other, **kw)).mean() <= 0.02
    u = speckle.estimate_displacement(ref, compressed, **kw)
    assert np.isfinite(u).mean() >= 0.5
    z = (np.arange(ref.shape[0]) + 0.5) * kw["pixel_size"]
    ok = np.isfinite(u)
    truth = np.broadcast_to((-0.01 * z)[:, None], u.shape)
    assert np.median(np.abs(u[ok] - truth[ok])) < 0.2 * kw["pixel_size"]


def test_sequence_pixel_size_from_coordinates_and_frame_stacks_checked_once(pair):
    ref, dfm, kw = pair
    p = kw["pixel_size"]
    frames = xr.DataArray(
        np.stack([ref, dfm, dfm]),
        dims=("frame", "depth", "aline"),
        coords={"depth": np.arange(ref.shape[0]) * p},
    )
    out = speckle.accumulate_strain(frames, k0=kw["k0"])
    np.testing.assert_array_equal(
        out["accumulated"].values,
        speckle.accumulate_strain(frames.values, **kw)["accumulated"].values,
    )
    with pytest.raises(ValueError, match=r"pixel_size=2\.0 disagrees with frames's coordinates"):
        speckle.accumulate_strain(frames, k0=kw["k0"], pixel_size=2.0)
    # a stack of pairs: every frame as if alone, the stack checked once (NaN frame named)
    stack = speckle.estimate_strain(frames[:2], frames[1:], k0=kw["k0"])
    alone = speckle.estimate_strain(frames[1], frames[2], k0=kw["k0"])
    np.testing.assert_array_equal(stack[1].values, alone.values)
    bad = frames.copy()
    bad[1, 3, 3] = np.nan
    with pytest.raises(ValueError, match=r"deformed holds 1 NaN .* in frames \[0\]"):
        speckle.estimate_strain(frames[:2], bad[1:], k0=kw["k0"])
