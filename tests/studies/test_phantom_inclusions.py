"""Inclusions of the phantom fit (issue 34): detection, fit, drawing, the closed loop's columns.

The physics and the statistics are in :mod:`speckle.studies.phantom._inclusions`.
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pytest
import xarray as xr
from scipy import special

import speckle
from speckle.studies.phantom import _inclusions as inc  # private: the model's pieces, tested
from speckle.studies.phantom._shapes import TransitionModel  # private: the depth PSF the model uses
from speckle.studies.phantom._slab import speckle_cell  # private: the count test's speckle cells

#: The reduced closed-loop scanner: 128 x 128 pixels of 6 µm, radius 10 µm.
SMALL = speckle.synthoct_config("reduced")


def _binomial_ok(k: int, n: int, p: float, z: float = 2.0) -> bool:
    """``k`` of ``n`` within ``z`` binomial SEs of the rate ``p``."""
    return abs(k / n - p) <= z * math.sqrt(p * (1 - p) / n)


def test_geometry_is_the_exact_chord():
    """``sum_z chi p`` is the chord ``2 h sqrt(1 - ((x - xc)/w)^2)`` (the PSF's weights sum to
    one) and ``L`` below the ellipse is the chord, on every line (no lateral smoothing)."""
    p = 6.0
    z = np.arange(80) * p
    x = np.linspace(-90, 90, 37)
    geo = inc._Geometry(z, x, p, 0.0, TransitionModel(128).cdf)
    theta = np.array([7.0, 200.0, 60.0, 33.0])
    chi, ell = geo.basis(theta)
    u = np.clip(1 - ((x - theta[0]) / theta[2]) ** 2, 0, None)
    chord = 2 * theta[3] * np.sqrt(u)
    np.testing.assert_allclose(chi.sum(axis=0) * p, chord, atol=1e-6 * p)
    np.testing.assert_allclose(ell[-1], chord, atol=1e-12)
    assert np.all(np.diff(ell, axis=0) >= -1e-12)  # L grows with depth


def test_model_is_the_intensity_mixture():
    """The level step mixes intensities: ``chi = 1`` gives ``a``, ``chi = 0`` nothing, half a
    pixel ``ln((1 + e^a)/2)``; the shadow is linear in ``L``."""
    basis = np.array([[1.0, 0.0, 0.5], [0.0, 10.0, 2.0]])
    got = inc._model(basis, 2.0, -0.1)
    np.testing.assert_allclose(got, [2.0, -1.0, math.log((1 + math.e**2) / 2) - 0.2])


def test_threshold_false_alarm_on_smoothed_noise():
    """The Euler-characteristic threshold on smoothed white noise (the detection's own
    smoothing and standardisation): the fraction of 400 fields of 120 x 118 whose largest
    ``|Z|`` exceeds ``t`` is at most FALSE_ALARM = 0.05 (2 binomial SEs, 1.1 %, allowed above)
    and at least a third of it. The expected Euler characteristic bounds the probability from
    above; measured 15/400 and (these seeds) 9/400, together 3.0 +- 0.6 %: conservative at
    this size by about 2 %, not exact, so the test is one-sided."""
    rng = np.random.default_rng(np.random.SeedSequence(340))
    sigma = (inc.SMOOTH_ROWS, inc.SMOOTH_CELLS * SMALL.beam_radius / SMALL.line_pitch)
    hits, n = 0, 400
    for _ in range(n):
        z = inc._standardised(inc._smooth(rng.standard_normal((120, 118)), sigma))
        hits += bool(np.nanmax(np.abs(z)) > inc._threshold(z, inc.FALSE_ALARM))
    se = math.sqrt(inc.FALSE_ALARM * (1 - inc.FALSE_ALARM) / n)
    assert inc.FALSE_ALARM / 3 < hits / n <= inc.FALSE_ALARM + 2 * se, hits


def test_count_gate_is_the_hosts_poisson_tail():
    """An ellipse must differ from its host by more than the host's Poisson count gives: ``N =
    rho A t_eq`` kurtosis-equivalent scatterers (``A`` its pixels' area, ``pi w h`` inside the
    window), ``ratio N`` seen (``ratio`` its mean intensity over the host's), the Poisson
    tail as a normal deviate above ``t``. A 2025 false alarm (patient 2, host 0.00281 µm^-3
    identified, 19.8 x 7.5 µm, intensity ratio 0.142: ``N`` = 12.8, 1.8 seen, ``P(N <= 1) =
    e^-N (1 + N)`` = 3.9e-5, 3.95 SDs) is refused at its t = 5.11; the 2025 patients' smallest
    true ellipse (157 x 10 µm, ``N`` = 135) at ratio 0.2 is kept (11.4 SDs), as is any ellipse
    in a host whose density is not identified but bounded (NaN with a lower bound: dense).
    Twice the host's intensity needs the upper tail: 3.2 SDs at ``N`` = 12.8 (refused), 10.2
    at 135 (kept). In a host without density (``var ln I`` not identified) a dark ellipse is
    tested with the density's lower bound (fewer scatterers: a wider count), and refused
    without one; a bright one is kept."""
    t_eq = speckle.studies.phantom.slab_constants(6.0)["t_eq"]
    n = 0.00281 * math.pi * 19.8 * 7.5 * t_eq
    tail = math.exp(-n) * (1 + n)  # floor(0.142 N) = 1
    assert abs(-special.ndtri(tail) - 3.95) < 0.01
    assert not inc._count_significant(0.142, math.pi * 19.8 * 7.5, 0.00281, t_eq, 5.11)
    assert inc._count_significant(0.2, math.pi * 157 * 10, 0.00281, t_eq, 5.11)
    assert inc._count_significant(0.142, math.pi * 19.8 * 7.5, math.nan, t_eq, 5.11, bound=0.01)
    assert not inc._count_significant(0.142, math.pi * 19.8 * 7.5, math.nan, t_eq, 5.11)
    assert inc._count_significant(2.0, math.pi * 19.8 * 7.5, math.nan, t_eq, 5.11)
    assert not inc._count_significant(2.0, math.pi * 19.8 * 7.5, 0.00281, t_eq, 5.11)
    assert inc._count_significant(2.0, math.pi * 157 * 10, 0.00281, t_eq, 5.11)

    # the count's intensity has its own speckle: a void like patient 9's (23 x 10 µm, ratio
    # 0.30, N = 52 expected; 106.7 pixels of 2.2 x 3.08 µm, 15.9 speckle cells) passes the
    # count alone (5.9 SDs; session 44's fit, with its own N: 5.4) against t = 5.19 and is
    # refused with the cells' gamma (3.6 SDs); the smallest true ellipse's 108 cells keep it
    def cells_of(w, h):
        return math.pi * w * h / (2.2 * 3.0769) / speckle_cell(601, 6.0, 3.0769)

    rho = 52 / (math.pi * 23 * 10 * t_eq)
    assert abs(cells_of(23, 10) - 15.9) < 0.1
    assert inc._count_significant(0.30, math.pi * 23 * 10, rho, t_eq, 5.19)
    void = inc._count_significant(0.30, math.pi * 23 * 10, rho, t_eq, 5.19, cells=cells_of(23, 10))
    assert not void
    true = math.pi * 157 * 10, 0.00281, t_eq, 5.11
    assert inc._count_significant(0.2, *true, cells=cells_of(157, 10))

    # the reduced box's hosts whose rows the floor clips, with the kurtosis's lower bound
    # (no var ln I there; session 46): seed 1's true inclusion (ratio 0.214 on 8748 µm^2, 42
    # cells; bound 8.32e-4 per µm^3: N = 118, tail 2.9e-13) is kept at its t = 4.39; seed 7's
    # void (ratio 0.295 on 3312 µm^2, 15.9 cells; bound 9.95e-4: N = 53, tail 1.5e-4) is
    # refused at its 4.41; with no bound seed 1's would be refused too
    t_small = speckle.studies.phantom.slab_constants(10.0)["t_eq"]
    seed1 = 0.214, 8748.0, math.nan, t_small, 4.39
    assert inc._count_significant(*seed1, cells=42.0, bound=8.32e-4)
    assert not inc._count_significant(*seed1, cells=42.0)
    seed7 = 0.295, 3312.0, math.nan, t_small, 4.41
    assert not inc._count_significant(*seed7, cells=15.9, bound=9.95e-4)
    # a bright one is kept where the density is not identified (reduced seed 0's, ratio 2.21,
    # would fail at its host's bound, 11 times below the host's density)
    seed0 = 2.21, 6660.0, math.nan, t_small, 4.31
    assert inc._count_significant(*seed0, cells=32.0, bound=3.5e-4)
    assert not inc._count_significant(*seed0[:2], 3.5e-4, *seed0[3:], cells=32.0)


TAIL_CASES = [(12.8, 5.0, 0.3), (12.8, math.inf, 0.3), (52, 16, 0.3), (52, 16, 2.0), (3, 2.5, 2.5)]


@pytest.mark.parametrize(("n_exp", "cells", "ratio"), TAIL_CASES)
def test_count_tail_is_the_compound_poisson_gamma(n_exp, cells, ratio):
    """``_count_tail`` against 400,000 draws of ``R = (n/N) S``, ``n ~ Poisson(N)``, ``S ~
    Gamma(cells)/cells``: within 4 binomial SEs of the draws' tail (5 cases)."""
    rng = np.random.default_rng(7)
    n = rng.poisson(n_exp, 400_000)
    r = n / n_exp * (rng.gamma(cells, 1 / cells, n.size) if math.isfinite(cells) else 1.0)
    mc = float(np.mean(r <= ratio) if ratio < 1 else np.mean(r >= ratio))
    se = math.sqrt(max(mc, 1e-5) * (1 - mc) / n.size)
    assert abs(inc._count_tail(ratio, n_exp, cells) - mc) < 4 * se


def test_speckle_cell_is_the_intensity_correlation_sum():
    """``speckle_cell``: the sum over all lags of the intensity's correlation coefficient,
    ``|sum S^2 e^{-2 pi i n d/N}|^2/(sum S^2)^2`` along depth (Parseval: 35/18 pixels for the
    continuous Hann window) times ``exp(-d^2 pitch^2/r^2)`` across lines (``r sqrt(pi)/pitch``
    when the lines are dense)."""
    for n, r, pitch in [(601, 6.0, 3.0769), (256, 10.0, 6.0), (128, 10.0, 6.0)]:
        s2 = np.hanning(n) ** 2
        along = np.sum(np.abs(np.fft.fft(s2)) ** 2) / np.sum(s2) ** 2
        lags = np.arange(-200, 201)
        across = np.sum(np.exp(-((lags * pitch / r) ** 2)))
        assert speckle_cell(n, r, pitch) == pytest.approx(along * across, rel=1e-12)
        assert along == pytest.approx(35 / 18, rel=0.02)
    assert speckle_cell(4096, 30.0, 1.0) / (35 / 18 * 30 * math.sqrt(math.pi)) == pytest.approx(
        1, rel=1e-3
    )


@pytest.mark.slow
def test_speckle_cell_holds_for_the_scanners_block_means():
    """The variance of ``I``'s mean over 8 x 8 pixels of the scanner's field (reduced box,
    1.6 million scatterers in ``|y| <= 2r``, no shadowing: fully developed) against the
    Gaussian field's exact ``sum_{d} rho_z(d) rho_x(d') (1 - |d|/8)(1 - |d'|/8) / 64`` from the
    same correlations as ``speckle_cell`` (0.0753; the infinite lags' ``speckle_cell/64`` is
    0.0905: a finite block holds a little more than ``n/speckle_cell`` cells, so the count
    test's ``cells`` errs low, on the side of fewer detections). 4 scans of 144 blocks:
    within 3 SE (measured 0.0744 +- 0.0044)."""
    from speckle.synthoct import _scan  # private: the scanner's spectrum

    m, a = 1_600_000, 8
    cfg = dataclasses.replace(SMALL, n_scatterers=m)
    r, pitch, n_pix = cfg.beam_radius, cfg.line_pitch, cfg.n_pixels
    s2 = _scan.hann_spectrum(n_pix) ** 2
    rz = np.abs(np.fft.fft(s2)) ** 2 / np.sum(s2) ** 2
    d = np.arange(-(a - 1), a)
    expected = (np.sum(rz[d % n_pix] * (1 - abs(d) / a)) / a) * (
        np.sum(np.exp(-((d * pitch / r) ** 2)) * (1 - abs(d) / a)) / a
    )
    assert expected == pytest.approx(0.0753, abs=1e-4)
    means = []
    for seed in range(4):
        rng = np.random.default_rng(seed)
        table = np.column_stack([
            rng.uniform(-cfg.x_max - 4 * r, cfg.x_max + 4 * r, m), rng.uniform(-2 * r, 2 * r, m),
            rng.uniform(0, n_pix * cfg.pixel_size, m), np.full(m, 1e-6),
        ])  # fmt: skip
        field = speckle.synthoct_scan(table, cfg, field=True, shadowing="none", nthreads=1)
        i = np.abs(np.asarray(field)[16:112, 16:112]) ** 2
        blocks = i.reshape(96 // a, a, 96 // a, a).mean(axis=(1, 3))
        means.append(blocks.ravel() / i.mean())
    v = np.concatenate(means)
    var = np.var(v, ddof=1)
    assert abs(var - expected) < 3 * var * math.sqrt(2 / (v.size - 1)), var


@pytest.fixture(scope="module")
def patient_fit():
    """Reduced box, virtual patient 2 (three flat layers, a dark inclusion of ln contrast -3.1
    in the top layer), scanned and fitted with inclusions."""
    table, truth = speckle.virtual_patient(2, config=SMALL, layers=(1, 3), shapes=("flat",),
                                           inclusions=True)  # fmt: skip
    scan = speckle.synthoct_scan(table, SMALL, nthreads=1)
    return truth, speckle.fit_phantom(scan, SMALL, inclusions=True)


def test_inclusion_found_and_fitted(patient_fit):
    """One inclusion, its centre within a pixel and 3 SE, its semi-axes within 2 pixels, its
    ``rho E`` from the level step and from the shadow within 3 SE of the truth (measured:
    centre 0.2 px off, pulls 0.7, 0.9 (centre), -1.1 (level) and 0.8 (shadow)); the density
    a lower bound (measured 3.5e-4 for 4.1e-3 per µm^3)."""
    truth, fit = patient_fit
    found = fit.inclusions
    assert found.sizes["inclusion"] == 1
    assert found.centre_x.attrs["units"] == "um" and found.rho_e.attrs["units"] == "um-3"
    first = found.isel(inclusion=0)
    true = {
        "centre_x": float(truth.inclusion_x[0]),
        "centre_z": float(truth.inclusion_z[0]),
        "axis_x": float(truth.inclusion_width[0]),
        "axis_z": float(truth.inclusion_height[0]),
        "rho_e": float(truth.inclusion_density[0] * truth.inclusion_energy[0] / 100),
    }
    true["rho_e_shadow"] = true["rho_e"]
    for name in ("centre_x", "centre_z"):
        assert abs(float(first[name]) - true[name]) < SMALL.pixel_size
        assert abs(float(first[name]) - true[name]) < 3 * float(first[f"{name}_se"])
    for name in ("axis_x", "axis_z"):
        assert abs(float(first[name]) - true[name]) < 2 * SMALL.pixel_size
    for name in ("rho_e", "rho_e_shadow"):
        assert abs(float(first[name]) - true[name]) < 3 * float(first[f"{name}_se"]), name
    assert int(first.host) == int(truth.inclusion_layer[0])
    # the density from the ellipse's own var ln I: not identified at 5 SE in its few dozen
    # pixels; its lower bound (97.7 %) holds, and the energy's upper bound
    assert np.isnan(float(first.density)) and np.isnan(float(first.energy))
    assert 0 < float(first.density_bound) < float(truth.inclusion_density[0])
    assert float(first.energy_bound) > float(truth.inclusion_energy[0])
    assert fit.layers.sizes["layer"] == truth.sizes["layer"]


@pytest.mark.slow
def test_phantom_draws_and_render_reproduces(patient_fit):
    """``.phantom`` draws the fitted ellipse (its scatterers at the host's density, energy
    ``100 rho_e/rho``), and its scan, fitted again, shows the inclusion at the same place
    within 2 pixels."""
    _, fit = patient_fit
    first = fit.inclusions.isel(inclusion=0)
    xc, zc, w, h = (float(first[v]) for v in ("centre_x", "centre_z", "axis_x", "axis_z"))
    table = fit.phantom(1)
    assert table.shape == (SMALL.n_scatterers, 4)
    inside = ((table[:, 0] - xc) / w) ** 2 + ((table[:, 2] - zc) / h) ** 2 < 1
    energies = np.unique(table[inside, 3])
    assert energies.size == 1
    host = int(first.host)
    host_rows = (table[:, 2] < fit.layers.top.values[host + 1]) & ~inside
    ratio = energies[0] / np.unique(table[host_rows, 3])[0]
    np.testing.assert_allclose(ratio, float(first.rho_e) / float(fit.layers.rho_e[host]),
                               rtol=1e-9)  # fmt: skip
    again = speckle.fit_phantom(fit.render(1, nthreads=1), SMALL, inclusions=True).inclusions
    assert again.sizes["inclusion"] >= 1
    assert abs(float(again.centre_x[0]) - xc) < 2 * SMALL.pixel_size
    assert abs(float(again.centre_z[0]) - zc) < 2 * SMALL.pixel_size


def test_phantom_draws_every_inclusion(patient_fit):
    """``.phantom`` draws every fitted inclusion, not only the first: the fit's inclusion and a
    second one beside it (its ``rho_e`` doubled, its density identified at twice its host's),
    each ellipse's scatterers at one energy ``100 rho_e/rho``, the counts inside in proportion
    to ``rho V`` (multinomial, within 4 SEs), the first at its host's density (not
    identified)."""
    import xarray as xr

    from speckle.studies.phantom.patients import region_volumes

    _, fit = patient_fit
    first = fit.inclusions.isel(inclusion=[0])
    host = int(first.host[0])
    second = first.copy(deep=True)
    second["centre_x"] = first.centre_x - 250.0
    second["rho_e"] = 2 * first.rho_e
    host_rho = float(fit.layers.density_bound[host])
    host_rho = max(host_rho, SMALL.n_scatterers / (SMALL.x_max * 2 * SMALL.beam_radius
                                                   * SMALL.depth_range))  # fmt: skip
    second["density"] = xr.full_like(first.density, 2 * host_rho)
    both = xr.concat([first, second], dim="inclusion").assign_coords(inclusion=[0, 1])
    table = dataclasses.replace(fit, inclusions=both).phantom(3)
    assert table.shape == (SMALL.n_scatterers, 4)
    ellipses = [tuple(float(both[v][j]) for v in ("centre_x", "centre_z", "axis_x", "axis_z"))
                for j in range(2)]  # fmt: skip
    coefficients = np.column_stack([fit.layers.top.values, fit.layers.top_tilt.values,
                                    fit.layers.top_curvature.values])[1:]  # fmt: skip
    volume, _ = region_volumes(SMALL, coefficients, ellipses)
    inside = [((table[:, 0] - xc) / w) ** 2 + ((table[:, 2] - zc) / h) ** 2 < 1
              for xc, zc, w, h in ellipses]  # fmt: skip
    energy = [np.unique(table[m, 3]) for m in inside]
    assert energy[0].size == 1 and energy[1].size == 1
    # energies 100 rho_e/rho: the second's rho is twice the first's, its rho_e twice too
    np.testing.assert_allclose(energy[1][0] / energy[0][0], 1.0, rtol=1e-9)
    counts = np.array([m.sum() for m in inside], float)
    expected = np.array([1.0, 2.0]) * volume[-2:]
    expected *= counts.sum() / expected.sum()
    se = np.sqrt(expected * (1 - expected / counts.sum()))
    assert np.all(np.abs(counts - expected) < 4 * se), (counts, expected)


@pytest.mark.slow
def test_two_inclusions_found():
    """A patient of two inclusions (reduced box, seed 11: one layer, ``ln contrast`` 2.2 and
    3.0, in different columns): both found, no false alarm, the layer count right (measured:
    both centres within a pixel; 27 s with scan and fit)."""
    case = speckle.phantom_closed_loop_case(11, config=SMALL, layers=(1, 3), shapes=("flat",),
                                            inclusions=2)  # fmt: skip
    assert int(case.n_inclusions_true) == 2 and int(case.n_inclusions_fit) == 2
    assert int(case.inclusion_found) == 2 and int(case.inclusion_false_alarms) == 0
    assert int(case.layers_right) == 1
    assert float(case.inclusion_centre_error) < 1.0


@pytest.mark.slow
def test_no_false_alarms_in_sparse_layers_2025():
    """2025 configuration, one to three flat layers, no inclusion, patients 0-4: at most 5 %
    report one, within 2 binomial SEs (24.5 %: at most 1 of 5). Before the count test 4 of 5
    did (voids of the sparse layers' scatterers, docs/explanation/phantom_fit.md); measured
    after: 0 of 5 (0 of 20 over patients 0-19 since session 45). And none of patients 5, 9, 16,
    17 (a regression guard: each reported a void after session 44; 5 and 17 in hosts without
    density or bound, 9 and 16 where the count alone, without the ellipse's speckle, called
    the void significant)."""
    cfg = speckle.synthoct_config("2025")

    def reports(seed):
        table, _ = speckle.virtual_patient(seed, config=cfg, layers=(1, 3), shapes=("flat",))
        scan = speckle.synthoct_scan(table, cfg, nthreads=1)
        return speckle.fit_phantom(scan, cfg, inclusions=True).inclusions.sizes["inclusion"] > 0

    false = sum(reports(seed) for seed in range(5))
    assert [seed for seed in (5, 9, 16, 17) if reports(seed)] == []
    assert false / 5 <= inc.FALSE_ALARM + 2 * math.sqrt(inc.FALSE_ALARM * 0.95 / 5), false


def test_off_by_default_and_refused():
    """Without ``inclusions`` the Dataset is empty (dim ``inclusion`` of 0) and the phantom
    the layers'; a non-bool is refused before any work."""
    table, _ = speckle.virtual_patient(1, config=SMALL, layers=(2, 2), shapes=("flat",))
    scan = speckle.synthoct_scan(table, SMALL, nthreads=1)
    fit = speckle.fit_phantom(scan, SMALL)
    assert fit.inclusions.sizes["inclusion"] == 0
    assert set(inc.VARIABLES) <= set(fit.inclusions.data_vars)
    with pytest.raises(TypeError, match="inclusions"):
        speckle.fit_phantom(np.zeros((3, 3), np.uint8), SMALL, inclusions="yes")


@pytest.mark.slow
def test_case_reports_the_inclusion():
    """The closed-loop case's inclusion scalars: found, no false alarm, centre within a pixel
    (patient 4: a dark inclusion, ln contrast -3.5, in the top layer)."""
    case = speckle.phantom_closed_loop_case(4, config=SMALL, layers=(1, 3), shapes=("flat",),
                                            inclusions=True)  # fmt: skip
    assert int(case.n_inclusions_true) == 1 and int(case.inclusion_found) == 1
    assert int(case.inclusion_false_alarms) == 0
    assert float(case.inclusion_centre_error) < 1.0
    assert case.inclusion_centre_error.attrs["units"] == "pixel"
    assert np.isfinite(float(case.inclusion_rho_e_pull))


@pytest.mark.slow
def test_closed_loop_rates():
    """Reduced box, one to three flat layers, seeds 0-29 (docs/explanation/phantom_fit.md,
    Inclusions). False alarms: of the same 30 patients without inclusion, at most 5 % report
    one, within 2 binomial SEs (3.98 %: at most 3 of 30; measured 0 since session 45, 3
    before, all dark ellipses in hosts without density or bound). Detection: 18 of 30 since
    session 46 (17 in session 45, when seed 1's, ln contrast -1.26, in a host whose rows the
    floor clips, was refused untested; its kurtosis bound keeps it), 15 of the 17 with ``|ln
    contrast|`` >= 1.5 (was 14 of 17 before the grid of starts; a measured floor of 14 is
    held, no derived power); the centre within a pixel in 13 of those found (was 11 of 17;
    held: 13, a measured regression guard, not derived). The shadow's ``rho E`` pulls: within 2 for
    95.45 % less 2 binomial SEs of the found ones (measured 16 of 17). The density's lower
    bound (97.7 % one-sided) holds for 97.7 % less 2 binomial SEs of the found ones (measured
    12 of 12). The level step's and the lateral geometry's pulls are still too wide (docs; not
    tested)."""
    seeds = list(range(30))
    ds = speckle.phantom_closed_loop(
        seeds, SMALL, layers=(1, 3), shapes=("flat",), inclusions=True, score=False,
        scheduler="synchronous",
    )  # fmt: skip
    false = 0
    for seed in seeds:
        case = speckle.phantom_closed_loop_case(seed, config=SMALL, layers=(1, 3),
                                                shapes=("flat",), fit_inclusions=True)  # fmt: skip
        false += int(case.n_inclusions_fit) > 0
    n = len(seeds)
    assert false / n <= inc.FALSE_ALARM + 2 * math.sqrt(inc.FALSE_ALARM * 0.95 / n), false
    contrast = []
    for seed in seeds:
        _, truth = speckle.virtual_patient(seed, config=SMALL, layers=(1, 3), shapes=("flat",),
                                           inclusions=True)  # fmt: skip
        host = int(truth.inclusion_layer[0])
        rho_e = float(truth.inclusion_density[0] * truth.inclusion_energy[0] / 100)
        contrast.append(abs(math.log(rho_e / float(truth.rho_e[host]))))
    found = ds.inclusion_found.values == 1
    strong = np.array(contrast) >= 1.5
    assert np.sum(found & strong) >= 14, (np.sum(found & strong), np.sum(strong))
    assert np.sum(ds.inclusion_centre_error.values[found] < 1) >= 13
    bound = ds.fit_inclusion_density_bound.values[found]
    true = ds.true_inclusion_density.values[found]
    held = np.mean(bound[np.isfinite(bound)] < true[np.isfinite(bound)])
    assert held >= 0.977 - 2 * math.sqrt(0.977 * 0.023 / np.isfinite(bound).sum()), held
    pulls = ds.inclusion_rho_e_shadow_pull.values[found]
    pulls = pulls[np.isfinite(pulls)]
    within = np.mean(np.abs(pulls) < 2)
    assert within >= 0.9545 - 2 * math.sqrt(0.9545 * 0.0455 / pulls.size), within


def test_untouched_lines_are_beyond_every_inclusion():
    """A line is untouched when it lies more than ``UNTOUCHED_RADII`` beam radii beyond every
    found inclusion's lateral semi-axis (the double-pass weight ``exp(-2 dx^2/r^2)``, 3e-4 at
    2 radii); no inclusion leaves every line."""
    x = np.arange(-100.0, 101.0, 5.0)
    found = xr.Dataset({"centre_x": ("inclusion", [-50.0, 40.0]),
                        "axis_x": ("inclusion", [10.0, 5.0])})  # fmt: skip
    far = inc.untouched_lines(x, found, 10.0)
    reach = inc.UNTOUCHED_RADII * 10.0
    expected = (np.abs(x + 50) > 10 + reach) & (np.abs(x - 40) > 5 + reach)
    np.testing.assert_array_equal(far, expected)
    assert far[0] and not far[x.tolist().index(-20.0)] and far[x.tolist().index(-15.0)]
    assert inc.untouched_lines(x, found.isel(inclusion=slice(0)), 10.0).all()


@pytest.mark.parametrize(("seed", "n_layers"), [(5, 4), (41, 4)])
def test_refit_with_more_layers_kept_where_untouched_lines_show_them(seed, n_layers):
    """Reduced patients with an inclusion. Patient 5's wide, dim inclusion hides two curved
    boundaries from the first fit (2 layers of 4, the boundary 47 pixels off); fitted again
    without it, all four are there, and the lines the inclusion does not reach show four
    layers too: kept (before: a refit with more layers was never kept). Patient 41: the
    refit's fifth layer (a boundary at 178 µm, 60 µm under a dark inclusion 29-117 µm deep)
    is the removal's; the untouched lines show four: not kept. Reduced seeds 0-69:
    counts right 62 -> 66 of 70, boundaries within a pixel 103 of 132 -> 112 of 145
    (docs/explanation/phantom_fit.md, "Inclusions")."""
    case = speckle.phantom_closed_loop_case(seed, config=SMALL, inclusions=True)
    assert int(case.n_true) == n_layers and int(case.n_fit) == n_layers
    assert bool(case.inclusion_found)
