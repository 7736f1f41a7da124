"""fit_phantom (issue 34): the published scans, a closed loop, refusals, the challenge's score."""

from __future__ import annotations

import dataclasses
import math
from importlib.resources import files

import numpy as np
import pytest

import speckle
from speckle.studies.phantom import PhantomFit, fit_phantom, slab_constants
from speckle.studies.phantom._density import kurtosis_volume  # private: kappa = 1/(rho V)

DATA = files("speckle.data") / "synthoct"
CFG = speckle.ScannerConfig()
#: The reduced closed-loop scanner: 128 x 128 pixels of 6 µm, radius 10 µm.
SMALL = speckle.ScannerConfig(n_pixels=128, n_lines=128, x_max=768.0, n_scatterers=37_500)


def baseline_mu(energy: float, cfg=CFG) -> float:
    """``rho (E/100) A2`` of the baseline's box (``rho = M/(x_max 2 r H)``)."""
    rho = cfg.n_scatterers / (cfg.x_max * 2 * cfg.beam_radius * cfg.depth_range)
    return rho * energy / 100 * slab_constants(cfg.beam_radius)["A2"]


def test_slab_constants_against_quadrature():
    from scipy import integrate

    r = 7.0
    c = slab_constants(r)
    a2, _ = integrate.dblquad(lambda y, x: np.exp(-2 * (x * x + y * y) / r**2), -8 * r, 8 * r,
                              -r, r)  # fmt: skip
    a4, _ = integrate.dblquad(lambda y, x: np.exp(-4 * (x * x + y * y) / r**2), -8 * r, 8 * r,
                              -r, r)  # fmt: skip
    assert c["A2"] == pytest.approx(a2, rel=1e-9)
    assert c["A4"] == pytest.approx(a4, rel=1e-9)
    # the rho E pi r^2/2 times erf(sqrt 2): the slab |y| <= r cuts the beam
    assert c["A2"] / (math.pi * r**2 / 2) == pytest.approx(0.954499736, rel=1e-8)


@pytest.fixture(scope="module")
def published():
    return {
        name: fit_phantom(DATA / f"Scan_{name}.png", CFG)
        for name in ("Exp1_Uniform_A", "Exp1_Uniform_B", "Exp2_Layers_A", "Exp2_Layers_B")
    }


@pytest.mark.parametrize("seed", ["A", "B"])
def test_published_uniform_is_one_layer(published, seed):
    layers = published[f"Exp1_Uniform_{seed}"].layers
    assert layers.sizes["layer"] == 1
    mu, se = float(layers.attenuation[0]), float(layers.attenuation_se[0])
    # within 3 jackknife SEs of rho (E/100) A2 (measured: +1.3 and +1.7 SE)
    assert abs(mu - baseline_mu(1.0)) < 3 * se
    assert se / mu < 0.01


@pytest.mark.parametrize("seed", ["A", "B"])
def test_published_layers_two_layers_at_400(published, seed):
    layers = published[f"Exp2_Layers_{seed}"].layers
    assert layers.sizes["layer"] == 2
    assert float(layers.top[0]) == 0.0
    top, top_se = float(layers.top[1]), float(layers.top_se[1])
    assert abs(top - 400.0) < CFG.pixel_size
    assert 0 < top_se < CFG.pixel_size
    mu, se = layers.attenuation.values, layers.attenuation_se.values
    assert abs(mu[1] - baseline_mu(2.5)) < 3 * se[1]
    # the upper layer (0.01 %) attenuates 4.8e-5/µm: unresolved by its slope, but its
    # brightness gives rho E/100 through the window fitted on the lower layer
    assert abs(mu[0] - baseline_mu(0.01)) < 3 * se[0]
    rho = CFG.n_scatterers / (CFG.x_max * 2 * CFG.beam_radius * CFG.depth_range)
    rho_e, rho_e_se = float(layers.rho_e[0]), float(layers.rho_e_se[0])
    assert abs(rho_e - rho * 1e-4) < 3 * rho_e_se


