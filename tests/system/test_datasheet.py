"""The datasheet constructor: derived model parameters against textbook formulas, both ways."""

import numpy as np
import pytest
from scipy.optimize import brentq

import speckle
from speckle.system import EXAMPLE_SYSTEMS, datasheet

LN2 = np.log(2)


def wide_system(**kw):
    """840 nm / 50 nm, camera +-3 FWHM (source truncated below 1e-10), n = 1.4."""
    args = dict(
        wavelength_nm=840.0,
        bandwidth_nm=50.0,
        camera_pixels=1024,
        camera_range_nm=(690.0, 990.0),
        refractive_index=1.4,
    )
    return speckle.datasheet(**{**args, **kw})


def test_imaging_depth_from_sampling_interval():
    s = wide_system()
    lam = s.camera_wavelengths()
    dl = 300e-3 / 1024
    assert s.sampling_interval == pytest.approx(dl, rel=1e-14)
    # exact: z_max = lambda_a lambda_b / (4 n dl) with the extreme pixel centres
    assert s.imaging_depth == pytest.approx(lam[0] * lam[-1] / (4 * 1.4 * dl), rel=1e-13)
    # textbook lambda0^2/(4 n dl) differs by exactly ((M - 1) dl / (2 lambda0))^2 (centred camera)
    textbook = 0.84**2 / (4 * 1.4 * dl)
    x = (1023 * dl / (2 * 0.84)) ** 2
    assert s.imaging_depth == pytest.approx(textbook * (1 - x), rel=1e-13)
    assert s.depth_range == pytest.approx(2 * s.imaging_depth, rel=1e-15)
    assert s.pixel_size == pytest.approx(s.depth_range / s.n_pixels, rel=1e-15)
    assert s.n_pixels == 1024


def test_imaging_depth_round_trip():
    """Given z_max, the camera step is the textbook one; the exact depth differs by lambda_a
    lambda_b / lambda0^2."""
    s = speckle.datasheet(840.0, 50.0, 2048, imaging_depth=2000.0, refractive_index=1.38)
    assert s.sampling_interval == pytest.approx(0.84**2 / (4 * 1.38 * 2000.0), rel=1e-13)
    lam = s.camera_wavelengths()
    assert s.imaging_depth == pytest.approx(2000.0 * lam[0] * lam[-1] / 0.84**2, rel=1e-13)
    assert (s.wavelength_min + s.wavelength_max) / 2 == pytest.approx(0.84, rel=1e-14)


def test_grid_spans_camera_and_model_parameters():
    s = wide_system()
    src = s.spectrum()
    k_cam = 2 * np.pi * 1.4 / s.camera_wavelengths()
    k = src.wavenumber.values
    np.testing.assert_allclose([k[0], k[-1]], [k_cam[-1], k_cam[0]], rtol=1e-14)
    np.testing.assert_allclose(np.diff(k), np.pi / s.depth_range, rtol=1e-10)
    assert src.attrs["k0"] == pytest.approx(s.k0, rel=1e-15)
    assert src.attrs["depth_range"] == pytest.approx(s.depth_range, rel=1e-15)
    assert src.attrs["k0_dk"] == pytest.approx(s.k0_dk, rel=1e-13)
    assert s.delta_k == pytest.approx(s.n_pixels * np.pi / s.depth_range, rel=1e-14)
    assert s.source_wavenumber == pytest.approx(2 * np.pi * 1.4 / 0.84, rel=1e-15)
    # the spectrum peaks at the source wavenumber with FWHM 2 pi n Delta_lambda / lambda0^2
    assert s.fwhm_k == pytest.approx(2 * np.pi * 1.4 * 0.05 / 0.84**2, rel=1e-14)
    assert s.fwhm_fraction == pytest.approx(s.fwhm_k / s.delta_k, rel=1e-15)
    half = s.source_wavenumber + s.fwhm_k / 2
    w = np.interp(half, k, src.values)
    assert w == pytest.approx(0.5, abs=1e-4)  # linear interpolation of the sampled Gaussian


def test_axial_resolution_both_ways():
    """(2 ln2/pi) lambda0^2/(n Delta_lambda) = FWHM of the amplitude PSF of the spectrum."""
    s = wide_system()
    expected = 2 * LN2 / np.pi * 0.84**2 / (1.4 * 0.05)
    assert s.gaussian_resolution == pytest.approx(expected, rel=1e-14)
    assert s.gaussian_resolution == pytest.approx(4 * LN2 / s.fwhm_k, rel=1e-14)
    assert s.axial_resolution == pytest.approx(expected, rel=1e-8)  # a camera wide enough
    src = s.spectrum()
    k = src.wavenumber.values

    def psf(u):  # |sum_n S_n exp(2i k_n u)| normalised, u in µm
        return np.abs(np.sum(src.values * np.exp(2j * (k - s.k0) * u))) / src.values.sum()

    half = brentq(lambda u: psf(u) - 0.5, 0.0, 3 * expected)
    assert 2 * half == pytest.approx(expected, rel=1e-8)
    # and back: the bandwidth that gives this resolution
    bw = 2 * LN2 / np.pi * 0.84**2 / (1.4 * 2 * half)
    assert bw * 1e3 == pytest.approx(50.0, rel=1e-8)
    # in air the same source resolves n times coarser
    assert wide_system(refractive_index=1.0).axial_resolution == pytest.approx(1.4 * expected)


