"""The phantom fit on measured images (speckle.studies.phantom.real): the equivalent system,
its window and noise, a closed loop through a measured-image file, and the study."""

import math
import warnings

import numpy as np
import pytest

import speckle
from speckle.data import SAMPLE_PITCH, SAMPLE_PIXEL_SIZE, sample_path
from speckle.studies.phantom import slab_constants

NEPER_DB = 10 / math.log(10)


@pytest.fixture(scope="module")
def pdms():
    return speckle.load_image(
        sample_path("pdms"), kind="log", dims=("depth", "x"),
        pixel_size=SAMPLE_PIXEL_SIZE, pitch=SAMPLE_PITCH["pdms"],
    )  # fmt: skip


@pytest.fixture(scope="module")
def system(pdms):
    return speckle.equivalent_system(
        pdms[:, :128], (90, 150), noise_rows=(5, 40), beam_radius=5.0, denoise=False
    )


def test_geometry_and_window(pdms, system):
    cfg = system.config
    assert (cfg.n_pixels, cfg.n_lines) == (60, 128)
    assert cfg.pixel_size == SAMPLE_PIXEL_SIZE
    assert cfg.line_pitch == pytest.approx(SAMPLE_PITCH["pdms"])
    assert cfg.beam_radius == 5.0 and math.isnan(system.waist)
    fs = speckle.fit_system(pdms[:, :160], region={"depth": [90, 150], "x": [0, 160]},
                            noise_rows=[5, 40])  # fmt: skip
    twin = speckle.equivalent_system(pdms[:, :160], (90, 150), noise_rows=(5, 40))
    assert twin.gain == pytest.approx(float(fs.parameters.gain), rel=1e-9)
    assert twin.config.beam_radius == pytest.approx(float(fs.parameters.waist) / math.sqrt(2))
    # n_scatterers: per_cell (2) kurtosis-equivalent scatterers per pixel per pitch
    t_eq = slab_constants(5.0)["t_eq"]
    assert cfg.n_scatterers == math.ceil(2 * 60 * 128 * 10.0 / t_eq)
    # the window: level L holds ln I - ln I_top in [L step - 51 dB, (L + 1) step - 51 dB)
    levels = system.scan_levels(pdms[:, :128]).values
    d = pdms.values[90:150, :128]
    rel = ((d - system.offset) / system.gain - system.window_top_log) * NEPER_DB + 51.0
    step = 51.0 / 256
    inside = levels > 0
    assert np.all(levels[inside] * step <= rel[inside] + 1e-9)
    assert np.all(rel[inside] < (levels[inside] + 1) * step + 1e-9)
    assert np.all(rel[~inside] < step + 1e-9)
    # the window's bottom is the noise rows' mean ln I
    noise = (pdms.values[5:40, :128] - system.offset) / system.gain
    assert system.noise_log == pytest.approx(noise.mean())
    assert system.window_top_log - 51.0 / NEPER_DB == pytest.approx(noise.mean())


def test_noise_of_the_scan(pdms, system):
    """A phantom of no energy scans as the measured noise alone: complex Gaussian noise of mean
    ln I at the window's bottom puts P(I < exp(-gamma) <I>) = 1 - exp(-exp(-gamma)) of its
    pixels at level 0, and the mean of its level-clipped ln I follows."""
    fit = speckle.fit_phantom(pdms[:, :128], system)
    dark = speckle.PhantomFit(layers=fit.layers.assign(rho_e=fit.layers.rho_e * 1e-30),
                              config=fit.config)  # fmt: skip
    scan = system.scan(dark, 4).values
    n = scan.size
    p0 = 1 - math.exp(-math.exp(-np.euler_gamma))
    frac = float(np.mean(scan == 0))
    assert abs(frac - p0) < 4 * math.sqrt(p0 * (1 - p0) / n)
    # the same seed, the same scan; another seed, another
    assert np.array_equal(system.scan(dark, 4).values, scan)
    assert not np.array_equal(system.scan(dark, 5).values, scan)


@pytest.mark.parametrize("noise_db", [2.0, 6.0])
def test_closed_loop_through_a_file(tmp_path, noise_db):
    """A layered phantom scanned, with noise, written as a linear intensity image and read by
    load_image: its fit through the equivalent system gives the attenuation back within 3 SE
    (mu = rho (E/100) A2) and the boundary within a pixel."""
    cfg = speckle.ScannerConfig(n_pixels=96, pixel_size=6.0, n_lines=160, x_max=960.0,
                                beam_radius=6.0, n_scatterers=60_000)  # fmt: skip
    rng = np.random.default_rng(np.random.SeedSequence(7))
    h, top = cfg.depth_range, 240.0
    rho = cfg.n_scatterers / (cfg.x_max * 2 * cfg.beam_radius * h)
    z = rng.uniform(0, h, cfg.n_scatterers)
    energy = np.where(z < top, 0.5, 2.0)
    table = np.column_stack(
        [
            rng.uniform(-0.5, 0.5, z.size) * cfg.x_max,
            rng.uniform(-1, 1, z.size) * cfg.beam_radius,
            z,
            energy,
        ]
    )
    field = speckle.synthoct_scan(table, cfg, field=True).values
    a2 = slab_constants(cfg.beam_radius)["A2"]
    mu_true = rho * np.array([0.5, 2.0]) / 100 * a2
    # complex noise 20 or 60 dB under the top rows' mean (the lower layer ends ~29 dB under
    # them), 16 noise rows above the "sample"; at 20 dB the rows near the floor hold S + N and
    # the fit finds the signal's slopes through denoise (without it: pulls -0.46 and -1.96,
    # attenuations 3.7 % and 6.2 % low; with it 2.0 % and 2.1 %; 60 dB: 0.9 % and 2.7 %)
    sigma2 = np.mean(np.abs(field[:10]) ** 2) * 10**-noise_db
    noise = math.sqrt(sigma2 / 2) * (
        rng.standard_normal((16 + 96, 160)) + 1j * rng.standard_normal((16 + 96, 160))
    )
    image = np.abs(np.concatenate([np.zeros((16, 160)), field]) + noise) ** 2
    path = tmp_path / "image.npy"
    np.save(path, image)
    im = speckle.load_image(path, kind="intensity", dims=("depth", "x"), pixel_size=6.0,
                            pitch=6.0)  # fmt: skip
    system = speckle.equivalent_system(im, (16, 112), noise_rows=(2, 14), beam_radius=6.0)
    fit = speckle.fit_phantom(im, system)
    layers = fit.layers
    assert layers.sizes["layer"] == 2
    assert abs(float(layers.top[1]) - top) < cfg.pixel_size
    pulls = (layers.attenuation.values - mu_true) / layers.attenuation_se.values
    assert np.all(np.abs(pulls) < 3), pulls