def test_published_density_not_identified_gives_a_bound(published):
    # at the baseline's density (1.9 equivalent scatterers per pixel per pitch) var ln I
    # exceeds pi^2/6 by ~0.05 (theory), ~2-3 SE: NaN or a value with its SE, and a bound
    rho = CFG.n_scatterers / (CFG.x_max * 2 * CFG.beam_radius * CFG.depth_range)
    for fit in published.values():
        layers = fit.layers
        for k in range(layers.sizes["layer"]):
            d, bound = float(layers.density[k]), float(layers.density_bound[k])
            if np.isnan(d) and np.isnan(float(layers.log_variance[k])):
                # no row far enough above the floor (Layers_B's dim top layer): the bound is
                # the intensity kurtosis's, 1/(V (kappa + 2 SE)); kappa = 1/(rho V) exactly
                # (Campbell), within 3 SE (measured: pull -2.1, so this 97.7 % bound lies
                # 2.6 % above the baseline's density here)
                kappa, se = float(layers.kurtosis[k]), float(layers.kurtosis_se[k])
                volume = kurtosis_volume(CFG)
                assert bound == pytest.approx(1 / (volume * (kappa + 2 * se)), rel=1e-12)
                assert abs(kappa - 1 / (rho * volume)) < 3 * se
            elif np.isnan(d):
                assert np.isfinite(bound) and bound < rho
                assert np.isnan(float(layers.energy[k]))
            else:
                assert abs(d - rho) < 3 * float(layers.density_se[k])
                assert np.isnan(bound)


def test_result_object_and_units(published):
    fit = published["Exp2_Layers_A"]
    assert isinstance(fit, PhantomFit)
    with pytest.raises(dataclasses.FrozenInstanceError):
        fit.config = CFG
    layers = fit.layers
    assert layers.top.attrs["units"] == "um"
    assert layers.attenuation.attrs["units"] == "1/um"
    assert layers.density.attrs["units"] == "um-3"
    assert layers.energy.attrs["units"] == "percent"
    assert np.isfinite(layers.attrs["window_top"]) and layers.attrs["window_top_se"] > 0
    assert "BIC" in layers.attrs["criterion"]


def test_phantom_table_and_files(published, tmp_path):
    fit = published["Exp2_Layers_A"]
    table = fit.phantom(3)
    assert table.shape == (CFG.n_scatterers, 4)
    assert np.array_equal(table, fit.phantom(3))
    assert np.all(np.abs(table[:, 0]) <= CFG.x_max / 2)
    assert np.all(np.abs(table[:, 1]) <= CFG.beam_radius)
    top = float(fit.layers.top[1])
    lower = table[:, 2] > top
    # rho E/100 of each layer recovered from the drawn table
    for sel, k in ((~lower, 0), (lower, 1)):
        thick = top if k == 0 else CFG.depth_range - top
        rho = sel.sum() / (thick * CFG.x_max * 2 * CFG.beam_radius)
        assert rho * table[sel, 3][0] / 100 == pytest.approx(float(fit.layers.rho_e[k]))
    fit.write(tmp_path / "Scatterers_Exp.txt", 3)
    back = speckle.read_phantom(tmp_path / "Scatterers_Exp.txt")
    assert back.sizes["scatterer"] == CFG.n_scatterers
    assert speckle.read_scanner_config(tmp_path / "Configuration.ini") == CFG


# --- refusals, before any work --------------------------------------------------------------


def test_refuses_bad_input(tmp_path):
    scan = speckle.read_scan(DATA / "Scan_Exp1_Uniform_A.png")
    with pytest.raises(ValueError, match="shape"):
        fit_phantom(scan, SMALL)
    with pytest.raises(ValueError, match="empty"):
        fit_phantom(np.zeros((256, 512), np.uint8), CFG)
    with pytest.raises(ValueError, match="saturated"):
        fit_phantom(np.full((256, 512), 255, np.uint8), CFG)
    with pytest.raises(TypeError, match="uint8"):
        fit_phantom(scan.values.astype(float), CFG)
    with pytest.raises(TypeError, match="config"):
        fit_phantom(scan, {"n_pixels": 256})
    with pytest.raises(ValueError, match="max_layers"):
        fit_phantom(scan, CFG, max_layers=0)
    ini = tmp_path / "Configuration.ini"
    speckle.write_scanner_config(CFG, ini)
    text = ini.read_text().splitlines()
    ini.write_text("\n".join(line for line in text if "beam radius" not in line))
    with pytest.raises(ValueError, match="missing key 'beam radius mcm'"):
        fit_phantom(scan, ini)


