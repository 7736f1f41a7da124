"""phantom_closed_loop (issue 34): the Dask batch of the closed loop and its challenge scores."""

from __future__ import annotations

import numpy as np
import pytest
import xarray as xr
from scipy import stats

import speckle
from speckle.studies.phantom.batch import (
    MARGIN,
    MAX_LAYERS,
    phantom_closed_loop,
    phantom_score_power,
)

#: A fast scanner for the batch's bookkeeping (96 x 96 pixels).
TINY = speckle.ScannerConfig(n_pixels=96, n_lines=96, x_max=576.0, n_scatterers=20_000)
#: Large enough for MS-SSIM's five scales (176 pixels a side): the challenge's pixels and
#: density over half its width.
SCORED = speckle.ScannerConfig(n_pixels=256, n_lines=256, x_max=1536.0, n_scatterers=150_000)


@pytest.mark.filterwarnings("ignore:MS-SSIM is NaN")
def test_same_numbers_whatever_the_workers_and_chunks():
    one = phantom_closed_loop([5, 6, 7], TINY, scheduler="synchronous")
    two = phantom_closed_loop([5, 6, 7], TINY, scheduler="threads", n_workers=2)
    assert one.identical(two)
    # another chunking of the seeds: alone and in another order, the same case
    alone = phantom_closed_loop([7, 5], TINY, scheduler="synchronous")
    assert alone.sel(case=[5, 7]).identical(one.sel(case=[5, 7]))
    assert list(one.candidate.values) == ["fitted", "floor", "baseline"]
    assert one["MS-SSIM"].dims == ("case", "candidate", "map")
    assert one.true_top.attrs["units"] == "um" and one.fit_attenuation.attrs["units"] == "1/um"
    assert one.boundary_error.attrs["units"] == "pixel" and one.case.attrs["long_name"]


def test_each_case_is_the_per_case_function_padded():
    ds = phantom_closed_loop([1, 2], TINY, layers=(1, 3), score=False, scheduler="synchronous")
    assert "MS-SSIM" not in ds and ds.sizes["layer"] == MAX_LAYERS
    for seed in (1, 2):
        case = speckle.phantom_closed_loop_case(seed, config=TINY, layers=(1, 3))
        row = ds.sel(case=seed)
        n = case.sizes["layer"]
        assert int(row.n_true) == n
        for name in ("true_top", "fit_attenuation", "rho_e_pull", "boundary_error"):
            assert np.array_equal(row[name].values[:n], case[name].values, equal_nan=True)
            assert np.all(np.isnan(row[name].values[n:]))
        assert list(row.true_shape.values[:n]) == list(case.true_shape.values)
        assert bool(row.success) == bool(case.success)
        expected = "none" if case.success else ("boundary" if case.layers_right else "layer count")
        assert str(row.failure_class.values) == expected


@pytest.mark.parametrize(
    ("kwargs", "error", "match"),
    [
        ({"seeds": []}, ValueError, "seeds"),
        ({"seeds": [1, 1]}, ValueError, "seeds"),
        ({"seeds": [-1]}, ValueError, r"seeds\[0\]"),
        ({"seeds": "12"}, TypeError, "seeds"),
        ({"config": "2026"}, ValueError, "config"),
        ({"config": {"n_pixels": 64}}, TypeError, "config"),
        ({"layers": (0, 2)}, ValueError, r"layers\[0\]"),
        ({"layers": (3, 2)}, ValueError, r"layers\[1\]"),
        ({"layers": (1, 6)}, ValueError, r"layers\[1\]"),
        ({"layers": 3}, TypeError, "layers"),
        ({"shapes": ("flat", "round")}, ValueError, r"shapes\[1\]"),
        ({"shapes": "flat"}, TypeError, "shapes"),
        ({"inclusions": 5}, ValueError, "inclusions"),
        ({"inclusions": "1"}, TypeError, "inclusions"),
        ({"rescans": 0}, ValueError, "rescans"),
        ({"score": 1}, TypeError, "score"),
        ({"scheduler": "gpu"}, ValueError, "scheduler"),
        ({"n_workers": 0}, ValueError, "n_workers"),
        ({"config": speckle.ScannerConfig(n_pixels=16, n_lines=96, x_max=576.0)}, ValueError,
         "21 x 21"),
    ],
)  # fmt: skip
def test_refuses_bad_input_before_any_work(kwargs, error, match):
    args = {"seeds": [1], "config": TINY, **kwargs}
    with pytest.raises(error, match=match):
        phantom_closed_loop(args.pop("seeds"), args.pop("config"), **args)