def test_axial_resolution_is_that_of_the_spectrum_built():
    """Issue 21: a camera range cutting the Gaussian broadens the PSF (4.51 -> 4.69 µm); the
    reported resolution is the built spectrum's FWHM (measured here by brute force)."""
    s = datasheet(840.0, 50.0, 2048, camera_range_nm=(790.0, 890.0), refractive_index=1.38)
    assert s.gaussian_resolution == pytest.approx(4.5125, abs=1e-4)
    src = s.spectrum()
    k = src.wavenumber.values

    def a(z):  # |PSF| at depths z, 1 at z = 0
        return np.abs(np.exp(2j * np.outer(z, k - s.k0)) @ src.values) / src.values.sum()

    # the first half-maximum crossing, bracketed on a coarse grid and solved to 1e-9 µm
    z = np.linspace(0, 6, 601)
    i = int(np.argmax(a(z) < 0.5))
    fwhm = 2 * brentq(lambda x: a(np.array([x]))[0] - 0.5, z[i - 1], z[i], xtol=1e-9)
    assert s.axial_resolution == pytest.approx(fwhm, abs=2e-4)
    assert s.axial_resolution == pytest.approx(4.69, abs=0.01)
    assert "camera cuts the Gaussian" in s.summary()


def test_lateral_resolution_both_ways():
    s = wide_system(beam_waist=8.0)
    fwhm = brentq(lambda r: np.exp(-2 * r**2 / 8.0**2) - 0.5, 0, 20) * 2
    assert s.lateral_resolution == pytest.approx(fwhm, rel=1e-12)
    s2 = wide_system(lateral_resolution=fwhm)
    assert s2.beam_waist == pytest.approx(8.0, rel=1e-12)


def test_rolloff_is_yun_formula():
    """sinc^2(zeta) exp(-omega^2 zeta^2/(2 ln2)), zeta = pi z/(2 z_max), z_max textbook."""
    s = speckle.example_system("840nm")
    dl = s.sampling_interval
    omega = s.spectral_resolution / dl
    zmax_textbook = s.wavelength**2 / (4 * s.refractive_index * dl)
    z = np.linspace(0, s.imaging_depth, 11)
    zeta = np.pi * z / (2 * zmax_textbook)
    yun = np.sinc(zeta / np.pi) ** 2 * np.exp(-(omega**2) * zeta**2 / (2 * LN2))
    np.testing.assert_allclose(s.rolloff(z), yun, rtol=1e-12)
    assert s.rolloff_db(s.rolloff_6db_depth) == pytest.approx(-6.0, abs=1e-9)
    ideal = wide_system()  # 100 % fill, ideal spectrometer: pure sinc^2, -3.92 dB at z_max
    zmax_ideal = ideal.wavelength**2 / (4 * ideal.refractive_index * ideal.sampling_interval)
    assert float(ideal.rolloff_db(zmax_ideal)) == pytest.approx(
        10 * np.log10((2 / np.pi) ** 2), abs=1e-9
    )


def test_summary_and_html():
    s = speckle.example_system("1310nm")
    text = s.summary()
    for piece in ("1310.0 nm", "100.0 nm", "1024 px", "axial resolution", "k0/Δk", "roll-off"):
        assert piece in text
    assert f"{s.axial_resolution:.2f} µm" in text
    html = s._repr_html_()
    assert html.startswith("<table>") and "illustrative" in html
    rec = s.to_dict()
    assert rec["n_pixels"] == 1024 and rec["depth_range"] == pytest.approx(s.depth_range)


def test_examples_are_illustrative():
    for name, args in EXAMPLE_SYSTEMS.items():
        s = speckle.example_system(name)
        assert "illustrative" in s.label and "not a vendor" in s.label
        assert s.wavelength * 1e3 == args["wavelength_nm"]
    assert speckle.example_system("840nm", camera_pixels=512).n_pixels == 512


@pytest.mark.parametrize(
    ("kwargs", "message"),
    [
        (dict(bandwidth_nm=900.0), "bandwidth_nm must be smaller"),
        (dict(bandwidth_nm=-1.0), "bandwidth_nm must be in"),
        (dict(camera_range_nm=(820.0, 990.0)), "must cover the FWHM band"),
        (dict(camera_range_nm=(690.0, 850.0)), "must cover the FWHM band"),
        (dict(camera_range_nm=(900.0, 800.0)), "camera_range_nm\\[1\\] must be in"),
        (dict(imaging_depth=2000.0), "exactly one of camera_range_nm"),
        (dict(camera_pixels=1), "camera_pixels must be an integer in"),
        (dict(refractive_index=0.5), "refractive_index must be in"),
        (dict(fill_factor=1.5), "fill_factor must be in"),
        (dict(beam_waist=5.0, lateral_resolution=5.0), "at most one"),
        (dict(spectral_resolution_nm=-0.1), "spectral_resolution_nm must be in"),
    ],
)
def test_bad_datasheet(kwargs, message):
    with pytest.raises(ValueError, match=message):
        wide_system(**kwargs)


def test_bad_example_and_types():
    with pytest.raises(ValueError, match="name must be one of"):
        speckle.example_system("800nm")
    with pytest.raises(TypeError, match="camera_pixels must be an integer"):
        wide_system(camera_pixels=1024.0)
    with pytest.raises(ValueError, match="exactly one of camera_range_nm"):
        speckle.datasheet(840.0, 50.0, 1024)