# --- closed loop ----------------------------------------------------------------------------


def virtual_patient(seed: int, base: speckle.ScannerConfig = SMALL):
    """1-3 flat layers (>= 90 µm thick, neighbours' energies >= 2.5x apart, 0.2-3 %), 20,000
    to 60,000 scatterers in the reduced box (as many per µm^3 in ``base``'s box):
    ``(config, table, tops, mu)``."""
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    k = int(rng.integers(1, 4))
    while True:
        tops = np.concatenate([[0.0], np.sort(rng.uniform(60, 420, k - 1))])
        if k == 1 or np.min(np.diff(tops)) >= 90:
            break
    energy = np.exp(rng.uniform(np.log(0.2), np.log(3), k))
    for i in range(1, k):
        while max(energy[i] / energy[i - 1], energy[i - 1] / energy[i]) < 2.5:
            energy[i] = np.exp(rng.uniform(np.log(0.2), np.log(3)))
    scale = base.x_max * base.depth_range / (SMALL.x_max * SMALL.depth_range)
    m = int(rng.integers(20_000, 60_000) * scale)
    cfg = dataclasses.replace(base, n_scatterers=m)
    z = rng.uniform(0, cfg.depth_range, m)
    layer = np.searchsorted(tops, z, side="right") - 1
    table = np.column_stack([
        rng.uniform(-0.5, 0.5, m) * cfg.x_max,
        rng.uniform(-1, 1, m) * cfg.beam_radius,
        z,
        energy[layer],
    ])  # fmt: skip
    rho = m / (cfg.x_max * 2 * cfg.beam_radius * cfg.depth_range)
    return cfg, table, tops, rho * energy / 100 * slab_constants(cfg.beam_radius)["A2"]


CASES = range(10)


@pytest.fixture(scope="module")
def closed_loop():
    out = []
    for seed in CASES:
        cfg, table, tops, mu = virtual_patient(seed)
        scan = speckle.synthoct_scan(table, cfg)
        fit = fit_phantom(scan, cfg)
        # boundaries the scan shows: above its fitted rows' end (rows 3 .. rows + 2)
        end = (fit.layers.attrs["rows"] + 2) * cfg.pixel_size
        visible = int(np.sum(tops < end - 4 * cfg.pixel_size))
        out.append((fit, tops[:visible], mu[:visible]))
    return out


@pytest.mark.slow
def test_closed_loop_counts_boundaries_pulls(closed_loop):
    pulls, rho_e_pulls, counts_right = [], [], 0
    a2 = slab_constants(SMALL.beam_radius)["A2"]
    for fit, tops, mu in closed_loop:
        layers = fit.layers
        if layers.sizes["layer"] != tops.size:
            continue
        counts_right += 1
        assert np.all(np.abs(layers.top.values - tops) < SMALL.pixel_size)
        pulls.extend((layers.attenuation.values - mu) / layers.attenuation_se.values)
        # rho E/100 from the slope, or from the brightness where the slope is not significant
        rho_e_pulls.extend((layers.rho_e.values - mu / a2) / layers.rho_e_se.values)
        # densities (sparse to moderate here) are bounded from below where not identified
        cfg = fit.config
        rho = cfg.n_scatterers / (cfg.x_max * 2 * cfg.beam_radius * cfg.depth_range)
        bound = layers.density_bound.values
        assert np.all(bound[np.isfinite(bound)] < rho)
    pulls = np.array(pulls)
    # measured: counts right in 10 of 10 cases, 26 attenuation pulls of rms 0.93, max 1.88,
    # mean 0.03; boundaries within 3.3 µm
    assert counts_right == len(closed_loop)
    assert np.all(np.abs(pulls) < 4)
    assert np.mean(np.abs(pulls) < 2) >= 0.85  # a normal distribution: 95 %
    assert 0.5 < np.sqrt(np.mean(pulls**2)) < 1.5
    # measured: rho_e pulls within 2.7 (brightness route: 0.13, -0.39, 2.67, 1.48)
    assert np.all(np.abs(rho_e_pulls) < 4)


