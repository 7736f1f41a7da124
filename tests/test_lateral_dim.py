"""One lateral dim for images (issue 32): scenes of independent lines keep ``aline``, every
image over them has ``x``; an image labelled the old way warns and gives the same numbers."""

import warnings

import numpy as np
import pytest

import speckle

N, H, K0 = 64, 200.0, 10.0


@pytest.fixture(scope="module")
def pair():
    src = speckle.spectrum(n_pixels=N, depth_range=H, k0=K0)
    scene = speckle.deformable_scene(8, 0.5, n_pixels=N, depth_range=H, seed=3, strain=[0.0, 0.01])
    images = speckle.bscan(speckle.uniaxial_strain(scene, [0.0, 0.01]), src)
    return scene, images


def test_the_scene_keeps_aline_and_its_image_has_x(pair):
    scene, images = pair
    assert "aline" in scene.z.dims and "x" not in scene.z.dims
    field = images.field
    assert field.dims[-2:] == ("depth", "x") and "aline" not in field.dims
    # the line positions of the scene are the image's lateral coordinate (µm, table attrs)
    np.testing.assert_array_equal(field.x.values, scene.aline.values[: field.sizes["x"]])
    assert field.x.attrs["units"] == "um"


def test_truth_of_a_line_scene_has_x():
    src = speckle.spectrum(n_pixels=N, depth_range=H, k0=K0)
    scene = speckle.random_scatterers(4, 0.5, n_pixels=N, depth_range=H, seed=1)
    truth = speckle.speckle_free_image(scene, src)
    assert truth.dims == ("depth", "x")
    np.testing.assert_array_equal(truth.x.values, scene.aline.values)


def test_an_aline_image_warns_and_gives_the_same_strain(pair):
    _, images = pair
    ref, dfm = images.field.isel(strain=0), images.field.isel(strain=1)
    p = H / N
    new = speckle.estimate_strain(ref, dfm, k0=K0, pixel_size=p, window=(16, 2))
    old_ref, old_dfm = ref.rename(x="aline"), dfm.rename(x="aline")
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):
        old = speckle.estimate_strain(old_ref, old_dfm, k0=K0, pixel_size=p, window=(16, 2))
    assert old.dims == new.dims == ("depth", "x")
    np.testing.assert_array_equal(old.values, new.values)  # the same numbers, exactly
    assert new.attrs["window_x_pixels"] == 2 and "window_aline_pixels" not in new.attrs


def test_an_x_image_does_not_warn(pair):
    _, images = pair
    ref = images.field.isel(strain=0)
    with warnings.catch_warnings():
        warnings.simplefilter("error", FutureWarning)
        speckle.correlation_map(ref, ref, window=8)


def test_a_displacement_field_is_over_x_and_an_aline_field_warns_with_the_same_numbers(pair):
    """Displacement fields are quantities over the image (dims ``depth, x``); a field written
    before issue 32, over ``(depth, aline)``, is renamed with a FutureWarning in ``compensate``
    and ``track(truth=)``, giving identical results."""
    from speckle.scene.deformation import uniaxial_pixel_displacement

    _, images = pair
    ref, dfm = images.isel(strain=0), images.isel(strain=1)
    disp = uniaxial_pixel_displacement([0.01], dfm.depth.values, dfm.x.values).isel(strain=0)
    assert disp.uz.dims == ("depth", "x")
    old = disp.rename(x="aline")
    new = speckle.compensate(dfm, disp)
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):
        np.testing.assert_array_equal(speckle.compensate(dfm, old).values, new.values)
    kw = dict(window=(16, 3), step=(8, 1))
    tracked = speckle.track(ref.field, dfm.field, truth=disp, **kw)
    with pytest.warns(FutureWarning, match="dim 'aline' is now 'x'"):
        again = speckle.track(ref.field, dfm.field, truth=old, **kw)
    np.testing.assert_array_equal(again.uz_residual.values, tracked.uz_residual.values)
