"""The flow-contrast study against its derived theory (speckle.studies.dynamics).

* the expected contrasts are checked on circular Gaussian frames drawn with the pairwise
  correlations the theory assumes (Monte Carlo, derived SE from the samples);
* the floors and the decorrelation calibration of simulated scenes (shared scene, scanned beam,
  receiver noise) against their derived values, within the standard error of ``R`` independent
  repeats: ``z = (measured - theory)/SE`` is Student-t with ``R - 1`` degrees of freedom, and
  the bound is its quantile for a family-wise false alarm of 1 % over the ``m`` values tested
  (Bonferroni), derived in :func:`t_bound`.
"""

from __future__ import annotations

import math

import dask
import numpy as np
import pytest
from scipy import special, stats

from speckle.analysis.dynamics_theory import g1_transverse_flow
from speckle.studies.dynamics import (
    FLOW_CONTRASTS,
    contrast_estimates,
    contrast_floors,
    decorrelation_calibration,
    expected_contrast,
    flow_failure,
    velocity_range,
)

DB2 = (10 / math.log(10)) ** 2
GEO = dict(n_pixels=24, n_lines=16, pixel_size=4.0, k0_dk=10.0, waist=8.0, density=16.0, margin=4)


def t_bound(m: int, repeats: int, alpha: float = 0.01) -> float:
    """|t| bound of ``m`` Student-t values (``repeats - 1`` dof), family-wise false alarm alpha."""
    return float(stats.t.ppf(1 - alpha / (2 * m), repeats - 1))


@pytest.fixture(autouse=True)
def _synchronous():
    with dask.config.set(scheduler="synchronous"):
        yield


def test_floors_are_the_closed_forms():
    n = 5
    for snr_db in (0.0, 10.0, 30.0):
        s = 1 / (1 + 10 ** (-snr_db / 10))
        assert contrast_floors("speckle_variance", n_frames=n, snr_db=snr_db) == pytest.approx(
            ((n - 1) / n * (1 - s**2), (n - 1) / n)
        )
        m = s**2  # SSADA: 1 - (E(m) - (1 - m) K(m))/m
        ratio = (special.ellipe(m) - (1 - m) * special.ellipk(m)) / m
        assert contrast_floors("decorrelation", n_frames=n, snr_db=snr_db) == pytest.approx(
            (1 - ratio, 1 - math.pi / 4)
        )
        li2 = special.spence(1 - s**2)
        assert contrast_floors("liv", n_frames=n, snr_db=snr_db) == pytest.approx(
            (DB2 * (n - 1) / n * (math.pi**2 / 6 - li2), DB2 * (n - 1) / n * math.pi**2 / 6)
        )
    # no noise, static: identical frames, every contrast zero
    for c in FLOW_CONTRASTS:
        assert contrast_floors(c, n_frames=3, snr_db=math.inf)[0] == pytest.approx(0, abs=1e-12)


@pytest.mark.parametrize("contrast", FLOW_CONTRASTS)
def test_expected_contrast_on_gaussian_frames(contrast):
    """Frames of circular Gaussian fields with rho_ij = s g1(|i-j|): the estimator's mean over
    independent pixels is within 3.5 of its sample SE of the theory."""
    rng = np.random.default_rng(7)
    n, pixels, snr_db = 4, 200_000, 6.0
    g1 = np.array([0.8, 0.5, 0.2])
    s = 1 / (1 + 10 ** (-snr_db / 10))
    lag = np.abs(np.subtract.outer(np.arange(n), np.arange(n)))
    rho = np.where(lag == 0, 1.0, s * np.r_[1.0, g1][lag])
    chol = np.linalg.cholesky(rho)
    z = (rng.standard_normal((n, pixels)) + 1j * rng.standard_normal((n, pixels))) / math.sqrt(2)
    field = (chol @ z).reshape(n, 400, 500)
    theory = expected_contrast(contrast, g1, snr_db=snr_db)
    value, win = contrast_estimates(contrast, field, window=(1, 1), intensity=1.0)
    se = win.std(ddof=1) / math.sqrt(win.size)  # independent pixels
    assert value == pytest.approx(win.mean(), rel=1e-12)
    assert abs(value - theory) < 3.5 * se, (value, theory, se)


def test_transverse_flow_g1_and_velocity_range_invert():
    lo, hi = velocity_range(
        "liv", n_frames=4, interval=1e-3, snr_db=20.0, waist=8.0, low=5.0, high=20.0
    )
    for v, level in ((lo, 5.0), (hi, 20.0)):
        g1 = g1_transverse_flow(np.arange(1, 4) * 1e-3, velocity=v, waist=8.0)
        assert expected_contrast("liv", g1, snr_db=20.0) == pytest.approx(level, rel=1e-9)
    # the range scales as w0/interval
    lo2, hi2 = velocity_range(
        "liv", n_frames=4, interval=2e-3, snr_db=20.0, waist=16.0, low=5.0, high=20.0
    )
    assert (lo2, hi2) == pytest.approx((lo, hi), rel=1e-9)
    # a level below the static floor: never told from static tissue
    static, _ = contrast_floors("liv", n_frames=4, snr_db=20.0)
    with pytest.warns(RuntimeWarning, match="low=.* lies outside the floors"):
        lo3, hi3 = velocity_range(
            "liv", n_frames=4, interval=1e-3, snr_db=20.0, waist=8.0, low=static / 2, high=20.0
        )
    assert math.isnan(lo3) and math.isnan(hi3)
    # levels in the wrong order: an empty range, NaN v_high with its reason
    with pytest.warns(RuntimeWarning, match="range is empty"):
        lo4, hi4 = velocity_range(
            "liv", n_frames=4, interval=1e-3, snr_db=20.0, waist=8.0, low=20.0, high=5.0
        )
    assert lo4 == pytest.approx(hi) and math.isnan(hi4)


