"""Layers under the window's floor (speckle.studies.phantom._floor): a layer so dim that most
of its pixels are clipped, between two bright ones or below the last, is fitted as a layer of
its own, its brightness from its censored pixels (docs/explanation/phantom_fit.md, "A layer
under the window's floor")."""

import math

import numpy as np
import pytest

import speckle

# private: the censored mean, the gap rule and the forced cuts against their definitions
from speckle.studies.phantom._count import segment, segment_rss  # private: the cuts
from speckle.studies.phantom._density import _CLIP  # private: the window's clip
from speckle.studies.phantom._floor import (  # private: the floor layers' rules
    BOUND_LEVEL,
    DARK_DROP,
    LINE_SCATTER,
    RISE_STEP,
    all_clipped_bound,
    censored_mean,
    dark_gaps,
)
from speckle.studies.phantom.patients import patient_table

C = math.exp(_CLIP)  # the window's clip, I/I_max


def test_censored_mean_is_the_exponential_mean():
    """200 draws of 4000 exponential intensities of mean 1.3 c, left-censored at c (46 %
    clipped): the maximum-likelihood means average to 1.3 c within 4 SE (the draws' spread);
    no clipped pixel gives the plain mean, every pixel clipped NaN."""
    rng = np.random.default_rng(0)
    theta = 1.3 * C
    est = []
    for _ in range(200):
        i = rng.exponential(theta, 4000)
        est.append(censored_mean(i, i < C))
    est = np.array(est)
    se = est.std(ddof=1) / math.sqrt(est.size)
    assert abs(est.mean() - theta) < 4 * se
    assert 0.01 < est.std() / theta < 0.05  # 4000 pixels, 54 % of them measured
    i = rng.exponential(theta, 100) + C
    assert censored_mean(i, np.zeros(100, bool)) == pytest.approx(i.mean(), rel=1e-12)
    assert math.isnan(censored_mean(i, np.ones(100, bool)))


def test_censored_mean_subtracts_known_tails():
    """Rows of exponential speckle of mean theta + a_r (a_r known, 0 to 2 theta: a bright
    neighbour's PSF tail), censored at c: 100 draws of 8 rows of 1000 pixels give back theta
    within 4 SE; ignoring the tails gives a mean 40 % higher."""
    rng = np.random.default_rng(3)
    theta = 0.8 * C
    tail = np.array([2.0, 1.0, 0.5, 0.2, 0.1, 0.0, 0.0, 0.0]) * theta
    est, plain = [], []
    for _ in range(100):
        i = rng.exponential((theta + tail)[:, None], (tail.size, 1000))
        est.append(censored_mean(i, i < C, tail))
        plain.append(censored_mean(i, i < C))
    est = np.array(est)
    assert abs(est.mean() - theta) < 4 * est.std(ddof=1) / math.sqrt(est.size)
    assert np.mean(plain) > 1.3 * theta


def test_all_clipped_bound_is_its_definition():
    """Every one of n cells below the clip has probability BOUND_LEVEL at the bound."""
    for n in (1, 30, 2000):
        b = all_clipped_bound(n)
        assert (-math.expm1(-C / b)) ** n == pytest.approx(BOUND_LEVEL, rel=1e-9)


def test_dark_gaps_need_the_psf_steps():
    """A gap whose last row above it drops more than DARK_DROP below the line of the rows
    before, and whose first row below it lies below the line of the rows after, is a layer
    under the floor (RISE_STEP: the step up may be smaller); a layer fading into the gap is
    not, nor a dim layer whose rows come back above the floor (no step up: 2025 patient 3),
    nor a gap after rows that are not one line (a transition among them); below the last run
    the gap reaches the box's bottom rows."""
    m = -0.01 * np.arange(100.0)
    runs = [(3, 40), (55, 97)]
    assert dark_gaps(m, runs, 100, gap=2) == []
    both = m.copy()
    both[37:40] -= [0.5, 1.0, DARK_DROP + 0.1]
    both[55:58] -= [RISE_STEP + 0.1, 0.5, 0.2]
    assert dark_gaps(both, runs, 100, gap=2) == [(40, 55)]
    assert dark_gaps(both, runs[:1], 100, gap=2) == [(40, 97)]
    entered = both.copy()
    entered[55:58] = m[55:58]
    assert dark_gaps(entered, runs, 100, gap=2) == []
    faint = both.copy()
    faint[39] = m[39] - (DARK_DROP - 0.1)
    assert dark_gaps(faint, runs, 100, gap=2) == []
    transition = both.copy()  # a boundary's step among the rows of the line: no comparison
    transition[30:34] -= LINE_SCATTER + 0.5
    assert dark_gaps(transition, runs, 100, gap=2) == []


