"""``results/elastography/failure_maps.{nc,png}`` built through Snakemake with the reduced CI
config: every sweep has the mean over seeds and its standard error for the relative rms error
and the answered fraction, with dims and units; the points and seeds run on the config's Dask
scheduler and give the same numbers with one synchronous worker as with two threads."""

import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from workflow_run import CI_CONFIG, IGNORE, snakemake

from speckle.figures.elastography import FAILURE_SWEEPS
from speckle.io import open_dataset
from speckle.studies.failure import mean_and_se

pytestmark = [pytest.mark.pipeline, pytest.mark.slow]
TARGET = "elastography/failure_maps.nc"
SCHEDULERS = {
    "threads": {"scheduler": "threads", "address": None, "n_workers": 2},
    "synchronous": {"scheduler": "synchronous", "address": None, "n_workers": 1},
}


def build(repo: Path, name: str) -> Path:
    results = f"results_{name}"
    (repo / f"{name}.yaml").write_text(
        yaml.safe_dump({"results": results, "dask": SCHEDULERS[name]})
    )
    targets = [f"{results}/{TARGET}", f"{results}/{TARGET.replace('.nc', '.png')}"]
    snakemake(repo, *targets, "--cores", "2", "--configfile", CI_CONFIG, f"{name}.yaml")
    return repo / results


@pytest.fixture(scope="module")
def repo(tmp_path_factory, repo_root) -> Path:
    dest = tmp_path_factory.mktemp("failure") / "repo"
    shutil.copytree(repo_root, dest, ignore=IGNORE)
    return dest


@pytest.fixture(scope="module")
def ci(repo_root) -> dict:
    return yaml.safe_load((repo_root / CI_CONFIG).read_text())["elastography"]


@pytest.fixture(scope="module")
def reference(repo) -> Path:
    return build(repo, "threads")


def test_failure_maps_have_means_and_standard_errors_over_seeds(reference, ci):
    ds = open_dataset(reference / TARGET)
    fc = ci["failure"]
    assert (ds.attrs["n_pixels"], ds.attrs["n_alines"]) == (fc["n_pixels"], fc["n_alines"])
    assert ds.sizes["replicate"] == fc["n_seeds"] >= 2
    assert list(ds.method.values) == ci["methods"]
    for name in FAILURE_SWEEPS:
        for var in ("relative_rms_error", "answered"):
            mean, se, per_seed = (ds[f"{var}_{name}{s}"] for s in ("", "_se", "_per_seed"))
            assert mean.dims == se.dims == (name, "method")
            assert per_seed.dims == (name, "method", "replicate")
            assert mean.attrs["units"] == se.attrs["units"] == "1"
            m, e = mean_and_se(per_seed.values)
            np.testing.assert_allclose(mean.values, m, equal_nan=True)
            np.testing.assert_allclose(se.values, e, equal_nan=True)
        answered = ds[f"answered_{name}_se"].values
        assert np.all(np.isfinite(answered) & (answered >= 0))
        assert ds[name].attrs["units"]
    # the seeds are independent scenes: the vector method's error differs between them
    per_seed = ds["relative_rms_error_strain_per_seed"].sel(method="vector").values
    assert np.all(np.isfinite(per_seed)) and np.all(per_seed[:, 0] != per_seed[:, 1])
    np.testing.assert_allclose(ds.strain.values, fc["strain"])
    assert (reference / TARGET.replace(".nc", ".png")).stat().st_size > 0


def test_same_numbers_whatever_the_scheduler_and_workers(repo, reference):
    other = build(repo, "synchronous")
    a, b = open_dataset(other / TARGET), open_dataset(reference / TARGET)
    assert set(a.data_vars) == set(b.data_vars)
    for var in a.data_vars:
        np.testing.assert_array_equal(a[var].values, b[var].values, err_msg=var)
