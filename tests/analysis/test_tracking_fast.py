"""The vectorised tracker (``speckle.track(method="fft")``) against the per-window skimage
reference and against known displacements.

Accuracy budget (as tests/test_tracking.py): the registration grid is 1/(upsample*oversample)
= 1/40 pixel in depth, so an estimate carries up to 1/80 pixel of rounding; the speckle texture
adds a few hundredths of a pixel for 32 x 16-pixel windows. Both methods run the same estimator
(plain cross-correlation of the oversampled amplitude, whole-pixel peak, 1.5*upsample-point DFT
refinement), so in depth they agree to the grid wherever the peak is unique.
"""

import numpy as np
import pytest

import speckle
from speckle.analysis import (
    interpolate_displacement,
    interpolate_windows,
    oversample_depth,
    sample_field,
    track_array,
)
from speckle.scene import deformation as D

N, PIXEL = 256, 8.0
H = N * PIXEL


def source():
    return speckle.spectrum(N, H, k0_dk=10, shape="gaussian", fwhm=0.5 * N * np.pi / H)


@pytest.fixture(scope="module")
def scene():
    return D.deformable_scene(64, 4.0, n_pixels=N, depth_range=H, seed=5, strain=[0.0, 0.02])


@pytest.fixture(scope="module")
def strained(scene):
    b = speckle.bscan(D.uniaxial_strain(scene, [0.0, 0.01]), source(), method="nufft")
    return b.isel(strain=0), b.isel(strain=1)


def test_oversampling_is_the_exact_trigonometric_interpolant():
    rng = np.random.default_rng(0)
    for n in (64, 63):
        a = rng.normal(size=(n, 3)) + 1j * rng.normal(size=(n, 3))
        for f in (2, 3):
            exact = sample_field(a.T, np.arange(0, n, 1 / f)).T
            np.testing.assert_allclose(oversample_depth(a, f), exact, atol=1e-9)


def test_fft_equals_reference_per_window(strained):
    ref, dfm = strained
    fast = speckle.track(ref, dfm, method="fft")
    slow = speckle.track(ref, dfm, method="reference")
    # depth: the same grid point in nearly every window, else the neighbouring one (single
    # precision amplitudes, and the depth Nyquist term taken as a cosine: real CC)
    dz = np.abs(fast.uz_pixels - slow.uz_pixels).values
    assert np.mean(dz < 1e-9) > 0.95 and dz.max() <= 1 / 40 + 1e-9
    # lateral: coordinate-wise search vs the reference's 2-D grid: within one grid step
    assert float(np.abs(fast.ux - slow.ux).max()) <= 1 / 20 * float(np.diff(ref.x)[0]) + 1e-9
    np.testing.assert_allclose(fast.registration_error, slow.registration_error, atol=2e-3)


@pytest.mark.parametrize("shift", [0.3, 1.7, -2.45])
def test_subpixel_rigid_shifts(scene, shift):
    ref = speckle.bscan(D.translate(scene, 0.0, wrap=True), source())
    moved = speckle.bscan(D.translate(scene, shift * PIXEL, wrap=True), source())
    truth = D.pixel_displacement(lambda z, x: np.full(z.shape, shift * PIXEL), ref.depth, ref.x)
    fast = speckle.track(ref, moved, window=(32, 16), step=(32, 16), truth=truth)
    slow = speckle.track(
        ref, moved, window=(32, 16), step=(32, 16), truth=truth, method="reference"
    )
    err = fast.uz_residual
    assert abs(float(err.mean())) < 0.05
    rms = float(np.sqrt((err**2).mean()))
    assert rms < 0.1
    assert rms <= float(np.sqrt((slow.uz_residual**2).mean())) + 1 / 80  # equal or better
    assert not bool(fast.failed.any())


def test_uniaxial_strain_and_interpolation(scene, strained):
    ref, dfm = strained
    truth = D.uniaxial_pixel_displacement([0.01], ref.depth.values, ref.x.values).isel(strain=0)
    tr = speckle.track(ref, dfm, truth=truth)
    assert float(np.sqrt((tr.uz_residual**2).mean())) < 0.1
    # the dense field interpolated back: within the same budget of the exact one
    est = interpolate_displacement(tr, ref.depth.values, ref.x.values)
    inner = slice(16, N - 16)
    diff = (est.uz - truth.uz).isel(depth=inner) / PIXEL
    assert float(np.sqrt((diff**2).mean())) < 0.1


