"""results/phantom/real/ through Snakemake on the reduced CI configuration, and its config checks.

The target runs once (module fixture) in a temporary copy of the repository; bad
``phantom_real`` sections are refused by ``check_config`` (directly, fast) and stop
``snakemake -n`` before any job.
"""

from __future__ import annotations

import copy
import shutil
from pathlib import Path

import jsonschema
import numpy as np
import pytest
import yaml
from workflow_run import CI_CONFIG, CI_RESULTS, IGNORE, snakemake

from speckle.io import open_dataset
from speckle.pipeline.phantom_real_checks import check_phantom_real


def _config(repo_root: Path) -> dict:
    cfg = yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())
    ci = yaml.safe_load((repo_root / CI_CONFIG).read_text())
    out = copy.deepcopy(cfg["phantom_real"])
    for key, value in ci["phantom_real"].items():
        if key == "images":
            for name, own in value.items():
                out["images"][name].update(own)
        else:
            out[key] = value
    return out


def test_sections_are_valid_and_ci_is_small(repo_root):
    schema = yaml.safe_load((repo_root / "workflow/schemas/config.schema.yaml").read_text())
    full = yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())["phantom_real"]
    for cfg in (full, _config(repo_root)):
        jsonschema.validate(cfg, schema["properties"]["phantom_real"] | {"$defs": schema["$defs"]})
        check_phantom_real(cfg)
    ci = _config(repo_root)
    assert ci["fit"] == ["pdms"] and len(ci["seeds"]) == 2
    rows, lines = ci["images"]["pdms"]["rows"], ci["images"]["pdms"]["lines"]
    assert (rows[1] - rows[0]) * (lines[1] - lines[0]) <= 10_000
    assert set(full["fit"]) == {"pdms", "thumb"}


@pytest.mark.parametrize(
    ("image", "top", "key"),
    [
        ({"rows": [90, 100]}, {}, r"phantom_real\.images\.pdms\.rows"),
        ({"rows": [400, 600]}, {}, r"phantom_real\.images\.pdms\.rows"),
        ({"noise_rows": [100, 120]}, {}, r"phantom_real\.images\.pdms\.noise_rows"),
        ({"noise_rows": [5, 7]}, {}, r"phantom_real\.images\.pdms\.noise_rows"),
        ({"lines": [0, 100]}, {}, r"phantom_real\.images\.pdms\.lines"),
        ({"lines": [0, 100], "beam_radius": 5.0}, {}, None),
        ({"lines": [0, 40], "beam_radius": 5.0}, {}, r"phantom_real\.images\.pdms\.lines"),
        ({"beam_radius": float("nan")}, {}, r"phantom_real\.images\.pdms\.beam_radius"),
        ({"image": "no/such.npy"}, {}, r"phantom_real\.images\.pdms\.image"),
        ({"rows": [90.0, 150]}, {}, r"phantom_real\.images\.pdms\.rows"),
        ({}, {"fit": ["pdms", "liver"]}, r"phantom_real\.fit"),
    ],
)
def test_bad_sections_name_the_key(repo_root, image, top, key):
    cfg = _config(repo_root)
    cfg["images"]["pdms"].update(image)
    cfg.update(top)
    if key is None:
        check_phantom_real(cfg)
        return
    with pytest.raises(ValueError, match=key):
        check_phantom_real(cfg)


@pytest.fixture(scope="module")
def repo(tmp_path_factory, repo_root) -> Path:
    repo = tmp_path_factory.mktemp("phantom_real") / "repo"
    shutil.copytree(repo_root, repo, ignore=IGNORE)
    return repo


@pytest.mark.pipeline
@pytest.mark.slow
def test_bad_section_stops_before_any_job(repo):
    bad = repo / "bad.yaml"
    bad.write_text(yaml.safe_dump({"phantom_real": {"images": {"pdms": {"rows": [90, 100]}}}}))
    proc = snakemake(repo, "-n", "--configfile", CI_CONFIG, str(bad), check=False)
    assert proc.returncode != 0 and "phantom_real.images.pdms.rows" in proc.stdout


@pytest.mark.pipeline
@pytest.mark.slow
def test_real_tissue_target(repo):
    out = f"{CI_RESULTS}/phantom/real"
    targets = [f"{out}/pdms.nc", f"{out}/pdms.png"]
    proc = snakemake(repo, "--cores", "1", "--configfile", CI_CONFIG, "--", *targets, check=False)
    assert proc.returncode == 0, proc.stdout[-5000:]
    ds = open_dataset(repo / out / "pdms.nc")
    assert ds.measured.dtype == np.uint8 and ds.fitted.shape == (2, 60, 160)
    assert ds.sizes["pair"] == 1 and list(ds["map"].values) == ["Struct", "OAC", "SC", "RSC"]
    assert np.all(np.isfinite(ds["SSIM_gap"].values))
    assert ds.profile_residual.attrs["units"] == "dB" and ds.attrs["rows"].tolist() == [90, 150]
    assert (repo / out / "pdms.png").stat().st_size > 0