@pytest.mark.slow
@pytest.mark.parametrize(("shapes", "cases"), [(("flat",), 12), (("flat", "tilted", "curved"), 30)])
def test_fitted_within_002_of_the_floor_on_every_map(shapes, cases):
    """The issue's acceptance: MS-SSIM of every map, target against the fitted phantom's scan,
    within 0.02 of the floor (target against the true patient drawn again with the same seed).

    One case's MS-SSIM of RSC scatters by ~0.05 between seeds, so the mean over the cases of
    the difference ``fitted - floor`` is compared: above ``-0.02 - 2 SE`` (SE from the cases'
    spread). Flat-layer patients, and patients of flat, tilted and curved boundaries. The
    baseline's two-layer phantom sits far below on some map (the test's power).

    The number of cases (phdens, session 40): a case's ``fitted - floor`` scatters by SD 0.030
    (SC, flat) and 0.055 / 0.049 (SC / RSC, every shape), so 8 cases gave SE 0.01-0.02 and
    passed anything above -0.04 to -0.06. The test fails a true mean ``delta`` below the margin
    with probability ``Phi((-0.02 - 2 SE - delta)/SE)``: 80 % at 0.03 beyond the margin needs
    ``SE <= 0.03/2.84 = 0.0106``, 8 flat cases (SC) and 27 of every shape (SC); 80 % at 0.02
    beyond needs ``SE <= 0.0070``, 18 and 62. Taken: 12 flat (93 % at -0.05) and 30 of every
    shape (83 % at -0.05). Measured (single process, shared machine, load 8.5): 139 s for the
    12 flat cases, 367 s for the 30 (8 cases: 147 s and 181 s); with 2 workers 101 s and 151 s.
    """
    ds = phantom_closed_loop(range(cases), SCORED, shapes=shapes, scheduler="threads",
                             n_workers=2)  # fmt: skip
    ms = ds["MS-SSIM"]
    diff = ms.sel(candidate="fitted") - ms.sel(candidate="floor")
    mean, se = diff.mean("case"), diff.std("case", ddof=1) / np.sqrt(ds.sizes["case"])
    # measured (Struct, OAC, SC, RSC): flat, 12 cases, -0.001, -0.004, +0.008, +0.000 (SE
    # 0.002, 0.005, 0.009, 0.006), all succeed. Every shape, 30 cases: -0.003, -0.003, +0.005,
    # -0.019 (SE 0.004, 0.005, 0.010, 0.009), 22 succeed; RSC -0.021 +- 0.009 over the 22
    # (shaped boundaries within a pixel still cost RSC; flat ones do not). Earlier, 8 cases:
    # the baseline -0.17, -0.32, -0.40, -0.33 (flat) and -0.10, -0.21, -0.33, -0.24
    # On the merged boundary fit (phscore, session 41, the same seeds and draws), every shape,
    # 30 cases: -0.005, -0.006, +0.005, -0.007 (SE 0.003, 0.002, 0.008, 0.005), RSC -0.001 +-
    # 0.005 over the 18 shaped ones (the RSC deficit is gone with the boundary merge); per-case
    # SD over seeds 0-39: 0.017, 0.022, 0.040, 0.035 (phantom_score_power: 15 cases for 80 %)
    assert np.all(mean > -0.02 - 2 * se), (mean.values, se.values)
    base = ms.sel(candidate="baseline") - ms.sel(candidate="floor")
    assert np.any(base.mean("case") < -0.02 - 2 * se)