def test_poisson_lateral_motion_does_not_spoil_axial_tracking(scene):
    s, nu = 0.02, 0.45
    b = speckle.bscan(D.uniaxial_strain(scene, [0.0, s], poisson_ratio=nu), source())
    ref, dfm = b.isel(strain=0), b.isel(strain=1)
    truth = D.uniaxial_pixel_displacement(
        [s], ref.depth.values, ref.x.values, poisson_ratio=nu
    ).isel(strain=0)
    tr = speckle.track(ref, dfm, truth=truth)
    slow = speckle.track(ref, dfm, truth=truth, method="reference")
    assert float(np.sqrt((tr.uz_residual**2).mean())) < 0.15
    assert float(np.abs(tr.uz_pixels - slow.uz_pixels).max()) <= 1 / 40 + 1e-9


def test_fe_inclusion_displacement():
    lines, s = 64, 0.004
    depth = np.arange(N) * PIXEL
    sc = speckle.deformable_scene(lines, 4.0, n_pixels=N, depth_range=H, seed=7, strain=0.02)
    x = sc.aline.values
    labels = speckle.inclusion_labels(depth, x, (H / 2, x.mean()), 160.0)
    fe = speckle.compress_phantom(labels, {0: 10.0, 1: 40.0}, 0.45, strain=s, contact="sliding")
    disp = fe[["uz", "ux"]]  # over (depth, x): read at the scene's line positions
    ref = speckle.bscan(speckle.displace(sc, lambda z, x: 0 * z), source(), method="nufft")
    dfm = speckle.bscan(speckle.displace(sc, disp), source(), method="nufft")
    truth = disp[["uz"]].assign_coords(depth=ref.depth, x=ref.x)
    tr = speckle.track(ref, dfm, truth=truth)
    assert float(np.sqrt((tr.uz_residual**2).mean())) < 0.1
    assert not bool(tr.failed.any())


def test_low_signal_and_nan_windows(strained):
    ref, dfm = (f.field.transpose("depth", "x").values for f in strained)
    base = track_array(ref, dfm)
    a, b = ref.copy(), dfm.copy()
    a[:48] = b[:48] = 0.0  # no signal in the top 48 px: windows starting above 16 px
    a[200, 40] = np.nan
    out = track_array(a, b)
    z0 = out["centre_depth"] - 15.5
    empty = z0 + 32 <= 48
    assert np.isnan(out["uz"][empty]).all() and np.isnan(out["error"][empty]).all()
    x0 = out["centre_x"] - 7.5
    holds_nan = ((z0 <= 200) & (z0 + 32 > 200))[:, None] & ((x0 <= 40) & (x0 + 16 > 40))[None]
    assert np.isnan(out["uz"][holds_nan]).all()
    # windows away from both (band-limited oversampling: the gap disturbs only half-pixel
    # samples near it) keep their estimate to the grid
    far = (z0 >= 64)[:, None] & ~holds_nan
    far &= ~(np.abs(out["centre_depth"] - 200) < 40)[:, None]
    np.testing.assert_allclose(out["uz"][far], base["uz"][far], atol=1 / 40 + 1e-9)


def test_interpolate_windows_modes():
    v = np.array([[0.0, 1.0], [2.0, 3.0]])
    cz, cx = np.array([1.0, 3.0]), np.array([0.0, 2.0])
    z, x = np.arange(5.0), np.arange(3.0)
    lin = interpolate_windows(v, cz, cx, z, x)
    assert lin[2, 1] == pytest.approx(1.5) and lin[0, 0] == pytest.approx(-1.0)
    near = interpolate_windows(v, cz, cx, z, x, outside="nearest")
    assert near[0, 0] == 0.0 and near[4, 2] == 3.0
    nan = interpolate_windows(v, cz, cx, z, x, outside="nan")
    assert np.isnan(nan[0]).all() and np.isfinite(nan[1:4]).all()


def test_bad_input():
    a = np.ones((64, 8), complex)
    with pytest.raises(ValueError, match="method"):
        track_array(a, a, window=8, method="magic")
    with pytest.raises(TypeError, match="complex"):
        track_array(a.real, a.real, window=8)
    with pytest.raises(ValueError, match="shape"):
        track_array(a, a[:32], window=8)
    with pytest.raises(ValueError, match="larger than the image"):
        track_array(a, a, window=(32, 16))
    with pytest.raises(TypeError, match="lateral"):
        track_array(a, a, window=8, lateral="no")
