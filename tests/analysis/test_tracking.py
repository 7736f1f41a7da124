"""Tests of speckle.analysis.tracking: sub-pixel accuracy on known rigid shifts and uniaxial strain,
failure reporting, estimated compensation, bad input.

Accuracy budget: the registration grid is 1/(upsample*oversample) = 1/40 pixel, so a single
estimate carries up to 1/80 pixel of rounding; speckle (a random texture) adds a scatter of a
few hundredths of a pixel for 32 x 16-pixel windows. We require a mean error below 0.05 pixel
(twice the grid step) and an rms error below 0.1 pixel.
"""

import numpy as np
import pytest
import xarray as xr

import speckle
from speckle.analysis import correlation as corr
from speckle.analysis import tracking as T
from speckle.scene import deformation as D

N, PIXEL = 128, 8.0
H = N * PIXEL


@pytest.fixture(scope="module")
def scene():
    return D.deformable_scene(32, 4.0, n_pixels=N, depth_range=H, seed=21, strain=[0.0, 0.02])


@pytest.mark.parametrize("shape", ["rectangular", "gaussian"])
@pytest.mark.parametrize("shift", [0.3, 1.7, -2.45])
def test_rigid_subpixel_shifts_are_recovered(scene, shape, shift):
    kw = {"fwhm": 0.5 * N * np.pi / H} if shape == "gaussian" else {}
    src = speckle.spectrum(N, H, k0_dk=10, shape=shape, **kw)
    ref = speckle.bscan(D.translate(scene, 0.0, wrap=True), src)
    moved = speckle.bscan(D.translate(scene, shift * PIXEL, wrap=True), src)
    truth = D.pixel_displacement(lambda z, x: np.full(z.shape, shift * PIXEL), ref.depth, ref.aline)
    tr = T.track(ref, moved, window=(32, 16), step=(32, 16), truth=truth)
    err = tr.uz_pixels - shift
    assert abs(float(err.mean())) < 0.05
    assert float(np.sqrt((err**2).mean())) < 0.1
    assert not bool(tr.failed.any())
    np.testing.assert_allclose(tr.uz, tr.uz_pixels * PIXEL)


def test_uniaxial_strain_is_tracked_and_compensated(scene):
    s = 0.02
    src = speckle.spectrum(N, H, k0_dk=10)
    b = speckle.bscan(D.uniaxial_strain(scene, [0.0, s]), src)
    ref, dfm = b.isel(strain=0), b.isel(strain=1)
    truth = D.uniaxial_pixel_displacement([s], b.depth.values, b.aline.values).isel(strain=0)
    tr = T.track(ref, dfm, truth=truth)
    assert float(np.sqrt((tr.uz_residual**2).mean())) < 0.1
    assert not bool(tr.failed.any())
    est = T.interpolate_displacement(tr, b.depth.values, b.aline.values)
    exact = float(corr.pearson(ref, corr.compensate(dfm, truth)))
    tracked = float(corr.pearson(ref, corr.compensate(dfm, est)))
    none = float(corr.pearson(ref, dfm))
    # estimated compensation recovers nearly all of the exact one; without it the image
    # decorrelates (displacements up to s*N = 2.6 pixels)
    assert tracked == pytest.approx(exact, abs=0.03)
    assert none < 0.5 * exact


def test_failures_are_reported(scene):
    """Registering against an unrelated speckle image (another seed) gives random peaks:
    with a true displacement of 0 nearly every window is off by more than max_error."""
    src = speckle.spectrum(N, H, k0_dk=10)
    ref = speckle.bscan(D.translate(scene, 0.0), src)
    other = speckle.bscan(D.deformable_scene(32, 4.0, n_pixels=N, depth_range=H, seed=77), src)
    zero = D.pixel_displacement(lambda z, x: np.zeros(z.shape), ref.depth, ref.aline)
    tr = T.track(ref, other, truth=zero, max_error=0.5)
    assert float(tr.failed.mean()) > 0.5
    assert "failed" in tr and tr.attrs["max_error_pixels"] == 0.5


def test_bad_tracking_input(scene):
    src = speckle.spectrum(N, H, k0_dk=10)
    b = speckle.bscan(D.uniaxial_strain(scene, [0.0, 0.01]), src)
    with pytest.raises(ValueError, match=r"must have dims \('depth', 'aline'\), got \('strain'"):
        T.track(b, b)
    ref = b.isel(strain=0)
    with pytest.raises(ValueError, match="larger than the image"):
        T.track(ref, ref, window=(256, 16))
    with pytest.raises(ValueError, match="quantity"):
        T.track(ref, ref, quantity="phase")
    with pytest.raises(TypeError):
        T.track(ref, xr.Dataset())
