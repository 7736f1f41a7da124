"""The one wrapping decorator (``speckle._wrap.preprocess_and_wrap``, as MetPy's)."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle._wrap import preprocess_and_wrap  # private: the decorator the analysis modules use


@preprocess_and_wrap(arrays=["x"], wrap_like="x", name="y", quantity="contrast", long_name="y")
def _square(x, power=2):
    assert isinstance(x, np.ndarray | float | int)  # the body never sees a DataArray
    return np.asarray(x, float) ** power


def test_plain_values_stay_plain():
    assert _square(3.0) == 9.0 and isinstance(_square(3.0), float)
    np.testing.assert_array_equal(_square(np.arange(3)), [0.0, 1.0, 4.0])


def test_labelled_values_keep_their_labels_and_get_the_table_attrs():
    x = xr.DataArray([1.0, 2.0], dims="depth", coords={"depth": [0.0, 5.0]}, attrs={"note": "a"})
    out = _square(x, power=3)
    assert out.name == "y" and out.dims == ("depth",)
    np.testing.assert_array_equal(out.depth, [0.0, 5.0])
    assert out.attrs["note"] == "a" and out.attrs["long_name"] == "y"
    np.testing.assert_array_equal(out, [1.0, 8.0])


def test_unknown_argument_refused_when_decorating():
    with pytest.raises(TypeError, match=r"has no arguments \['z'\]"):
        preprocess_and_wrap(arrays=["z"])(lambda x: x)


def test_first_users_keep_their_behaviour():
    density = xr.DataArray([1.0, 4.0], dims="density", coords={"density": [1.0, 4.0]})
    c = speckle.contrast_theory(density, 64)
    assert c.name == "contrast_theory" and c.dims == ("density",)
    assert speckle.contrast_theory(4.0, 64) == float(c[1])
    img = xr.DataArray(np.ones((8, 8)), dims=("depth", "x"))
    out = speckle.despeckle(img, "lee")
    assert out.attrs["filter"] == "lee" and out.attrs["domain"] == "linear"


# --- declarative checks, frame stacks and the grid from coordinates -------------------------

# private: the decorator's parts, tested here
from speckle._wrap import ArraySpec, Out, map_frames  # noqa: E402
from speckle.conventions import grid  # noqa: E402

_IMAGE = ArraySpec(kind="complex", dims=("depth", "x"), min_shape=(2, 1), lazy=True)


@preprocess_and_wrap(
    checks={
        "a": _IMAGE,
        "b": ArraySpec(kind="complex", dims=("depth", "x"), same_as="a", lazy=True),
    },
    stack=("frame",),
    from_grid={"pixel_size": "a"},
    wrap_like="a",
)
def _phase_step(a, b, *, pixel_size=None):
    assert not isinstance(a, xr.DataArray) and not isinstance(b, xr.DataArray)

    def core(x, y):
        return np.angle(y * np.conj(x)) / pixel_size, np.abs(x)

    step, amp = map_frames(core, a, b, ndim=2, n_out=2)
    return Out(step, name="step", attrs={"pixel_size": pixel_size}, coords={"amp": (amp, {})})


def _image(shape=(4, 3), dz=2.0, seed=0):
    rng = np.random.default_rng(seed)
    v = rng.normal(size=shape) + 1j * rng.normal(size=shape)
    dims = ("depth", "x") if len(shape) == 2 else ("frame", "depth", "x")
    coords = {"depth": np.arange(shape[-2]) * dz, "x": np.arange(shape[-1]) * 5.0}
    return xr.DataArray(v, dims=dims, coords=coords)


@pytest.mark.parametrize(
    ("a", "b", "kw", "err", "match"),
    [
        (
            np.ones((4, 3)),
            np.ones((4, 3), complex),
            {"pixel_size": 1.0},
            TypeError,
            "a must be complex",
        ),
        (
            np.full((4, 3), np.nan + 0j),
            np.ones((4, 3), complex),
            {"pixel_size": 1.0},
            ValueError,
            "a holds 12 NaN or infinite pixels",
        ),
        (
            np.ones((0, 3), complex),
            np.ones((0, 3), complex),
            {"pixel_size": 1.0},
            ValueError,
            "a must not be empty",
        ),
        (
            np.ones((1, 3), complex),
            np.ones((1, 3), complex),
            {"pixel_size": 1.0},
            ValueError,
            r"a must be at least \(depth >= 2, x >= 1\)",
        ),
        (
            np.ones(4, complex),
            np.ones(4, complex),
            {"pixel_size": 1.0},
            ValueError,
            "a must be 2-D",
        ),
        (
            "x",
            np.ones((4, 3), complex),
            {"pixel_size": 1.0},
            TypeError,
            "a must be a numeric array",
        ),
        (
            np.ones((4, 3), complex),
            np.ones((4, 2), complex),
            {"pixel_size": 1.0},
            ValueError,
            "a and b differ in shape",
        ),
        (np.ones((4, 3), complex), np.ones((4, 3), complex), {}, ValueError, "needs pixel_size"),
    ],
)
def test_checks_refuse_naming_the_argument(a, b, kw, err, match):
    with pytest.raises(err, match=match):
        _phase_step(a, b, **kw)


def test_labelled_inputs_mismatched_or_mixed_refused_never_aligned():
    a = _image()
    with pytest.raises(ValueError, match="different 'depth' coordinates"):
        _phase_step(a, a.assign_coords(depth=a.depth + 1.0))
    with pytest.raises(TypeError, match="both be numpy arrays or both DataArrays"):
        _phase_step(a, a.values)
    with pytest.raises(ValueError, match="must have dims"):
        _phase_step(a.rename(x="lateral"), a.rename(x="lateral"))
    with pytest.raises(ValueError, match=r"only a has a .frame. dim"):
        _phase_step(a.expand_dims(frame=2), a)


def test_grid_read_from_coordinates_and_a_disagreeing_value_refused():
    a, b = _image(dz=2.0), _image(dz=2.0, seed=1)
    out = _phase_step(a, b)
    assert out.attrs["pixel_size"] == 2.0 and out.name == "step" and "amp" in out.coords
    np.testing.assert_allclose(out, np.angle(b * np.conj(a)) / 2.0)
    assert _phase_step(a, b, pixel_size=2.0).attrs["pixel_size"] == 2.0
    with pytest.raises(ValueError, match=r"pixel_size=3.0 disagrees with a's coordinates \(2.0\)"):
        _phase_step(a, b, pixel_size=3.0)
    plain = _phase_step(a.values, b.values, pixel_size=2.0)
    assert isinstance(plain, np.ndarray)
    np.testing.assert_array_equal(plain, out.values)


def test_frame_stack_mapped_in_one_pass_lazy_or_not():
    a, b = _image((3, 4, 2)), _image((3, 4, 2), seed=1)
    out = _phase_step(a, b)
    assert out.dims == ("frame", "depth", "x") and out.sizes["frame"] == 3
    for i in range(3):  # every frame as if alone
        np.testing.assert_array_equal(out[i].values, _phase_step(a[i], b[i]).values)
    dask = pytest.importorskip("dask")
    lazy = _phase_step(a.chunk({"frame": 1}), b.chunk({"frame": 1}))
    assert dask.is_dask_collection(lazy.data)
    np.testing.assert_array_equal(lazy.values, out.values)
    bad = a.copy()
    bad[1, 0, 0] = np.nan
    with pytest.raises(ValueError, match=r"a holds 1 NaN .* in frames \[1\]"):
        _phase_step(bad, b)


def test_grid_helper_reads_sources_and_images_and_names_what_is_missing():
    src = speckle.spectrum(n_pixels=64, depth_range=200.0, k0=10.0)
    g = grid(src)
    assert g.n_pixels == 64 and g.depth_range == 200.0 and g.k0 == 10.0
    assert g.pixel_size == pytest.approx(200.0 / 64) and g.spectrum is src and g.pitch is None
    g = grid(_image(dz=2.0))
    assert (g.pixel_size, g.pitch, g.k0) == (2.0, 5.0, None)
    with pytest.raises(ValueError, match=r"\['k0'\] cannot be read"):
        grid(_image(), need=("k0",))
    with pytest.raises(TypeError, match="labelled"):
        grid(np.ones(3))


# --- every public analysis function goes through the decorator ------------------------------

import inspect  # noqa: E402

import speckle.analysis  # noqa: E402

#: Public functions that need no decorator, each with its reason.
NOT_WRAPPED = {
    "filter_available": "takes a filter name, no array",
    "subband_fwhm": "takes two sizes, no array",
    "subband_apodizations": "takes sizes and an apodization name, no array",
    "brownian_frames": "scene: a scatterer Dataset (positions per scatterer), not an image",
    "load_measured": "takes a file path, no array (retired shim of speckle.io.load_image)",
    **{
        n: "the one xarray wrapper of a decorated numpy core (*_array): a Dataset gives its "
        "intensity or, without one, its field (two variables; ArraySpec.variable names one)"
        for n in ("g2", "liv", "ocds", "speckle_variance")
    },
}


def _analysis_functions():
    for name in speckle.analysis.__all__:
        obj = getattr(speckle.analysis, name)
        if inspect.isfunction(obj) or hasattr(obj, "__wrapped__"):
            yield name, obj


@pytest.mark.parametrize("name", [n for n, _ in _analysis_functions() if n not in NOT_WRAPPED])
def test_every_public_analysis_function_is_decorated(name):
    func = getattr(speckle.analysis, name)
    assert hasattr(func, "__speckle_checks__"), (
        f"{func.__module__}.{name} does not use speckle._wrap.preprocess_and_wrap: decorate "
        "it (its array checks declared there) or add it to NOT_WRAPPED with a reason"
    )


def test_the_exception_lists_hold_only_real_names():
    names = dict(_analysis_functions())
    assert set(NOT_WRAPPED) <= set(names)
