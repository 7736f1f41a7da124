"""B-scans as labelled datasets: dims, units, normalisation, extra dims, dask chunking."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.imaging import bscan, expected_intensity

N, H = 64, 512.0


@pytest.fixture(scope="module")
def scene():
    return speckle.random_scatterers(32, 4.0, n_pixels=N, depth_range=H, seed=5)


@pytest.fixture(scope="module")
def source():
    return speckle.spectrum(N, H, k0_dk=10)


def test_dataset_layout(scene, source):
    ds = bscan(scene, source)
    assert ds.field.dims == ("depth", "x") and ds.field.dtype == np.complex128
    np.testing.assert_allclose(ds.depth, np.arange(N) * H / N)
    assert ds.depth.attrs["units"] == "um"
    np.testing.assert_allclose(ds.intensity, np.abs(ds.field) ** 2)
    np.testing.assert_allclose(ds.amplitude, np.abs(ds.field))
    assert ds.attrs["k0_dk"] == pytest.approx(10) and ds.attrs["scene_seed"] == 5
    assert ds.attrs["speckle_version"]
    line = speckle.ascan(
        scene.z[3].values,
        scene.amplitude[3].values,
        n_pixels=N,
        depth_range=H,
        k0=source.attrs["k0"],
    )
    np.testing.assert_array_equal(ds.field.isel(x=3).values, line)


def test_density_normalisation_is_explicit(scene, source):
    raw = bscan(scene, source)
    dens = bscan(scene, source, normalise="density")
    np.testing.assert_allclose(dens.field, raw.field / 2.0)
    assert dens.attrs["normalisation"] == "density"


def test_expected_normalisation_gives_unit_mean_intensity(source):
    """<I> = rho N sum S^2 exactly when 2 k0 H is a multiple of 2 pi (k0_dk = 10: k0 H = 640 pi).

    The sample mean over 64 independent lines x 64 pixels has relative standard error
    about C/sqrt(n_lines * N / 2) (~2 correlated pixels per speckle), C ~ 1.08: 5 sigma ~ 0.05.
    """
    sc = speckle.random_scatterers(64, 4.0, n_pixels=N, depth_range=H, seed=9)
    ds = bscan(sc, source, normalise="expected")
    assert float(ds.intensity.mean()) == pytest.approx(1.0, abs=0.05)
    assert expected_intensity(4.0, N, None) == 4.0 * N * N


def test_extra_dims_are_carried(scene, source):
    stacked = xr.concat([scene, scene.assign(z=scene.z + H / N)], dim="strain")
    ds = bscan(stacked, source)
    assert ds.field.dims == ("strain", "depth", "x")
    # a one-pixel shift rolls each line by one pixel with carrier exp(2i k0 H/N)
    k0 = source.attrs["k0"]
    np.testing.assert_allclose(
        ds.field.isel(strain=1).values,
        np.roll(ds.field.isel(strain=0).values, 1, axis=0) * np.exp(2j * k0 * H / N),
        atol=1e-8,
    )


@pytest.mark.parametrize("chunks", [1, 5, 32])
def test_dask_chunks_give_identical_numbers(scene, source, chunks):
    eager = bscan(scene, source)
    lazy = bscan(scene.chunk(aline=chunks), source)
    assert lazy.field.chunks is not None
    np.testing.assert_array_equal(lazy.field.values, eager.field.values)


def test_bad_bscan_input(scene, source):
    with pytest.raises(ValueError, match="normalise"):
        bscan(scene, source, normalise="max")
    with pytest.raises(TypeError, match="scene"):
        bscan(scene.z, source)
    with pytest.raises(TypeError, match="source"):
        bscan(scene, source.values)
    with pytest.raises(ValueError, match="density"):
        bscan(
            speckle.random_scatterers(2, 0.0, n_pixels=N, depth_range=H, seed=1),
            source,
            normalise="density",
        )