def test_segmentation_cuts_at_a_floor_layer():
    """With a forced cut at row 20 no segment holds rows on both sides, the next starts there
    with no gap left out, and K = 1 is not offered; K = 2 is the cut itself."""
    rng = np.random.default_rng(1)
    z = np.arange(50) * 6.0
    m = np.where(z < 120, -0.002 * z, -3 - 0.001 * z) + rng.normal(0, 0.05, z.size)
    w = np.ones(z.size)
    best = segment(z, m, w, 4, gap=2, min_rows=4, cuts=(20,))
    assert 1 not in best and set(best) == {2, 3, 4}
    rss = segment_rss(z, m, w, min_rows=4)
    assert best[2][1] == [(0, 20), (20, 50)]
    assert best[2][0] == pytest.approx(rss[0, 20] + rss[20, 50], rel=1e-12)
    for _, segs in best.values():
        assert not any(a < 20 < b for a, b in segs)


def _three_layers(q, seed, *, thickness=16, terminal=False):
    """The failure map's phantom (reduced box, flat layers, E = 0.2 %), the middle layer's (or,
    with ``terminal``, the lower of two layers') energy ``q`` times its neighbours': its
    8-bit scan, true tops (µm) and true ``rho E/100`` per layer."""
    cfg = speckle.synthoct_config("reduced")
    h, p = cfg.depth_range, cfg.pixel_size
    if terminal:
        tops = np.array([0.0, h / 2])
        energy = np.array([0.2, 0.2 * q])
    else:
        tops = np.array([0.0, h / 4, h / 4 + thickness * p])
        energy = np.array([0.2, 0.2 * q, 0.2])
    coef = np.column_stack([tops[1:], np.zeros((tops.size - 1, 2))])
    rng = np.random.default_rng(np.random.SeedSequence([seed, 0, 0]))
    table, _ = patient_table(cfg, coef, np.ones(energy.size), energy, None, rng)
    edges = np.append(tops, h)
    volume = cfg.x_max * 2 * cfg.beam_radius * np.diff(edges)
    counts = np.histogram(table[:, 2], bins=edges)[0]
    scan = np.asarray(speckle.synthoct_scan(table, cfg, nthreads=1))
    return scan, cfg, tops, counts / volume * energy / 100


@pytest.mark.slow
def test_a_middle_layer_under_the_floor_is_fitted():
    """Three flat layers, the middle one 16 pixels thick and 1e-4 times as bright (40 dB, about
    half its pixels clipped; session 52's fit put both boundaries 29-54 µm off): three layers,
    the middle one a floor layer, both boundaries within a pixel, every ``rho E`` within 3 SE
    of the truth. Its fitted phantom, rendered and fitted again, has the floor layer too. So
    for a layer of 8 pixels, whose rows all hold its neighbours' PSF tails, and at 1e-5 (its
    inner rows all clipped: identified from the rows its neighbours' tails lift)."""
    scan, cfg, tops, rho_e = _three_layers(1e-4, 0)
    fit = speckle.fit_phantom(scan, cfg)
    layers = fit.layers
    assert layers.floor.values.tolist() == [False, True, False]
    assert np.all(np.abs(layers.top.values - tops) < cfg.pixel_size)
    pulls = (layers.rho_e.values - rho_e) / layers.rho_e_se.values
    assert np.all(np.abs(pulls) < 3), pulls
    assert np.isnan(layers.rho_e_bound.values).all()
    again = speckle.fit_phantom(np.asarray(fit.render(1, nthreads=1)), cfg).layers
    assert again.floor.values.tolist() == [False, True, False]

    scan, cfg, tops, rho_e = _three_layers(1e-4, 0, thickness=8)  # 8 px: the tails subtracted
    layers = speckle.fit_phantom(scan, cfg).layers
    assert layers.floor.values.tolist() == [False, True, False]
    assert np.all(np.abs(layers.top.values - tops) < cfg.pixel_size)
    pulls = (layers.rho_e.values - rho_e) / layers.rho_e_se.values
    assert np.all(np.abs(pulls) < 3), pulls

    scan, cfg, tops, rho_e = _three_layers(1e-5, 0)
    layers = speckle.fit_phantom(scan, cfg).layers
    assert layers.floor.values.tolist() == [False, True, False]
    assert np.all(np.abs(layers.top.values - tops) < cfg.pixel_size)
    pull = (layers.rho_e.values[1] - rho_e[1]) / layers.rho_e_se.values[1]
    assert abs(pull) < 3 and np.isnan(layers.rho_e_bound.values[1])  # from the tails' rows


