"""The SynthOCT scanner against the four published scans and an exact reference (issue 33).

Acceptance (issue 33): on each published scan, our scan of the regenerated phantom correlates
at >= 0.95 with the official one (log image, each row normalised, rows above the floor:
speckle.synthoct.scanner.FLOOR_FRACTION) and its row means are within 0.5 dB. Measured when
identified: 0.9967-0.9973 and 0.10-0.23 dB (per-line shadowing); the assertions keep the
issue's thresholds, the identification's alternatives are checked to do worse.
"""

from __future__ import annotations

import dataclasses
from importlib.resources import files

import numpy as np
import pytest

import speckle
from speckle.synthoct import _scan  # private: the core against its direct sum, its options
from speckle.synthoct.files import ScannerConfig, baseline_table, read_png
from speckle.synthoct.scanner import scan_agreement

DATA = files("speckle.data") / "synthoct"
SCANS = {
    ("uniform", 42): "Scan_Exp1_Uniform_A.png",
    ("uniform", 101): "Scan_Exp1_Uniform_B.png",
    ("layers", 42): "Scan_Exp2_Layers_A.png",
    ("layers", 101): "Scan_Exp2_Layers_B.png",
}


@pytest.fixture(scope="module")
def tables():
    return {key: baseline_table(*key) for key in SCANS}


@pytest.mark.parametrize("key", list(SCANS))
def test_published_scan_reproduced(tables, key):
    official = read_png(DATA / SCANS[key])
    scan = speckle.synthoct_scan(tables[key], ScannerConfig())
    assert scan.dtype == np.uint8 and scan.shape == official.shape
    got = scan_agreement(scan, official)
    assert got["rows"] >= 110  # the rows above the floor (114-123 in the four scans)
    assert got["correlation"] >= 0.95
    assert got["row_mean_error"] <= 0.5
    # the other realisation's phantom does not match: the agreement is grain for grain
    other = (key[0], 101 if key[1] == 42 else 42)
    assert scan_agreement(scan, read_png(DATA / SCANS[other]))["correlation"] < 0.1


def test_identification_alternatives_do_worse(tables):
    """Per-line shadowing beats the mean field; the Hann spectrum beats Gaussians of FWHM
    0.45-0.5 of the band; the window's top at the image maximum beats +-0.5 dB shifts."""
    key = ("layers", 101)
    official = read_png(DATA / SCANS[key])
    cfg = ScannerConfig()

    def corr(**options):
        levels = _scan.scan_levels(tables[key], cfg, **options)
        return scan_agreement(levels, official)

    best = corr()
    assert corr(shadow="mean")["correlation"] < best["correlation"] - 0.005
    assert corr(shadow="none")["row_mean_error"] > 5.0
    for fwhm in (0.45, 0.5):
        n = np.arange(256) - 128
        gauss = np.exp(-4 * np.log(2) * (n / (fwhm * 256)) ** 2)
        assert corr(spectrum=gauss)["correlation"] < best["correlation"] - 0.005
    field = _scan.scan_fields(tables[key], cfg)[0]
    level = 20 * np.log10(np.abs(field) / np.abs(field).max())
    for shift in (-0.5, 0.5):  # a window placed 0.5 dB off the maximum shifts every row mean
        moved = np.clip(np.floor((level + 51 - shift) * 256 / 51), 0, 255).astype(np.uint8)
        assert scan_agreement(moved, official)["row_mean_error"] > 0.4


def _small(seed=1, m=300):
    rng = np.random.default_rng(seed)
    cfg = ScannerConfig(n_pixels=64, pixel_size=4.0, n_lines=24, x_max=96.0, beam_radius=5.0,
                        n_scatterers=m)  # fmt: skip
    h = cfg.depth_range
    table = np.column_stack([
        rng.uniform(-55, 55, m), rng.uniform(-6, 6, m),
        np.round(rng.uniform(0, h, m)),  # integer depths: ties (shared shadowing) occur
        rng.uniform(0, 60, m),
    ])  # fmt: skip
    return cfg, table


@pytest.mark.parametrize("shadow", _scan.SHADOWING)
def test_fast_path_against_the_direct_sum(shadow):
    """Exact reference: the direct double sum of the same formula (every pair, shadowing by
    explicit depth comparisons). Budget: pairs with weight < tol are dropped, FINUFFT at eps;
    relative l2 error <= tol + eps (measured 0.9e-4 at the defaults 1e-4, 6e-13 at 1e-12)."""
    cfg, table = _small()
    kw = dict(n_pixels=cfg.n_pixels, depth_range=cfg.depth_range, k0=cfg.k0, shadow=shadow,
              line_x=cfg.line_positions, line_y=1.0, radius=cfg.beam_radius)  # fmt: skip
    ref = _scan.direct_field(table, **kw)
    for tol, eps in ((_scan.TOL, _scan.EPS), (1e-12, 1e-12)):
        fast = _scan.bscan_field(table, tol=tol, eps=eps, **kw)
        err = np.linalg.norm(fast - ref) / np.linalg.norm(ref)
        assert err <= tol + eps


def test_direct_sum_against_the_project_beam_scan():
    """Without shadowing the formula is speckle.beam_scan's with waist sqrt(2) r and the Hann
    spectrum (the project's exact direct sum; 2-D scene at y = 0)."""
    cfg, table = _small(seed=2)
    table[:, 1] = 0.0
    ours = _scan.direct_field(table, n_pixels=cfg.n_pixels, depth_range=cfg.depth_range,
                              k0=cfg.k0, line_x=cfg.line_positions, line_y=0.0,
                              radius=cfg.beam_radius, shadow="none")  # fmt: skip
    theirs = speckle.beam_scan(
        table[:, 2], table[:, 0], np.sqrt(table[:, 3] / 100), lines=cfg.line_positions,
        waist=np.sqrt(2) * cfg.beam_radius, n_pixels=cfg.n_pixels, depth_range=cfg.depth_range,
        k0=cfg.k0, spectrum=np.hanning(cfg.n_pixels), method="direct",
    )  # fmt: skip
    np.testing.assert_allclose(ours, theirs, rtol=0, atol=1e-12 * np.abs(theirs).max())


