"""Elastography config constraints refused when the workflow loads (``snakemake -n``), naming
the key, before any job; and the same checks called directly."""

import copy
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest
import yaml
from workflow_run import IGNORE

from speckle.pipeline.checks import check_config

BAD = {
    "elastography.window": {"elastography": {"window": [1, 4]}},
    "elastography.window too large": {"elastography": {"window": [32, 4096]}},
    "elastography.tol": {"elastography": {"tol": 5}},
    "elastography.failure.windows[0]": {"elastography": {"failure": {"windows": [1, 8]}}},
    "elastography.failure.n_alines": {
        "elastography": {"window": [32, 8], "failure": {"n_alines": 4}}
    },
    "elastography.failure.n_alines too large": {
        "elastography": {"failure": {"n_pixels": 4096, "n_alines": 4096, "density": [16.0]}}
    },
    "elastography.failure.n_seeds": {"elastography": {"failure": {"n_seeds": 1}}},
}
#: Refused by the schema (snakemake's validate), not by check_config.
SCHEMA_ONLY = {"elastography.tol", "elastography.failure.n_seeds"}


def _merge(base: dict, over: dict) -> dict:
    out = copy.deepcopy(base)
    for key, value in over.items():
        if isinstance(value, dict) and isinstance(out.get(key), dict):
            out[key] = _merge(out[key], value)
        else:
            out[key] = value
    return out


@pytest.fixture(scope="module")
def merged(repo_root) -> dict:
    base = yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())
    return _merge(base, yaml.safe_load((repo_root / "workflow/config/ci.yaml").read_text()))


@pytest.mark.parametrize("key", [k for k in BAD if k not in SCHEMA_ONLY])
def test_check_config_names_the_key(merged, key):
    name = key.split(" ")[0].replace("[", r"\[").replace("]", r"\]")
    with pytest.raises(ValueError, match=name):
        check_config(_merge(merged, BAD[key]))


@pytest.mark.slow
@pytest.mark.parametrize("key", list(BAD))
def test_snakemake_dry_run_refuses_before_any_job(tmp_path, repo_root, key):
    repo = tmp_path / "repo"
    shutil.copytree(repo_root, repo, ignore=IGNORE)
    (repo / "bad.yaml").write_text(yaml.safe_dump(BAD[key]))
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(repo), *filter(None, [os.environ.get("PYTHONPATH")])]),
    }
    cmd = [sys.executable, "-m", "snakemake", "-n", "--directory", str(repo)]
    cmd += ["--snakefile", str(repo / "Snakefile")]
    cmd += ["--configfile", "workflow/config/ci.yaml", "bad.yaml"]
    proc = subprocess.run(cmd, cwd=repo, env=env, capture_output=True, text=True)
    out = proc.stdout + proc.stderr
    assert proc.returncode != 0, out[-3000:]
    assert "Job stats" not in out
    parts = key.split(" ")[0].replace("[", ".").replace("]", "").split(".")
    assert all(p in out for p in parts), out[-3000:]
    assert not Path(repo / "results").exists() and not Path(repo / "results_ci").exists()
