"""results/despeckle/ through Snakemake on the reduced CI configuration, and its config checks.

The despeckle targets run once (module fixture) in a temporary copy of the repository with the
copy's ``speckle`` first on ``PYTHONPATH``; the outputs are then checked against the contract of
issue 19 and the theory. Bad ``despeckle`` sections stop ``snakemake -n`` before any job, with
the key named.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from workflow_run import CI_CONFIG, CI_RESULTS, IGNORE, snakemake

from speckle.analysis.filters import FILTERS, filter_available
from speckle.io import open_dataset

pytestmark = [pytest.mark.pipeline, pytest.mark.slow]

TARGETS = [
    "phantom.nc",
    "phantom.png",
    "methods.nc",
    "methods.png",
    "failure.nc",
    "failure.png",
    "frequency_compounding.nc",
]


@pytest.fixture(scope="module")
def repo(tmp_path_factory, repo_root) -> Path:
    repo = tmp_path_factory.mktemp("despeckle") / "repo"
    shutil.copytree(repo_root, repo, ignore=IGNORE)
    return repo


@pytest.fixture(scope="module")
def results(repo) -> Path:
    targets = [f"{CI_RESULTS}/despeckle/{t}" for t in TARGETS]
    proc = snakemake(repo, "--cores", "2", *targets, "--configfile", CI_CONFIG, check=False)
    assert proc.returncode == 0, proc.stdout[-5000:]
    return repo / CI_RESULTS / "despeckle"


def test_every_output_is_written(results):
    for t in TARGETS:
        assert (results / t).stat().st_size > 0, t


def test_frequency_compounding_contract_and_theory(results):
    ds = open_dataset(results / "frequency_compounding.nc")
    assert ds.looks.values.tolist() == [1, 2, 4, 8]
    assert {"contrast", "contrast_theory", "axial_fwhm", "axial_fwhm_theory"} <= set(ds.data_vars)
    assert ds.attrs["density"] >= 8 and ds.attrs["n_pixels"] >= 256 and ds.attrs["n_lines"] >= 256
    assert ds.axial_fwhm.attrs["units"] == "um"
    # measured within the SE (16 blocks of lines) of the exact finite-density theory: four
    # correlated values (one realisation), each |z| < 3.5 (family-wise false alarm < 0.2 %)
    z = abs(ds.contrast - ds.contrast_theory) / ds.contrast_standard_error
    assert float(z.max()) < 3.5, ds.to_dataframe()
    np.testing.assert_allclose(ds.contrast_dense, 1 / np.sqrt(ds.looks), rtol=1e-12)
    # band-limited x64 interpolation: linear crossing error ~(1/64)^2 of a pixel
    np.testing.assert_allclose(ds.axial_fwhm, ds.axial_fwhm_theory, rtol=1e-3)
    ratio = ds.axial_fwhm_theory / ds.axial_fwhm_theory.sel(looks=1)
    np.testing.assert_allclose(ratio, ds.looks, rtol=5e-3)


def test_methods_table_has_every_family_and_metric(results):
    ds = open_dataset(results / "methods.nc")
    families = set(ds.family.values.tolist())
    expected = {"frequency", "angular", "spatial", "polarization", "temporal"}
    expected |= {f for f in FILTERS if filter_available(f)}
    assert expected <= families
    assert set(ds.averaging.values.tolist()) >= {"intensity", "magnitude", "complex"}
    assert set(ds.domain.values.tolist()) >= {"linear", "log"}
    assert set(ds.noise.values.tolist()) == {0, 1}
    for v in (
        "contrast",
        "enl",
        "cnr",
        "psnr",
        "ssim",
        "fwhm_axial",
        "fwhm_lateral",
        "edge_width",
        "resolution_loss",
        "speckle_reduction",
        "time_per_mpx",
    ):
        assert np.isfinite(ds[v].values).mean() > 0.9, v
    # complex averaging of one realisation removes no speckle: rectangular sub-bands tiling the
    # band sum to the full-band field, so the contrast is the single look's exactly
    names = ds.technique.values.tolist()
    c = dict(zip(names, ds.contrast.values.tolist(), strict=True))
    for nl in (2, 4):
        assert c[f"frequency L={nl} rectangular overlap=0 complex"] == pytest.approx(
            c["single look"], rel=1e-9
        )
    # and for every set of looks it removes less than intensity averaging does
    for name in names:
        if name.endswith(" complex") or name.endswith(" complex + noise"):
            assert c[name] > c[name.replace(" complex", " intensity")], name
    ph = open_dataset(results / "phantom.nc")
    assert {"labels", "truth", "single_look", "best"} <= set(ph.data_vars)
    assert set(ph.family.values.tolist()) == expected


def test_failure_map_sweeps(results):
    ds = open_dataset(results / "failure.nc")
    for axis in ("density", "snr_db", "feature_radius"):
        for v in ("speckle_reduction", "feature_retained", "helps", "erases"):
            assert ds[f"{v}_{axis}"].dims == ("technique", axis)
    names = ds.technique.values.tolist()
    np.testing.assert_allclose(ds.speckle_reduction_density.values[names.index("single")], 1.0)


@pytest.mark.parametrize(
    "override,message",
    [
        ({"physical": {"frequency": {"looks": [2, 200]}}}, "n_looks"),
        ({"physical": {"frequency": {"overlap": [1.5]}}}, "overlap"),
        ({"physical": {"temporal": {"diffusion": -1.0}}}, "diffusion"),
        ({"filters": {"median": {"size": [4]}}}, "size"),
        ({"filters": {"anisotropic": {"k": [1]}}}, "anisotropic"),
        ({"frequency_compounding": {"looks": [1, 3]}}, "multiple"),
    ],
)
def test_bad_despeckle_config_stops_before_any_job(repo, override, message):
    path = repo / "bad_despeckle.yaml"
    path.write_text(yaml.safe_dump({"despeckle": override}))
    proc = snakemake(repo, "-n", "--configfile", CI_CONFIG, str(path), check=False)
    assert proc.returncode != 0
    assert message in proc.stdout, proc.stdout[-3000:]
