"""The challenge's metrics: the published table of its self-consistency check, and refusals."""

from __future__ import annotations

import csv
import importlib.util
from pathlib import Path

import numpy as np
import pytest
import xarray as xr

import speckle

DATA = Path(speckle.__file__).parent / "data" / "synthoct"
#: The orchestrator's three comparisons: seed A against seed B of each phantom, and (its
#: "Cross_Uniform_vs_Layers") the uniform phantom's A against the layered phantom's A.
EXPERIMENTS = {
    "Exp1_Uniform": ("Exp1_Uniform_A", "Exp1_Uniform_B"),
    "Exp2_Layers": ("Exp2_Layers_A", "Exp2_Layers_B"),
    "Cross_Uniform_vs_Layers": ("Exp1_Uniform_A", "Exp2_Layers_A"),
}
#: The issue's acceptance: absolute for SSIM, MS-SSIM, VIF and PSNR (dB), relative for MSE.
TOLERANCE = {"SSIM": 0.01, "MS-SSIM": 0.01, "VIF": 0.01, "PSNR": 0.1}


def _published() -> dict[tuple[str, str], dict[str, float]]:
    with open(DATA / "Final_Metrics_Report.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    return {
        (r["Experiment"], r["Map_Type"]): {k: float(v) for k, v in r.items() if k in
                                           speckle.METRIC_NAMES}
        for r in rows
    }  # fmt: skip


@pytest.fixture(scope="module")
def computed() -> dict[str, xr.Dataset]:
    return {
        name: speckle.synthoct_metrics(DATA / f"Scan_{a}.png", DATA / f"Scan_{b}.png", lpips=False)
        for name, (a, b) in EXPERIMENTS.items()
    }


@pytest.mark.parametrize("experiment", list(EXPERIMENTS))
def test_published_table_is_reproduced(computed, experiment):
    """Every row of Final_Metrics_Report.csv within the issue's tolerances (LPIPS aside).

    The computation is the orchestrator's arithmetic operation for operation (the maps' PNGs
    are equal pixel for pixel, test_maps), so the agreement is to rounding: 4e-15 measured;
    asserted at 1e-9 (relative for PSNR and MSE).
    """
    published = _published()
    ds = computed[experiment]
    assert list(ds["map"].values) == ["Struct", "OAC", "SC", "RSC"]
    for name in ds["map"].values:
        row = published[(experiment, str(name))]
        got = {m: float(ds[m].sel(map=name)) for m in ("SSIM", "MS-SSIM", "PSNR", "MSE", "VIF")}
        for metric, tol in TOLERANCE.items():
            assert abs(got[metric] - row[metric]) <= tol, (name, metric)
            assert got[metric] == pytest.approx(row[metric], rel=1e-9, abs=1e-9), (name, metric)
        assert got["MSE"] == pytest.approx(row["MSE"], rel=0.02)
        assert got["MSE"] == pytest.approx(row["MSE"], rel=1e-9)
        assert np.isnan(float(ds["LPIPS"].sel(map=name)))


def test_identical_scans_score_perfectly():
    scan = DATA / "Scan_Exp2_Layers_B.png"
    ds = speckle.synthoct_metrics(scan, scan, lpips=False)
    for metric in ("SSIM", "MS-SSIM"):
        np.testing.assert_allclose(ds[metric].values, 1.0, rtol=1e-12)
    # VIF's gain is var/(var + 1e-10): 1 - O(1e-10/var), var >= 1 grey level squared here
    np.testing.assert_allclose(ds["VIF"].values, 1.0, rtol=1e-9)
    assert np.all(ds["MSE"].values == 0) and np.all(np.isinf(ds["PSNR"].values))
    assert ds["PSNR"].attrs["units"] == "dB" and ds["SSIM"].attrs["units"] == "1"


def test_ms_ssim_and_vif_equal_sewar():
    """The scipy reimplementation equals sewar's msssim and vifp (the orchestrator's)."""
    import sewar.full_ref as sewar  # the [test] extra installs it

    # private: the two reimplemented metrics are compared with the reference package directly
    from speckle.synthoct.metrics import _ms_ssim, _vif

    rng = np.random.default_rng(3)
    a = rng.integers(0, 256, (256, 512), dtype=np.uint8)
    b = np.clip(a + rng.integers(-40, 40, a.shape), 0, 255).astype(np.uint8)
    assert _ms_ssim(a, b) == pytest.approx(float(np.real(sewar.msssim(a, b))), abs=1e-12)
    assert _vif(a, b) == pytest.approx(sewar.vifp(a, b), abs=1e-12)