def test_refused(pdms):
    with pytest.raises(TypeError, match="DataArray"):
        speckle.equivalent_system(pdms.values, (90, 150), noise_rows=(5, 40))
    with pytest.raises(ValueError, match="rows"):
        speckle.equivalent_system(pdms, (90, 100), noise_rows=(5, 40))
    with pytest.raises(ValueError, match="noise_rows"):
        speckle.equivalent_system(pdms, (90, 150), noise_rows=(40, 5))
    with pytest.raises(ValueError, match="per_cell"):
        speckle.equivalent_system(pdms, (90, 150), noise_rows=(5, 40), per_cell=0)
    with pytest.raises(ValueError, match="beam_radius"):
        speckle.equivalent_system(pdms, (90, 150), noise_rows=(5, 40), beam_radius=-1.0)
    with pytest.raises(ValueError, match="seeds"):
        speckle.real_tissue_phantom(pdms, (90, 150), noise_rows=(5, 40), seeds=(1, 1))
    with pytest.raises(ValueError, match="variant"):
        speckle.real_tissue_phantom(pdms, (90, 150), noise_rows=(5, 40), variant="x")


def test_study_small(pdms):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # MS-SSIM is NaN under 176 pixels
        ds = speckle.real_tissue_phantom(pdms[:, :128], (90, 150), noise_rows=(5, 40),
                                         seeds=(1, 2, 3), beam_radius=5.0)  # fmt: skip
    assert ds.measured.shape == (60, 128) and ds.fitted.shape == (3, 60, 128)
    assert ds.sizes["pair"] == 3 and ds.sizes["map"] == 4
    assert np.all(np.isfinite(ds["SSIM_gap"])) and np.all(np.isfinite(ds["SSIM_gap_se"]))
    # the gap is the mean over seeds minus the mean over pairs
    gap = ds["PSNR_versus"].mean("seed") - ds["PSNR_floor"].mean("pair")
    np.testing.assert_allclose(ds["PSNR_gap"], gap)
    assert ds.profile_residual.units == "dB"
    assert 0 < float(ds.log_variance_measured) < math.pi**2 / 6 + 1
    assert ds.attrs["beam_radius"] == 5.0
    assert {"top", "attenuation", "rho_e"} <= set(ds.data_vars)
    assert ds.fitted.dtype == np.uint8 and ds.measured.dtype == np.uint8


def test_denoise_is_exact_for_gaussian_speckle_and_noise(tmp_path):
    """Circular Gaussian speckle of row means s_q plus circular Gaussian noise of mean n: each
    row's ln I after the shift ln(1 - n/(s + n)) has mean ln s_q - gamma (within 4 SE of the
    row mean's, the row mean's own error propagated)."""
    rng = np.random.default_rng(np.random.SeedSequence(11))
    n_lines, s = 4000, np.geomspace(100.0, 1.0, 40)  # signal from 20 dB above the noise to 0

    def gauss(shape):
        return (rng.standard_normal(shape) + 1j * rng.standard_normal(shape)) / math.sqrt(2)

    field = np.sqrt(s)[:, None] * gauss((40, n_lines))
    image = np.abs(np.concatenate([np.zeros((8, n_lines)), field]) + gauss((48, n_lines))) ** 2
    path = tmp_path / "image.npy"
    np.save(path, image)
    im = speckle.load_image(path, kind="intensity", dims=("depth", "x"), pixel_size=6.0,
                            pitch=6.0)  # fmt: skip
    system = speckle.equivalent_system(im, (8, 48), noise_rows=(0, 8), beam_radius=6.0)
    levels = system.scan_levels(im).values
    assert np.mean(levels == 0) < 0.5
    # undo the 8-bit window: the rows' ln I relative to the window's top
    step = 51.0 / 256 / NEPER_DB
    bottom = system.window_top_log - 51.0 / NEPER_DB
    li = (levels + 0.5) * step + bottom
    li[levels == 0] = bottom + step - 1.0  # E ln I below a clip c: ln c - 1 (density flat at 0)
    noise_log = system.noise_log  # ln n - gamma, measured from the noise rows
    n = math.exp(noise_log + np.euler_gamma)
    good = s >= 10 * n  # rows whose shifted values stay inside the window (few clipped)
    mean = li[good].mean(axis=1)
    expect = np.log(s[good]) - np.euler_gamma
    # SE: speckle's ln I has sd pi/sqrt 6 per pixel; the shift's derivative n/s amplifies
    # the row mean's error by (1 + n/(s - n)) at most; the noise level's own error is common
    se = math.pi / math.sqrt(6 * n_lines) * (1 + n / (s[good] - n))
    assert np.all(np.abs(mean - expect) < 4 * se), (mean - expect) / se
