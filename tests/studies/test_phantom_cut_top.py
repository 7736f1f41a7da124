"""Layers near the window's floor (issue 34): a top layer cut by the floor takes ``rho E`` from the
mean intensity of its own rows, its attenuation ``A2 rho E`` and the window's top with it; a
layer without a significant slope takes ``rho E`` from its rows' mean intensity too."""

from __future__ import annotations

import math
import warnings

import numpy as np
import pytest

import speckle
from speckle.studies.phantom import slab_constants

# private: the censored row means' slope, the fit's own step (the private module _censoring)
from speckle.studies.phantom._censoring import slope_gains

# private: the PSF's area and the layers' clipped rates are the fit's own steps (_density)
from speckle.studies.phantom._density import _psf_area, clip_rates

# private: the rows above the floor are the fit's first step (the private module _fit)
from speckle.studies.phantom._floor import MAX_CLIPPED, _above_floor, _log_intensity

# private: the window-and-brightness chain of the fit (the private module _window) is the unit
from speckle.studies.phantom._window import cut_top_rho_e, window_and_brightness

# private: the scanner's own 8-bit window makes the levels
from speckle.synthoct._scan import DYNAMIC_RANGE, LEVELS, to_levels

CFG = speckle.synthoct_config("2025")


def _model(re0, re1, t1, wt, blocks=4):
    """Exact mean profiles of two dense layers (``rho E/100`` ``re0`` over ``0..t1``, ``re1``
    below): the top layer's own rows' mean intensity, and the fitted rows as the fit sees them
    when the floor cut the top layer (4 rows in the transition, slope wrong, then layer 1)."""
    consts, p = slab_constants(CFG.beam_radius), CFG.pixel_size
    scale = consts["a2_y"] * _psf_area(CFG)
    mu0, mu1 = consts["A2"] * re0, consts["A2"] * re1
    own = np.arange(3, int(t1 / p) - 2) * p
    intensity = re0 * scale * np.exp(-2 * mu0 * own - wt)
    z = np.concatenate([np.arange(4) * p + t1 - 3 * p, np.arange(8, 200) * p + t1])
    level = math.log(re1 * scale) - np.euler_gamma - wt
    m = np.where(z < t1, -2.0 + 0.66 * (z - t1), level - 2 * mu0 * t1 - 2 * mu1 * (z - t1))
    segs = [(0, 4), (6, z.size)]
    fitted = {
        "mu": np.array([-0.33, mu1]), "mu_se": np.array([0.01, mu1 / 50]),
        "mu_jk": np.tile([-0.33, mu1], (blocks, 1)), "tops": np.array([0.0, t1]),
        "tops_jk": np.tile([0.0, t1], (blocks, 1)),
        "offsets": np.full(2, -np.euler_gamma), "offsets_se": np.zeros(2),
        "intensity": np.exp(m + np.euler_gamma),
        "intensity_jk": np.tile(np.exp(m + np.euler_gamma), (blocks, 1)),
    }  # fmt: skip
    cut = {"z": own, "intensity": intensity, "intensity_jk": np.tile(intensity, (blocks, 1))}
    return m, np.tile(m, (blocks, 1)), z, segs, fitted, cut


@pytest.mark.parametrize("re0", [1e-6, 3e-5])
def test_cut_top_chain_recovers_a_model_profile(re0):
    """The chain inverts its own model: ``rho E`` of the cut top layer, its ``mu = A2 rho E``
    and the window's top exactly (1e-9), the deeper layer's ``rho E`` as ``mu/A2``; without
    ``cut_top`` the transition's slope (-0.33/µm) would be taken as the top layer's."""
    re1, t1, wt = 3.2e-5, 378.9, 7.5
    m, m_jk, z, segs, fitted, cut = _model(re0, re1, t1, wt)
    out = window_and_brightness(m, m_jk, z, segs, fitted, CFG, cut_top=cut)
    a2 = slab_constants(CFG.beam_radius)["A2"]
    assert out["rho_e"][0] == pytest.approx(re0, rel=1e-9)
    assert out["mu"][0] == pytest.approx(a2 * re0, rel=1e-9)
    assert out["mu_jk"][:, 0] == pytest.approx(a2 * re0, rel=1e-9)
    assert out["wt"] == pytest.approx(wt, abs=1e-9)
    assert out["rho_e"][1] == pytest.approx(re1, rel=1e-12)
    plain = window_and_brightness(m, m_jk, z, segs, fitted, CFG)
    assert plain["mu"][0] == -0.33  # the old reading: a negative attenuation


