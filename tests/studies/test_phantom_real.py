"""The phantom fit on measured images (speckle.studies.phantom.real): the equivalent system,
its window and noise, a closed loop through a measured-image file, and the study."""

import math
import warnings

import numpy as np
import pytest

import speckle
from speckle.data import SAMPLE_PITCH, SAMPLE_PIXEL_SIZE, sample_path
from speckle.studies.phantom._fit import slab_constants
from speckle.synthoct import _scan

NEPER_DB = 10 / math.log(10)


@pytest.fixture(scope="module")
def pdms():
    return speckle.load_image(
        sample_path("pdms"), kind="log", dims=("depth", "x"),
        pixel_size=SAMPLE_PIXEL_SIZE, pitch=SAMPLE_PITCH["pdms"],
    )  # fmt: skip


@pytest.fixture(scope="module")
def system(pdms):
    return speckle.equivalent_system(pdms[:, :128], (90, 150), noise_rows=(5, 40), beam_radius=5.0)


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


@pytest.mark.parametrize("noise_db", [6.0])
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
    # noise 60 dB under the top rows' mean (the lower layer ends ~29 dB under them: the fit
    # does not model noise, whose bias ln(1 + N/S) the floor of its window keeps small
    # here), in 16 noise rows above the "sample"
    inten = np.abs(field) ** 2
    sigma2 = inten[:10].mean() * 10**-noise_db
    noise = sigma2 * rng.exponential(size=(16 + 96, 160))
    image = np.concatenate([np.zeros((16, 160)), inten]) + noise
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
    assert np.all(ds.fitted.values <= _scan.LEVELS - 1)
