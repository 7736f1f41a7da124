"""results/synthoct/ through Snakemake on the reduced CI configuration, and its config checks.

The targets run once (module fixture) in a temporary copy of the repository with the copy's
``speckle`` first on ``PYTHONPATH``. The self-consistency table must carry the published
scores and the same scores recomputed from the published scans (the acceptance of issue 33);
bad ``synthoct`` sections are refused by ``check_config`` (directly, fast) and stop
``snakemake -n`` before any job.
"""

from __future__ import annotations

import copy
import csv
import shutil
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import yaml
from workflow_run import CI_CONFIG, CI_RESULTS, IGNORE, snakemake

import speckle
from speckle.io import open_dataset
from speckle.pipeline.synthoct_checks import check_synthoct

TOLERANCE = {"SSIM": 0.01, "MS-SSIM": 0.01, "VIF": 0.01, "PSNR": 0.1}


def _config(repo_root: Path) -> dict:
    cfg = yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())
    ci = yaml.safe_load((repo_root / CI_CONFIG).read_text())
    out = copy.deepcopy(cfg["synthoct"])
    out["batch"].update(ci["synthoct"]["batch"])
    return out


def test_ci_section_is_small_and_valid(repo_root):
    schema = yaml.safe_load((repo_root / "workflow/schemas/config.schema.yaml").read_text())
    cfg = _config(repo_root)
    jsonschema.validate(cfg, schema["properties"]["synthoct"] | {"$defs": schema["$defs"]})
    b = cfg["batch"]
    assert b["boundary"]["num"] * b["energy"]["num"] <= 4 and b["n_pixels"] * b["n_lines"] < 2**15
    full = yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())["synthoct"]
    fb = full["batch"]
    assert fb["boundary"]["num"] * fb["energy"]["num"] >= 100
    assert (fb["n_pixels"], fb["n_lines"], fb["n_scatterers"]) == (256, 512, 300_000)


@pytest.mark.parametrize(
    ("changes", "key"),
    [
        ({"n_pixels": 300}, r"synthoct\.batch\.n_pixels"),
        ({"n_lines": 20}, r"synthoct\.batch\.n_lines"),
        ({"boundary": {"start": 0.0, "stop": 500.0, "num": 3}}, r"batch\.boundary\.start"),
        ({"boundary": {"start": 100.0, "stop": 2000.0, "num": 3}}, r"boundary\.stop"),
    ],
)  # fmt: skip
def test_bad_sections_name_the_key(repo_root, changes, key):
    cfg = _config(repo_root)
    cfg["batch"].update(changes)
    with pytest.raises(ValueError, match=key):
        check_synthoct(cfg)


@pytest.fixture(scope="module")
def repo(tmp_path_factory, repo_root) -> Path:
    repo = tmp_path_factory.mktemp("synthoct") / "repo"
    shutil.copytree(repo_root, repo, ignore=IGNORE)
    return repo


@pytest.mark.pipeline
@pytest.mark.slow
def test_bad_section_stops_before_any_job(repo):
    bad = repo / "bad.yaml"
    boundary = {"start": 100.0, "stop": 2000.0, "num": 2}
    bad.write_text(yaml.safe_dump({"synthoct": {"batch": {"boundary": boundary}}}))
    proc = snakemake(repo, "-n", "--configfile", CI_CONFIG, str(bad), check=False)
    assert proc.returncode != 0 and "synthoct.batch.boundary.stop" in proc.stdout


@pytest.fixture(scope="module")
def results(repo) -> Path:
    cfg = yaml.safe_load((repo / CI_CONFIG).read_text())
    out = f"{CI_RESULTS}/synthoct"
    targets = [f"{out}/self_consistency.nc", f"{out}/self_consistency.csv",
               f"{out}/self_consistency.png"]  # fmt: skip
    full = yaml.safe_load((repo / "workflow/config/config.yaml").read_text())
    if full["synthoct"]["scanner"] or cfg.get("synthoct", {}).get("scanner"):
        targets += [f"{out}/batch.nc", f"{out}/batch.png"]
    proc = snakemake(repo, "--cores", "2", "--configfile", CI_CONFIG, "--", *targets, check=False)
    assert proc.returncode == 0, proc.stdout[-5000:]
    return repo / CI_RESULTS / "synthoct"


@pytest.mark.pipeline
@pytest.mark.slow
def test_self_consistency_table_beside_the_published(results):
    with open(results / "self_consistency.csv", newline="") as f:
        rows = list(csv.DictReader(f))
    assert len(rows) == 3 * 4 * len(speckle.METRIC_NAMES)
    assert {"published", "recomputed"} <= set(rows[0])
    for r in rows:
        if r["metric"] in TOLERANCE:
            assert abs(float(r["recomputed"]) - float(r["published"])) <= TOLERANCE[r["metric"]]
        elif r["metric"] == "MSE":
            assert float(r["recomputed"]) == pytest.approx(float(r["published"]), rel=0.02)
    ds = open_dataset(results / "self_consistency.nc")
    assert ds["OAC"].attrs["units"] == "1/um" and ds["PSNR"].attrs["units"] == "dB"
    assert ds["scan"].dtype == np.uint8 and ds.sizes["phantom"] == 4
    assert (results / "self_consistency.png").stat().st_size > 0


@pytest.mark.pipeline
@pytest.mark.slow
def test_batch_scores_every_candidate(results):
    if not (results / "batch.nc").exists():
        pytest.skip("synthoct.scanner is false: no drop-in scanner, no batch")
    ds = open_dataset(results / "batch.nc")
    assert ds.attrs["n_phantoms"] == ds.sizes["boundary"] * ds.sizes["energy"]
    assert list(ds["map"].values) == ["Struct", "OAC", "SC", "RSC"]
    assert np.all(np.isfinite(ds["SSIM"].values)) and np.all(np.isfinite(ds["MS-SSIM"].values))
    assert "[" in (results.parent / "logs" / "synthoct_batch.log").read_text()  # progress bar
