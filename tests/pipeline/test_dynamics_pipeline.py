"""results/dynamics/ through Snakemake on the reduced CI configuration, and its config checks.

The dynamics targets run once (module fixture) in a temporary copy of the repository with the
copy's ``speckle`` first on ``PYTHONPATH``; the outputs are checked against the contract of
issue 35 and their theory, each ``z = (measured - theory)/SE`` against the Student-t bound of
its degrees of freedom for a family-wise false alarm of 1 % (Bonferroni over the values
tested). Bad ``dynamics`` sections stop ``snakemake -n`` before any job, with the key named.
"""

from __future__ import annotations

import shutil
from pathlib import Path

import numpy as np
import pytest
import yaml
from scipy import stats
from workflow_run import CI_CONFIG, CI_RESULTS, IGNORE, snakemake

from speckle.io import open_dataset

pytestmark = [pytest.mark.pipeline, pytest.mark.slow]

TARGETS = [
    f"{name}.{ext}" for name in ("phantom", "g1", "failure", "calibration") for ext in ("nc", "png")
]


def t_bound(m: int, dof: int, alpha: float = 0.01) -> float:
    """|t| bound of ``m`` Student-t values with ``dof`` degrees of freedom (family-wise)."""
    return float(stats.t.ppf(1 - alpha / (2 * m), dof))


@pytest.fixture(scope="module")
def repo(tmp_path_factory, repo_root) -> Path:
    repo = tmp_path_factory.mktemp("dynamics") / "repo"
    shutil.copytree(repo_root, repo, ignore=IGNORE)
    return repo


@pytest.fixture(scope="module")
def results(repo) -> Path:
    targets = [f"{CI_RESULTS}/dynamics/{t}" for t in TARGETS]
    proc = snakemake(repo, "--cores", "1", *targets, "--configfile", CI_CONFIG, check=False)
    assert proc.returncode == 0, proc.stdout[-5000:]
    return repo / CI_RESULTS / "dynamics"


def test_every_output_is_written(results):
    for t in TARGETS:
        assert (results / t).stat().st_size > 0, t


def test_g1_contract_and_theory(results):
    ds = open_dataset(results / "g1.nc")
    assert {"brownian", "transverse_flow"} <= set(ds.model.values.tolist())
    assert ds.lag.attrs["units"] == "s" and ds.lag.dims == ("lag",)
    assert {"g1", "g1_se", "g1_theory"} <= set(ds.data_vars)
    assert ds.g1.dims == ("model", "lag")
    assert ds.diffusion.attrs["units"] == "um^2/s" and ds.velocity.attrs["units"] == "um/s"
    assert float(ds.diffusion.sel(model="brownian")) > 0
    assert float(ds.velocity.sel(model="transverse_flow")) > 0
    for key in ("k0", "refractive_index", "waist"):
        assert key in ds.attrs, key
    lag = ds.lag.values > 0  # |g1(0)| = 1 exactly
    z = ((ds.g1 - ds.g1_theory) / ds.g1_se).values[:, lag]
    # blocks of lines: t with blocks - 1 dof; lags of one curve are correlated (the bound is
    # Bonferroni, conservative for them)
    assert np.abs(z).max() < t_bound(z.size, int(ds.attrs["blocks"]) - 1), z


def test_failure_floors_and_maps(results):
    ds = open_dataset(results / "failure.nc")
    assert ds.measured.dims == ("contrast", "velocity", "snr_db", "interval")
    assert ds.velocity.attrs["units"] == "um/s" and ds.interval.attrs["units"] == "s"
    dof = int(ds.attrs["repeats"]) - 1
    for name in ("static_floor", "noise_floor"):
        z = ((ds[name] - ds[f"{name}_theory"]) / ds[f"{name}_se"]).values
        z = z[np.isfinite(z)]
        assert np.abs(z).max() < t_bound(z.size, dof), (name, z)
    assert set(np.unique(ds.status.values)) <= {0, 1, 2}
    assert (ds.status.sel(velocity=0.0) == 0).all()  # no motion: static tissue
    # fast flow at high SNR: every contrast leaves the static floor
    fast = ds.status.sel(velocity=ds.velocity.max(), snr_db=ds.snr_db.max())
    assert (fast > 0).all()


def test_calibration_against_theory(results):
    ds = open_dataset(results / "calibration.nc")
    z = ((ds.decorrelation - ds.theory) / ds.decorrelation_se).values
    assert np.abs(z).max() < t_bound(z.size, int(ds.attrs["repeats"]) - 1), z
    assert np.all(np.diff(ds.theory_curve.values) >= 0)


def test_phantom_moving_regions_stand_out(results):
    ds = open_dataset(results / "phantom.nc")
    for name in ("speckle_variance", "ssada", "liv", "liv_doct", "ocds"):
        assert ds[name].dims == ("depth", "x"), name
    for name in ("speckle_variance", "ssada", "liv", "liv_doct"):
        means = ds[f"{name}_region"].values  # layer 1, layer 2, cells, vessel
        assert min(means[2], means[3]) > 2 * max(means[0], means[1]), (name, means)


@pytest.mark.parametrize(
    "override,message",
    [
        ({"phantom": {"cells": {"diffusion": -1.0}}}, "diffusion"),
        ({"phantom": {"vessel": {"peak_velocity": 1.0e6}}}, "peak_velocity"),
        ({"failure": {"intervals": [4.0e-3, 1.0e-3]}}, "failure.intervals"),
        ({"failure": {"window": [64, 2]}}, "failure.window"),
        ({"phantom": {"cells": {"centre": [500.0, 64.0]}}}, "phantom.cells"),
        ({"phantom": {"doct": {"delays": [4.0e-3, 5.0e-3]}}}, "doct.delays"),
        ({"g1": {"velocity": 1.0e9}}, "g1.velocity"),
        ({"geometry": {"margin": 16}}, "geometry.margin"),
    ],
)
def test_bad_dynamics_config_stops_before_any_job(repo, override, message):
    path = repo / "bad_dynamics.yaml"
    path.write_text(yaml.safe_dump({"dynamics": override}))
    proc = snakemake(repo, "-n", "--configfile", CI_CONFIG, str(path), check=False)
    assert proc.returncode != 0
    assert message in proc.stdout, proc.stdout[-3000:]