@pytest.mark.skipif(
    importlib.util.find_spec("lpips") is not None, reason="lpips installed: LPIPS is computed"
)
def test_lpips_without_its_packages_is_nan_and_says_why():
    rng = np.random.default_rng(0)
    a = rng.integers(0, 256, (180, 200), dtype=np.uint8)
    with pytest.warns(RuntimeWarning, match=r"speckle-oct\[lpips\]"):
        ds = speckle.synthoct_metrics(a, a)
    assert np.all(np.isnan(ds["LPIPS"].values))


def test_ms_ssim_of_small_images_is_nan_and_says_why():
    """Five scales of an 11-pixel window need 11 x 2**4 = 176 pixels a side."""
    a = np.random.default_rng(0).integers(0, 256, (175, 200), dtype=np.uint8)
    with pytest.warns(RuntimeWarning, match="176 pixels"):
        ds = speckle.synthoct_metrics(a, a, lpips=False)
    assert np.all(np.isnan(ds["MS-SSIM"].values)) and np.all(ds["SSIM"].values == 1)


def test_physical_variant_differs_where_the_quirks_act():
    """Physical: the same Struct scores up to the truncation quirk, other maps."""
    a, b = (DATA / f"Scan_{s}.png" for s in EXPERIMENTS["Exp1_Uniform"])
    official = speckle.synthoct_metrics(a, b, lpips=False)
    physical = speckle.synthoct_metrics(a, b, variant="physical", lpips=False)
    assert physical.attrs["variant"] == "physical"
    # Struct: MSE/PSNR/SSIM read level/255 (the luminance only to an ulp): equal to 1e-12
    for metric in ("MSE", "SSIM"):
        assert float(physical[metric].sel(map="Struct")) == pytest.approx(
            float(official[metric].sel(map="Struct")), rel=1e-12
        )
    assert not np.allclose(physical["SSIM"].values[1:], official["SSIM"].values[1:])


@pytest.mark.parametrize(
    ("reference", "target", "kwargs", "error", "word"),
    [
        (np.zeros((40, 40), np.uint8), np.zeros((40, 41), np.uint8), {}, ValueError, "target"),
        (np.zeros((40, 40), np.uint16), np.zeros((40, 40), np.uint8), {}, TypeError, "reference"),
        (np.zeros((40, 40), np.uint8), np.zeros((40, 40), float), {}, TypeError, "target"),
        (np.zeros((0, 40), np.uint8), np.zeros((0, 40), np.uint8), {}, ValueError, "reference"),
        (np.zeros((40, 40), np.uint8), np.zeros((0, 40), np.uint8), {}, ValueError, "target"),
        (np.zeros((20, 40), np.uint8), np.zeros((20, 40), np.uint8), {}, ValueError, "reference"),
        (np.zeros((40, 40), np.uint8), "missing.png", {}, ValueError, "target"),
        (np.zeros((40, 40), np.uint8), np.zeros((40, 40), np.uint8), {"variant": "x"},
         ValueError, "variant"),
        (np.zeros((40, 40), np.uint8), np.zeros((40, 40), np.uint8), {"lpips": 1},
         TypeError, "lpips"),
    ],
)  # fmt: skip
def test_bad_input_is_refused(reference, target, kwargs, error, word):
    with pytest.raises(error, match=word):
        speckle.synthoct_metrics(reference, target, **kwargs)


def test_vif_of_a_constant_reference_is_nan_and_says_why():
    """A constant reference has no variance at any scale: VIF is sewar's 0/0, NaN, with a
    warning giving the reason; the other metrics answer (PSNR of two levels 20 apart)."""
    a = np.full((40, 40), 100, np.uint8)
    b = np.full((40, 40), 120, np.uint8)
    with pytest.warns(RuntimeWarning, match="VIF is NaN: the reference has no variance"):
        ds = speckle.synthoct_metrics(a, b, lpips=False)
    assert np.isnan(ds["VIF"].values[0])
    assert ds["PSNR"].values[0] == pytest.approx(-10 * np.log10((20 / 255) ** 2), rel=1e-6)
