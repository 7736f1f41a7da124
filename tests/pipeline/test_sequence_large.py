"""``results/elastography/sequence_large.{nc,png}`` built through Snakemake with the reduced CI
config, under the threads, processes and local dask.distributed schedulers of the ``dask``
section: the same numbers in every variable (the sequence is simulated and processed lazily,
pair by pair, and streamed to a chunked NetCDF)."""

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
TARGET = "elastography/sequence_large.nc"
SCHEDULERS = {
    "threads": {"scheduler": "threads", "address": None, "n_workers": 2},
    "processes": {"scheduler": "processes", "address": None, "n_workers": 2},
    "local_cluster": {"scheduler": "distributed", "address": None, "n_workers": 2},
}


def build(repo: Path, name: str, dask: dict) -> Path:
    results = f"results_{name}"
    (repo / f"{name}.yaml").write_text(yaml.safe_dump({"results": results, "dask": dask}))
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(repo), *filter(None, [os.environ.get("PYTHONPATH")])]),
    }
    cmd = [sys.executable, "-m", "snakemake", "--directory", str(repo)]
    cmd += ["--snakefile", str(repo / "Snakefile")]
    cmd += [f"{results}/{TARGET}", f"{results}/{TARGET.replace('.nc', '.png')}", "--cores", "2"]
    cmd += ["--configfile", "workflow/config/ci.yaml", f"{name}.yaml"]
    proc = subprocess.run(cmd, cwd=repo, env=env, capture_output=True, text=True)
    assert proc.returncode == 0, (proc.stdout + proc.stderr)[-4000:]
    return repo / results


@pytest.fixture(scope="module")
def repo(tmp_path_factory, repo_root) -> Path:
    dest = tmp_path_factory.mktemp("seq") / "repo"
    shutil.copytree(repo_root, dest, ignore=IGNORE)
    return dest


@pytest.fixture(scope="module")
def reference(repo) -> Path:
    return build(repo, "threads", SCHEDULERS["threads"])


def test_target_is_chunked_per_frame_and_follows_the_compression(reference):
    ds = open_dataset(reference / TARGET, load=False)
    assert ds["accumulated"].encoding["chunksizes"][0] == 1
    assert (reference / TARGET.replace(".nc", ".png")).stat().st_size > 0
    med = [float(np.nanmedian(ds["accumulated"].isel(frame=i).values)) for i in range(2)]
    assert med[1] > med[0] > 0  # compression accumulates


@pytest.mark.parametrize("name", ["processes", "local_cluster"])
def test_same_numbers_under_every_scheduler(repo, reference, name):
    results = build(repo, name, SCHEDULERS[name])
    a, b = open_dataset(results / TARGET), open_dataset(reference / TARGET)
    for var in ("interframe", "quality", "accumulated", "position"):
        np.testing.assert_array_equal(a[var].values, b[var].values)