def test_simulated_floors_match_their_derived_values():
    ds = flow_failure(
        GEO,
        velocities=[0.0, 40000.0],
        snr_db=[5.0, 20.0],
        intervals=[1e-3],
        n_frames=4,
        window=(4, 4),
        repeats=8,
        seed=3,
    )
    bound = t_bound(18, 8)  # 6 static, 6 noise, 6 fully decorrelated values
    for name in ("static_floor", "noise_floor"):
        z = (ds[name] - ds[f"{name}_theory"]) / ds[f"{name}_se"]
        assert float(abs(z).max()) < bound, ds[[name, f"{name}_theory", f"{name}_se"]]
    # no motion is static tissue: the v = 0 column is the static floor (same frames and noise)
    np.testing.assert_allclose(
        ds.measured.sel(velocity=0.0).squeeze("interval"), ds.static_floor, rtol=1e-12
    )
    # 40 mm/s moves 40 µm = 5 w0 per frame: fully decorrelated, at the noise floor's value
    fast = ds.measured.sel(velocity=40000.0).squeeze("interval")
    z = (fast - ds.noise_floor_theory) / ds.measured_se.sel(velocity=40000.0).squeeze("interval")
    assert float(abs(z).max()) < bound, fast
    assert set(np.unique(ds.status.values)) <= {0, 1, 2}
    assert (ds.status.sel(velocity=0.0) == 0).all()


def test_decorrelation_calibration_against_theory():
    ds = decorrelation_calibration(
        GEO,
        velocities=[0.0, 2000.0, 4000.0, 8000.0, 16000.0],
        interval=1e-3,
        snr_db=25.0,
        n_frames=3,
        repeats=8,
        seed=11,
    )
    z = (ds.decorrelation - ds.theory) / ds.decorrelation_se
    # v = 0: identical frames but for their noise, SE > 0 from the noise
    assert float(abs(z).max()) < t_bound(5, 8), ds.to_dataframe()
    assert np.all(np.diff(ds.theory.values) > 0)
    assert ds.velocity.attrs["units"] == "um/s"


@pytest.mark.parametrize(
    "kwargs,message",
    [
        ({"velocities": [-1.0]}, "velocities"),
        ({"velocities": [2.0, 1.0]}, "velocities"),
        ({"intervals": [0.0]}, "intervals"),
        ({"n_frames": 1}, "n_frames"),
        ({"repeats": 1}, "repeats"),
        ({"snr_db": [20.0, 10.0]}, "snr_db"),
    ],
)
def test_bad_input_is_refused_before_work(kwargs, message):
    args = dict(
        velocities=[0.0],
        snr_db=[10.0],
        intervals=[1e-3],
        n_frames=2,
        window=(2, 2),
        repeats=2,
        seed=0,
    )
    with pytest.raises(ValueError, match=message):
        flow_failure(GEO, **{**args, **kwargs})
    with pytest.raises(ValueError, match="contrast"):
        expected_contrast("variance", [0.5])
    with pytest.raises(ValueError, match="g1"):
        expected_contrast("liv", [1.5])


def test_phantom_series_says_why_a_region_mean_is_nan():
    """A vessel below the image holds no pixel: its region means are NaN, with a warning that
    names the region; a phantom that is not a dict, or lacks keys, is refused naming it."""
    from speckle.studies.dynamics_series import phantom_series

    geo = dict(n_pixels=16, n_lines=8, pixel_size=4.0, k0_dk=10.0, waist=8.0, density=4.0)
    ph = dict(
        interface=24.0,
        backscatter=[1.0, 2.0],
        cells=dict(centre=[12.0, 16.0], radius=6.0, diffusion=0.5),
        vessel=dict(depth=500.0, radius=8.0, peak_velocity=2000.0),
        angiography=dict(frames=3, interval=2e-3),
        doct=dict(frames=3, interval=4e-3, delays=[4e-3, 8e-3]),
        window=[3, 3],
        n_bands=2,
    )
    with pytest.warns(RuntimeWarning, match=r"region\(s\) \[3\]"):
        ds = phantom_series(geo, ph, snr_db=30.0, seed=1)
    assert np.isnan(ds.liv_region.values[3]) and np.all(np.isfinite(ds.liv_region.values[:3]))
    with pytest.raises(TypeError, match="phantom"):
        phantom_series(geo, [ph], snr_db=30.0, seed=1)
    with pytest.raises(ValueError, match=r"phantom lacks .*vessel"):
        phantom_series(geo, {k: v for k, v in ph.items() if k != "vessel"}, snr_db=30.0, seed=1)