def test_an_entirely_clipped_floor_layer_has_a_bound():
    """A middle layer 1e-6 times as bright (60 dB): every pixel of its rows clipped but where
    its neighbours' tails reach; ``rho E`` not identified, its upper bound above the truth."""
    scan, cfg, _, rho_e = _three_layers(1e-6, 0)
    layers = speckle.fit_phantom(scan, cfg).layers
    assert layers.floor.values.tolist() == [False, True, False]
    assert np.isnan(layers.rho_e.values[1]) and layers.rho_e_bound.values[1] > rho_e[1]


@pytest.mark.slow
def test_two_layers_under_the_floor():
    """Two middle layers 1e-4 times as bright, 16 pixels each, around a bright one of 12
    pixels: five layers, the second and fourth floor layers, every boundary within a pixel.
    (Around a bright layer of 7 pixels, whose rows hold both transitions, neither gap has a
    clean line on that side: no floor layer, as before; docs/explanation/phantom_fit.md.)"""
    cfg = speckle.synthoct_config("reduced")
    h, p = cfg.depth_range, cfg.pixel_size
    tops = np.array([0.0, h / 4, h / 4 + 16 * p, h / 4 + 28 * p, h / 4 + 44 * p])
    coef = np.column_stack([tops[1:], np.zeros((4, 2))])
    rng = np.random.default_rng(np.random.SeedSequence([0, 0, 0]))
    energy = np.array([0.2, 2e-5, 0.2, 2e-5, 0.2])
    table, _ = patient_table(cfg, coef, np.ones(5), energy, None, rng)
    layers = speckle.fit_phantom(np.asarray(speckle.synthoct_scan(table, cfg, nthreads=1)),
                                 cfg).layers  # fmt: skip
    assert layers.floor.values.tolist() == [False, True, False, True, False]
    assert np.all(np.abs(layers.top.values - tops) < p)


@pytest.mark.slow
def test_a_bottom_layer_under_the_floor_is_fitted():
    """Two flat layers, the lower one 1e-4 times as bright, from half the box's depth: two
    layers, the lower one a floor layer, its boundary within a pixel, both ``rho E`` within
    3 SE."""
    scan, cfg, tops, rho_e = _three_layers(1e-4, 0, terminal=True)
    layers = speckle.fit_phantom(scan, cfg).layers
    assert layers.floor.values.tolist() == [False, True]
    assert abs(float(layers.top[1]) - tops[1]) < cfg.pixel_size
    pulls = (layers.rho_e.values - rho_e) / layers.rho_e_se.values
    assert np.all(np.abs(pulls) < 3), pulls


def test_published_scans_have_no_floor_layer():
    """The published two-layer scan: no layer under the floor, ``rho_e_bound`` NaN."""
    from importlib.resources import files

    scan = files("speckle.data") / "synthoct" / "Scan_Exp2_Layers_A.png"
    layers = speckle.fit_phantom(scan, speckle.ScannerConfig()).layers
    assert not layers.floor.values.any()
    assert np.isnan(layers.rho_e_bound.values).all()
