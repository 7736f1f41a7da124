"""results/twin/ through Snakemake on the reduced CI config, and its config refusals.

The target runs in a copy of the repository (as ``tests/test_pipeline.py`` does) with the
copy's package first on ``PYTHONPATH``: the shipped PDMS image is fitted, compared with its
twin and the failure maps are predicted. Bad ``twin`` sections stop the workflow when it loads,
naming the key.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
import yaml
from workflow_run import IGNORE

from speckle.io import open_dataset

pytestmark = [pytest.mark.pipeline, pytest.mark.slow]

CI_CONFIG = "workflow/config/ci.yaml"
RESULTS = "results_ci"  # the CI config's results folder
TARGETS = [f"{RESULTS}/twin/" + f for f in ("fit.nc", "compare.png", "failure.png")]


def snakemake(repo: Path, *args: str) -> subprocess.CompletedProcess:
    env = {**os.environ, "PYTHONPATH": str(repo)}
    cmd = [sys.executable, "-m", "snakemake", "--directory", str(repo), *args]
    proc = subprocess.run(cmd, cwd=repo, env=env, capture_output=True, text=True)
    proc.stdout += proc.stderr
    return proc


@pytest.fixture(scope="module")
def repo(tmp_path_factory, repo_root) -> Path:
    path = tmp_path_factory.mktemp("twin") / "repo"
    shutil.copytree(repo_root, path, ignore=IGNORE)
    return path


def test_twin_target_on_the_shipped_image(repo):
    proc = snakemake(repo, "--cores", "1", "--configfile", CI_CONFIG, "--", *TARGETS)
    assert proc.returncode == 0, proc.stdout[-4000:]
    ci = yaml.safe_load((repo / CI_CONFIG).read_text())["twin"]
    fit = open_dataset(repo / RESULTS / "twin/fit.nc")
    for k in ("spectrum_width", "waist", "snr_db", "attenuation", "inverse_density"):
        assert np.isfinite(float(fit[k])) and float(fit[f"{k}_se"]) > 0, k
    assert fit.waist.attrs["units"] == "um" and fit.attrs["kind"] == "log"
    cmp_ = open_dataset(repo / RESULTS / "twin/compare.nc")
    assert list(cmp_.source.values) == ["measured", "twin"]
    assert cmp_.sizes["lag"] == ci["max_lag"] + 1
    depth = ci["region"]["depth"]
    assert cmp_.measured_image.shape == (depth[1] - depth[0], ci["region"]["x"][1])
    failure = open_dataset(repo / RESULTS / "twin/failure.nc")
    assert list(failure.method.values) == ci["failure"]["methods"]
    assert np.allclose(failure.strain, ci["failure"]["strains"])
    assert (repo / RESULTS / "twin/failure.png").stat().st_size > 0
    assert "waist =" in (repo / RESULTS / "logs/twin.log").read_text()


@pytest.mark.parametrize(
    ("twin", "message"),
    [
        ({"region": {"depth": [95, 600]}}, "twin.region.depth"),
        ({"kind": "decibel"}, "decibel"),
        ({"noise_rows": [500, 530]}, "twin.noise_rows"),
        ({"region": {"depth": [95, 100]}}, "too small for"),
        ({"image": "no/such/file.npy"}, "twin.image"),
    ],
)
def test_bad_twin_config_is_refused_when_the_workflow_loads(repo, twin, message):
    (repo / "bad.yaml").write_text(yaml.safe_dump({"twin": twin}))
    proc = snakemake(repo, "-n", "--configfile", CI_CONFIG, "bad.yaml")
    assert proc.returncode != 0 and message in proc.stdout, proc.stdout[-3000:]
