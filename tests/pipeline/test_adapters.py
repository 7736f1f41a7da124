"""The config adapter: one way from a ``source`` section to spectrum and scene arguments."""

from __future__ import annotations

import numpy as np
import pytest

import speckle
from speckle.pipeline import adapters

SOURCE = {"n_pixels": 64, "pixel_size": 8.0, "k0_dk": 10, "shape": "gaussian", "fwhm_fraction": 0.4}


def test_spectrum_kwargs_are_the_model_parameters():
    kw = adapters.spectrum_kwargs(SOURCE)
    assert kw == {
        "n_pixels": 64,
        "depth_range": 512.0,
        "k0_dk": 10,
        "shape": "gaussian",
        "fwhm_fraction": 0.4,
    }
    # a rectangular spectrum takes no FWHM; overrides replace the section's values
    rect = adapters.spectrum_kwargs(SOURCE, shape="rectangular", k0_dk=3.0, n_pixels=32)
    assert rect == {"n_pixels": 32, "depth_range": 256.0, "k0_dk": 3.0, "shape": "rectangular"}
    assert adapters.scene_kwargs(SOURCE, n_pixels=32) == {"n_pixels": 32, "depth_range": 256.0}
    spec = adapters.source_spectrum(SOURCE)
    ref = speckle.spectrum(64, 512.0, k0_dk=10, shape="gaussian", fwhm_fraction=0.4)
    np.testing.assert_array_equal(spec.values, ref.values)
    assert spec.attrs == ref.attrs


@pytest.mark.parametrize(
    ("change", "name"),
    [
        ({"n_pixels": None}, "n_pixels"),
        ({"pixel_size": 0.0}, "pixel_size"),
        ({"k0_dk": None}, "k0_dk"),
        ({"n_pixels": 1}, "n_pixels"),
    ],
)
def test_bad_or_missing_source_values_are_named(change, name):
    with pytest.raises(ValueError, match=name):
        adapters.spectrum_kwargs({**SOURCE, **change})


def test_random_bscan_is_the_bscan_of_the_seeded_scene():
    ds, src = adapters.random_bscan(SOURCE, 2.0, n_alines=3, seed=5, normalise="density")
    scene = speckle.random_scatterers(3, 2.0, n_pixels=64, depth_range=512.0, seed=5)
    ref = speckle.bscan(scene, src, normalise="density")
    np.testing.assert_array_equal(ds.field.values, ref.field.values)
    assert src.attrs["k0_dk"] == 10 and src.attrs["shape"] == "gaussian"