@pytest.mark.filterwarnings("ignore:MS-SSIM is NaN")
def test_a_refused_scan_is_a_row_not_a_crash(monkeypatch):
    """A scan the fit refuses (seen: seed 3401 of the 2025 configuration, a sparse top layer
    with 10-14 % of its pixels below the window's floor) is recorded with its reason."""
    from speckle.studies.phantom import batch

    real = batch.phantom_closed_loop_case

    def refusing(seed, **kwargs):
        if seed == 6:
            raise ValueError("scan has 0 rows above the floor (<= 10% clipped)")
        return real(seed, **kwargs)

    monkeypatch.setattr(batch, "phantom_closed_loop_case", refusing)
    ds = phantom_closed_loop([6, 5], TINY, scheduler="synchronous")
    row = ds.sel(case=6)
    assert str(row.failure_class.values) == "refused"
    assert "0 rows above the floor" in str(row.failure.values)
    assert int(row.success) == 0 and np.all(np.isnan(row["MS-SSIM"].values))
    _, truth = speckle.virtual_patient(6, config=TINY, layers=(1, 3))
    n = truth.sizes["layer"]
    assert int(row.n_true) == n and np.allclose(row.true_top.values[:n], truth.top_mean.values)
    assert ds.fit_attenuation.attrs["units"] == "1/um"  # the refused row first: units kept
    assert str(ds.sel(case=5).failure_class.values) in {"none", "layer count", "boundary"}


@pytest.mark.parametrize(("cases", "sd"), [(5, 0.03), (12, 0.04), (30, 0.055)])
def test_score_power_is_the_simulated_rejection_rate(cases, sd):
    """The score test run on simulated normal differences (true mean 0.03 below the margin,
    SD ``sd``): its rejection rate equals the noncentral-t power within 3 binomial SEs."""
    rng = np.random.default_rng(np.random.SeedSequence([34, cases]))
    trials = 20_000
    d = rng.normal(-MARGIN - 0.03, sd, (trials, cases))
    se = d.std(axis=1, ddof=1) / np.sqrt(cases)
    rate = np.mean(d.mean(axis=1) < -MARGIN - 2 * se)
    power = phantom_score_power(cases, sd)
    assert abs(rate - power) < 3 * np.sqrt(power * (1 - power) / trials), (rate, power)


def test_score_power_limits_and_input():
    # many cases: the normal limit Phi(beyond sqrt(n)/sd - 2)
    n = 2000
    assert phantom_score_power(n, 0.5) == pytest.approx(
        stats.norm.cdf(0.03 * np.sqrt(n) / 0.5 - 2), abs=2e-3
    )
    # rising with the cases from 3 on (2 cases: a t of one degree of freedom, whose heavy tail
    # makes the SE's draw fail the test more often than 3 cases do)
    grid = phantom_score_power(np.arange(2, 60), 0.055)
    assert np.all(np.diff(grid[1:]) > 0) and grid[0] > grid[1] and grid.shape == (58,)
    for kwargs, error, match in [
        ({"cases": 1}, ValueError, "cases"),
        ({"cases": 2.5}, ValueError, "cases"),
        ({"cases": "8"}, TypeError, "cases"),
        ({"sd": 0.0}, ValueError, "sd"),
        ({"sd": np.nan}, ValueError, "sd"),
        ({"beyond": -0.01}, ValueError, "beyond"),
        ({"beyond": True}, TypeError, "beyond"),
    ]:
        args = {"cases": 8, "sd": 0.05, **kwargs}
        with pytest.raises(error, match=match):
            phantom_score_power(args.pop("cases"), args.pop("sd"), **args)


def test_score_summary_states_its_power():
    """The pipeline's summary: the power of its own test at the measured per-case SD."""
    from speckle.figures.phantom import score_summary

    rng = np.random.default_rng(3)
    ms = rng.uniform(0.5, 0.9, (1, 10, 3, 4))  # configuration, case, candidate, map
    ds = xr.Dataset(
        {"MS-SSIM": (("configuration", "case", "candidate", "map"), ms)},
        coords={"configuration": ["challenge"], "candidate": ["fitted", "floor", "baseline"],
                "map": ["Struct", "OAC", "SC", "RSC"]},
    )  # fmt: skip
    out = score_summary(ds).sel(configuration="challenge", candidate="fitted")
    diff = ms[0, :, 0] - ms[0, :, 1]
    assert np.allclose(out.power.values, phantom_score_power(10, diff.std(axis=0, ddof=1)))
    assert np.all(np.isnan(score_summary(ds).power.sel(candidate="floor").values))
