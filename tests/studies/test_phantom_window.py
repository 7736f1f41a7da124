"""The window's top of the phantom fit: each placing layer's estimate weighted by the inverse of
its variance, a layer that disagrees with the others left out (docs/explanation/phantom_fit.md,
"The window's top: weights")."""

import numpy as np
import pytest

import speckle

# private: the layers' weights are the fit's own step (the private module _window)
from speckle.studies.phantom._window import window_weights


def _replicates(spread, blocks=16, seed=0):
    """Jackknife replicates whose delete-one-block variance is exactly ``spread**2`` per layer."""
    rng = np.random.default_rng(seed)
    x = rng.standard_normal((blocks, len(spread)))
    x = (x - x.mean(0)) / np.sqrt((blocks - 1) / blocks * np.sum((x - x.mean(0)) ** 2, 0))
    return x * np.asarray(spread)


def test_window_weights_are_inverse_variances():
    """Weights ``1/(jackknife variance + offset variance)``; with two layers neither is left
    out, however far apart (which one is wrong cannot be told)."""
    spread, osd = np.array([0.02, 0.3]), np.array([0.01, 0.04])
    est = np.array([0.0, 5.0])
    w = window_weights(est, est + _replicates(spread), osd)
    np.testing.assert_allclose(w, 1.0 / (spread**2 + osd**2), rtol=1e-12)


def test_window_weights_leave_out_the_layer_that_disagrees():
    """Four layers: one 10 SE from the others' mean is left out, one 1.5 SE off is kept; a
    layer without an estimate in some replicate gets no weight."""
    spread, osd = np.full(4, 0.05), np.zeros(4)
    est = np.array([0.0, 0.0, 0.05 * 1.5 * np.sqrt(1 + 1 / 2), 0.05 * 10])
    reps = est + _replicates(spread)
    w = window_weights(est, reps, osd)
    assert w[3] == 0 and np.all(w[:3] > 0)
    reps[5, 1] = np.nan
    w = window_weights(est, reps, osd)
    assert w[1] == 0 and w[3] == 0 and np.all(w[[0, 2]] > 0)
    assert not window_weights([np.nan], np.full((16, 1), np.nan), [0.0]).any()
    assert window_weights([], [[] for _ in range(16)], []).size == 0  # no layer places it


@pytest.fixture(scope="module")
def patient32():
    cfg = speckle.synthoct_config("challenge")
    table, truth = speckle.virtual_patient(32, config=cfg)
    field = speckle.synthoct_scan(table, cfg, field=True, nthreads=1)
    fit = speckle.fit_phantom(speckle.synthoct_scan(table, cfg, nthreads=1), cfg)
    return truth, 20 * np.log10(np.abs(field.values).max()), fit.layers


def test_challenge_patient_whose_bottom_slope_is_not_its_brightness(patient32):
    """Challenge patient 32: its faint bottom layer (``mu`` 5.6e-6/µm) has a slope of
    1.18e-4 +- 0.33e-4 over its rows, 21 times the truth at 3.6 SE. Weighted by rows (88 of
    its 244), it put the window's top 6.0 dB high (6.3 SE) and the two layers without a
    measurable slope at 4.2 and 4.4 times their ``rho E`` (pulls +4.4, +4.5). Its estimate
    of the window's top is 3.0 neper above the other two's, and it is left out: measured, the
    window 0.39 SE low, the four upper layers' ``rho E`` pulls +0.09, -0.62, +0.72, +0.34
    (the bottom layer's ``rho E`` is its slope's, pull +3.4)."""
    truth, top, layers = patient32
    assert layers.sizes["layer"] == truth.sizes["layer"] == 5
    assert abs(layers.attrs["window_top"] - top) < 2 * layers.attrs["window_top_se"]
    true_rho_e = (truth.density * truth.energy / 100).values
    pull = (layers.rho_e.values - true_rho_e) / layers.rho_e_se.values
    assert np.all(np.abs(pull[:4]) < 2.5), pull