def test_cut_top_rho_e_refuses_nothing_silently():
    """No intensity in the rows (every pixel zero) gives NaN, not a number."""
    z = np.arange(3, 20) * CFG.pixel_size
    assert math.isnan(cut_top_rho_e(np.zeros(z.size), z, 50.0, 3.0, CFG))


def test_sparse_top_layer_cut_by_the_floor():
    """2025 patient 5 (three flat layers): its top layer is sparse (0.00097 per µm^3, ``var ln
    I`` about 11) and 7-24 % of its rows' pixels are clipped, so only 4 rows in the next
    boundary's transition were fitted; their slope read as its attenuation gave -0.33/µm and
    ``rho E`` 7.9 times the truth (pull +5.1). From its rows' mean intensity: every layer's
    ``rho E`` and attenuation within 3 SE of the truth (measured pulls +1.07, -1.55, -1.65).
    Since its clipped pixels are known for sparse speckle's empty ones (each lateral block's
    mean intensity puts fully developed speckle's clip under 5 %), its rows are fitted and the
    cut top's path is not taken: measured ``rho E`` pulls +0.31, -1.64, -1.44."""
    case = speckle.phantom_closed_loop_case(5, config="2025", shapes=("flat",), layers=(1, 3))
    assert int(case.n_fit) == int(case.n_true) == 3
    assert float(case.fit_attenuation[0]) > 0
    for name in ("rho_e_pull", "attenuation_pull"):
        assert np.all(np.abs(case[name].values) < 3), (name, case[name].values)


def test_dim_sparse_layer_brightness_from_its_mean_intensity():
    """2025 patient 6 (three flat layers, 1-5 drawn): its middle layer has no significant slope
    and no rows far enough above the floor for ``var ln I`` (0.0040 per µm^3: ``E ln(I/<I>)``
    -0.77, not ``-gamma``). From the mean of its rows' ``ln I`` with ``-gamma`` its ``rho E``
    came out 0.83 times the truth (pull -7.0); from their mean intensity, which needs no
    speckle statistics, every layer's ``rho E`` is within 3 SE (measured pulls +1.10, -0.17,
    -0.35)."""
    case = speckle.phantom_closed_loop_case(6, config="2025", shapes=("flat",), layers=(1, 5))
    assert int(case.n_fit) == int(case.n_true) == 3
    assert np.all(np.abs(case.rho_e_pull.values) < 3), case.rho_e_pull.values


def test_cut_top_layer_boundary_from_its_brightness():
    """2025 patient 1 (1-5 layers drawn, three flat): its top layer (0.0011 per µm^3, ``rho E``
    5.3e-7 over 2.35e-5) is cut by the floor. Its boundary was located with the line of the
    few rows the floor left, in the transition: 0.70 pixel off, pull +4.8. Located again with
    the layer's line from its brightness (and the ``E ln(I/<I>)`` its rows show), over those
    rows too: within 3 SE (measured 0.003 pixel, pull +0.06). Its rows are fitted as sparse
    speckle now (the cut top's path is not taken): 0.02 pixel, pull +0.51."""
    case = speckle.phantom_closed_loop_case(1, config="2025", shapes=("flat",), layers=(1, 5))
    assert int(case.n_fit) == int(case.n_true) == 3
    assert abs(float(case.top_pull[1])) < 3, float(case.top_pull[1])