def test_shadowing_law_on_a_uniform_slab():
    """Mean field of the per-line law: for a laterally uniform density rho (per µm^3, 3-D
    phantom) of energy fraction e, C(z) = rho e z pi r^2/2, so the mean log level falls by
    20 log10(e) rho e pi r^2/2 dB per µm (the speckle's log mean is depth independent)."""
    rng = np.random.default_rng(5)
    cfg = ScannerConfig(n_pixels=128, pixel_size=4.0, n_lines=64, x_max=384.0,
                        beam_radius=8.0, n_scatterers=60_000)  # fmt: skip
    m, h = cfg.n_scatterers, cfg.depth_range
    table = np.column_stack([rng.uniform(-232, 232, m), rng.uniform(-40, 40, m),
                             rng.uniform(0, h, m), np.full(m, 5.0)])  # fmt: skip
    rho = m / (464 * 80 * h)
    slope = -20 * np.log10(np.e) * rho * 0.05 * np.pi * 8.0**2 / 2  # dB/µm
    field = _scan.scan_fields(table, cfg)[0][10:118]
    level = np.log(np.abs(field) ** 2).mean(axis=1) * 10 / np.log(10)  # mean log intensity
    z = np.arange(10, 118) * 4.0
    fit = np.polyfit(z, level, 1)[0]
    # standard error of the fitted slope: the log of an exponential intensity has sd 5.57 dB
    se = 5.57 / np.sqrt(64 / 2) / np.sqrt(np.sum((z - z.mean()) ** 2))
    assert abs(fit - slope) < 4 * se  # measured: -0.1364 vs -0.1378 dB/µm, 1.9 se


def test_options_and_refusals(tmp_path):
    cfg, table = _small(m=200)
    base = speckle.synthoct_scan(table, cfg)
    assert base.dims == ("depth", "x") and int(base.max()) == 255
    field = speckle.synthoct_scan(table, cfg, field=True)
    assert field.dtype == np.complex128
    np.testing.assert_array_equal(_scan.to_levels(field.values), base.values)
    noisy = speckle.synthoct_scan(table, cfg, noise=-30.0, seed=3)
    assert not np.array_equal(noisy.values, base.values)
    np.testing.assert_array_equal(noisy, speckle.synthoct_scan(table, cfg, noise=-30.0, seed=3))
    with pytest.raises(ValueError, match="seed"):
        speckle.synthoct_scan(table, cfg, noise=-30.0)
    with pytest.raises(ValueError, match="shadowing"):
        speckle.synthoct_scan(table, cfg, shadowing="beer")
    with pytest.raises(ValueError, match="n_scatterers"):
        speckle.synthoct_scan(table[:10], cfg)
    with pytest.raises(TypeError, match="config"):
        speckle.synthoct_scan(table, {"n_pixels": 64})
    # files: INI and phantom paths work too
    speckle.write_scanner_config(cfg, tmp_path / "c.ini")
    speckle.write_phantom(table, tmp_path / "p.txt")
    from_files = speckle.synthoct_scan(tmp_path / "p.txt", tmp_path / "c.ini")
    np.testing.assert_array_equal(from_files.x, base.x)


def test_several_bscans_stack_along_y():
    cfg, table = _small(m=200)
    cfg3 = dataclasses.replace(cfg, n_bscans=3, y_max=12.0)
    scan = speckle.synthoct_scan(table, cfg3)
    assert scan.dims == ("y", "depth", "x")
    np.testing.assert_allclose(scan.y, [-6.0, -2.0, 2.0])
    levels = _scan.scan_levels(table, cfg3)
    np.testing.assert_array_equal(levels, scan.values.reshape(-1, cfg.n_lines))
    # the B-scan at y = 2 is the one-B-scan scan of the phantom shifted by -2 in y, same window
    shifted = table.copy()
    shifted[:, 1] -= 2.0
    f3 = _scan.scan_fields(table, cfg3)
    f1 = _scan.scan_fields(shifted, cfg)
    np.testing.assert_allclose(f3[2], f1[0], atol=1e-9 * np.abs(f1).max())


@pytest.mark.parametrize(("n_pixels", "n_lines"), [(33, 1), (31, 24), (64, 1)])
def test_fast_path_odd_pixels_and_one_line(n_pixels, n_lines):
    """Odd N (spectral index from -(N//2)) and a single A-line: same exact agreement."""
    rng = np.random.default_rng(3)
    m, h = 200, 4.0 * n_pixels
    table = np.column_stack([rng.uniform(-30, 30, m), rng.uniform(-5, 5, m),
                             rng.uniform(0, h, m), rng.uniform(0, 50, m)])  # fmt: skip
    kw = dict(n_pixels=n_pixels, depth_range=h, k0=4.8, line_x=np.arange(n_lines) * 5.0 - 10,
              line_y=0.5, radius=5.0)  # fmt: skip
    ref = _scan.direct_field(table, **kw)
    fast = _scan.bscan_field(table, tol=1e-12, eps=1e-12, **kw)
    assert np.linalg.norm(fast - ref) / np.linalg.norm(ref) <= 2e-12