@pytest.mark.slow
def test_scored_as_the_challenge_scores():
    """MS-SSIM of every map of the target against the fitted phantom's scan (another seed)
    within 0.02 of the floor, the true phantom scanned with another seed: the published
    two-layer scans (A the target, B the floor)."""
    target = speckle.read_scan(DATA / "Scan_Exp2_Layers_A.png")
    floor = speckle.read_scan(DATA / "Scan_Exp2_Layers_B.png")
    fit = fit_phantom(target, CFG)
    with pytest.warns(RuntimeWarning, match="LPIPS"):
        ours = speckle.synthoct_metrics(target, fit.render(1))["MS-SSIM"]
    with pytest.warns(RuntimeWarning, match="LPIPS"):
        best = speckle.synthoct_metrics(target, floor)["MS-SSIM"]
    # measured: 0.748 / 0.813 / 0.864 / 0.923 against 0.747 / 0.808 / 0.863 / 0.927
    assert np.all(ours.values > best.values - 0.02)


def test_window_top_is_the_fields_maximum(published):
    """The fitted window's top against ``20 log10 max |A|`` of the true phantom's field, within
    3 SE (the SE includes the uncertainty of the layer's ``E ln(I/<I>)``, taken from its
    ``var ln I``).
    """
    field = speckle.synthoct_scan(speckle.baseline_phantom("uniform", "A"), CFG, field=True)
    truth = 20 * np.log10(np.abs(field.values).max())
    layers = published["Exp1_Uniform_A"].layers
    # measured: 36.59 +- 0.08 dB fitted against 36.70 (36.75 +- 0.06 with E ln(I/<I>) = -gamma)
    assert abs(layers.attrs["window_top"] - truth) < 3 * layers.attrs["window_top_se"]


#: A closed-loop scanner large enough for MS-SSIM's five scales (176 pixels a side).
SCORED = speckle.ScannerConfig(n_pixels=256, n_lines=256, x_max=1536.0, n_scatterers=1)


def redraw(table: np.ndarray, tops: np.ndarray, cfg, seed: int) -> np.ndarray:
    """The same true phantom (layers and energies) drawn again with another seed."""
    rng = np.random.default_rng(np.random.SeedSequence(seed))
    m = table.shape[0]
    energy = np.array([table[table[:, 2] >= t][np.argmin(table[table[:, 2] >= t, 2]), 3]
                       for t in tops])  # fmt: skip
    z = rng.uniform(0, cfg.depth_range, m)
    return np.column_stack([
        rng.uniform(-0.5, 0.5, m) * cfg.x_max,
        rng.uniform(-1, 1, m) * cfg.beam_radius,
        z,
        energy[np.searchsorted(tops, z, side="right") - 1],
    ])  # fmt: skip


@pytest.mark.slow
@pytest.mark.filterwarnings("ignore:LPIPS is NaN")
def test_closed_loop_scored_at_the_floor():
    """Closed-loop case 0 (three layers) at 256 x 256: MS-SSIM of each map between the target
    and the fitted phantom's scans (seeds 11-13) against the floor, the true phantom redrawn
    with the same seeds. One seed's MS-SSIM of RSC scatters by ~0.05 (SC, OAC, Struct by <=
    0.02), so the means of three seeds are compared: within 0.02 of the floor, plus 2 standard
    errors of the difference of the means (from the seeds' spread)."""
    cfg, table, tops, _ = virtual_patient(0, SCORED)
    target = speckle.synthoct_scan(table, cfg)
    fit = fit_phantom(target, cfg)
    assert fit.layers.sizes["layer"] == tops.size
    ours, floor = [], []
    for seed in (11, 12, 13):
        ours.append(speckle.synthoct_metrics(target, fit.render(seed))["MS-SSIM"].values)
        truth = speckle.synthoct_scan(redraw(table, tops, cfg, seed), cfg)
        floor.append(speckle.synthoct_metrics(target, truth)["MS-SSIM"].values)
    ours, floor = np.array(ours), np.array(floor)
    se = np.sqrt((ours.var(axis=0, ddof=1) + floor.var(axis=0, ddof=1)) / 3)
    # measured (Struct, OAC, SC, RSC): means 0.848 / 0.728 / 0.851 / 0.750 against
    # 0.851 / 0.733 / 0.847 / 0.782; SE of the difference 0.002 / 0.006 / 0.017 / 0.037
    assert np.all(ours.mean(axis=0) > floor.mean(axis=0) - 0.02 - 2 * se)
    assert np.all(np.abs(ours.mean(axis=0) - floor.mean(axis=0))[:2] < 0.02)