def test_rows_above_the_floor_keep_sparse_speckle_not_a_floor():
    """Which rows the fit keeps (964 lines, 16 lateral blocks of 60; ``c`` the clip, the
    intensity of level 1's lower edge 51 dB - 1 level below the peak).

    - Fully developed speckle of ``<I> = c/0.16`` clips ``1 - exp(-0.16) = 14.8 %`` (SD 1.1 %
      over 964 pixels: 4.3 SD above :data:`MAX_CLIPPED`) and a block's mean (CV 13 %) never
      puts it under 5 %: left out, the floor.
    - Fully developed speckle of ``<I> = c/0.03``: 3.0 % clipped, kept.
    - Sparse speckle: 15 % of the pixels empty (``c/100``), the others exponential of mean
      ``200 c``: 15.4 % clipped, but every block's mean (about ``170 c``) puts fully developed
      speckle's clip at 0.6 %: kept.
    - Half the lines at the floor and half of mean ``1000 c``: the row's mean would pass
      (0.2 %), the floor's blocks do not: left out.
    - A bright row (holds the peak): kept."""
    rng = np.random.default_rng(11)
    n = 964
    c = 10 ** ((DYNAMIC_RANGE / LEVELS - DYNAMIC_RANGE) / 10)  # I/I_max of level 1's edge
    dense_floor = rng.exponential(c / 0.16, n)
    dense = rng.exponential(c / 0.03, n)
    sparse = np.where(rng.random(n) < 0.15, c / 100, rng.exponential(200 * c, n))
    half = np.where(np.arange(n) < n // 2, c / 100, rng.exponential(1000 * c, n))
    bright = rng.exponential(0.05, n)
    bright[0] = 1.0
    intensity = np.stack([dense_floor, dense, sparse, half, bright])
    assert intensity[:4].max() < 1.0
    levels = to_levels(np.sqrt(intensity))
    clipped = np.mean(levels == 0, axis=1)
    assert clipped[0] > MAX_CLIPPED and clipped[2] > MAX_CLIPPED and clipped[3] >= 0.5
    assert _above_floor(levels).tolist() == [False, True, True, False, True]
    with warnings.catch_warnings():  # fewer lines than blocks: a line a block, no empty block
        warnings.simplefilter("error")
        assert _above_floor(levels[:, :8])[4]


@pytest.mark.parametrize("empty", [0.0, 0.15])
def test_censored_row_means_fall_by_the_slope_gain(empty):
    """A layer of exponential speckle decaying as ``exp(-2 mu z)`` (``u = c/<I>`` 0.005 to
    0.037 over 100 rows of 4000 lines), a share ``empty`` of its pixels far under the clip
    (``c/100``: a sparse layer's empty pixels). Its censored row means (clipped pixels at
    ``ln c - 1``) fall as ``-2 mu g``, ``g = (1 - empty) exp(-u) (1 + u)``: 0.85 within 0.1 %
    with 15 % empty (the gain the fit measures, within 3 of the slope's SEs; ``-2 mu``
    itself more than 10 SEs off), and fully developed speckle's gain is 1 exactly (its
    clipped count is fully developed speckle's: no gain taken)."""
    rng = np.random.default_rng(5)
    n_rows, n, p, mu = 100, 4000, 2.2, 0.0045
    z = np.arange(n_rows) * p
    c = 10 ** ((DYNAMIC_RANGE / LEVELS - DYNAMIC_RANGE) / 10)
    mean = c / 0.005 * np.exp(-2 * mu * z)
    intensity = rng.exponential(mean[:, None], (n_rows, n))
    intensity[rng.random((n_rows, n)) < empty] = c / 100
    levels = to_levels(np.sqrt(np.vstack([intensity, np.ones((1, n))])))[:n_rows]
    li = _log_intensity(levels)
    gain = slope_gains(levels, [(0, n_rows)], clip_rates(li, z, [(0, n_rows)]))
    if empty == 0.0:
        assert gain.tolist() == [1.0]
        return
    assert float(gain[0]) == pytest.approx(1 - empty, abs=0.003)
    (slope, _), cov = np.polyfit(z, li.mean(axis=1), 1, cov=True)
    se = math.sqrt(cov[0, 0])
    assert abs(slope + 2 * mu * gain[0]) < 3 * se, (slope, -2 * mu * gain[0], se)
    assert abs(slope + 2 * mu) > 10 * se