def test_render_and_ini_path(tmp_path):
    cfg, table, tops, _ = virtual_patient(1)
    scan = speckle.synthoct_scan(table, cfg)
    ini = tmp_path / "Configuration.ini"
    speckle.write_scanner_config(cfg, ini)
    png = tmp_path / "scan.png"
    speckle.write_scan(scan, png)
    fit = fit_phantom(png, ini)
    same = fit_phantom(scan, cfg)
    assert fit.layers.identical(same.layers)
    again = fit.render(5)
    assert again.dims == ("depth", "x") and again.shape == scan.shape
    assert again.dtype == np.uint8 and int(again.max()) == 255
    # the re-rendered scan is fitted back to the same layers
    refit = fit_phantom(again, cfg).layers
    assert refit.sizes["layer"] == tops.size
    assert abs(float(refit.top[1]) - float(fit.layers.top[1])) < cfg.pixel_size


def test_mean_shadowing_constant_against_the_scanners_law():
    """The scanner's own per-line shadowing (``_scan.shadowing``) of a uniform slab: the mean
    over central lines of the exponent at the bottom, ``C(H)``, against ``rho (E/100) A2 H``.

    SE of that mean (compound Poisson): ``(E/100) sqrt(rho H int (mean_i W_i^2)^2 dx dy)``.
    """
    # private: the scanner core's own shadowing law is what this test holds the constant against
    from speckle.synthoct import _scan

    cfg = SMALL
    rng = np.random.default_rng(7)
    m, energy = 200_000, 0.5
    table = np.column_stack([
        rng.uniform(-0.5, 0.5, m) * cfg.x_max,
        rng.uniform(-1, 1, m) * cfg.beam_radius,
        np.sort(rng.uniform(0, cfg.depth_range, m)),
        np.full(m, energy),
    ])  # fmt: skip
    x, y, z, e = table.T
    j, line, w = _scan.beam_pairs(x, y, cfg.line_positions, 0.0, cfg.beam_radius, 1e-12)
    t = _scan.shadowing(z, e, j, line, w, cfg.n_lines, "line")
    # C at the bottom of each line: its last pair's exponent plus that pair's own loss
    last = np.r_[line[1:] != line[:-1], True]
    c_bottom = -np.log(t[last]) + (e[j[last]] / 100) * w[last] ** 2
    central = np.abs(cfg.line_positions[line[last]]) <= cfg.x_max / 2 - 3 * cfg.beam_radius
    mean_c = c_bottom[central].mean()
    rho = m / (cfg.x_max * 2 * cfg.beam_radius * cfg.depth_range)
    expected = rho * energy / 100 * slab_constants(cfg.beam_radius)["A2"] * cfg.depth_range
    # SE: the mean over the central lines' W^2, squared, integrated over the slab
    lines = cfg.line_positions[np.abs(cfg.line_positions) <= cfg.x_max / 2 - 3 * cfg.beam_radius]
    gx = np.linspace(-cfg.x_max / 2, cfg.x_max / 2, 4001)
    gy = np.linspace(-cfg.beam_radius, cfg.beam_radius, 201)
    wx = np.exp(-2 * (gx[:, None] - lines[None, :]) ** 2 / cfg.beam_radius**2).mean(axis=1)
    wy = np.exp(-2 * gy**2 / cfg.beam_radius**2)
    integral = np.trapezoid(wx**2, gx) * np.trapezoid(wy**2, gy)
    se = energy / 100 * np.sqrt(rho * cfg.depth_range * integral)
    # measured: 9.768 against 9.761 (+0.29 SE); without erf(sqrt 2): -18 SE
    assert abs(mean_c - expected) < 3 * se
    assert se / expected < 0.01  # the test resolves the erf(sqrt 2) = 0.9545 factor
