"""The twin config section: what the schema and check_twin refuse, directly (fast).

The same cases through ``snakemake -n`` are in ``test_twin_pipeline.py``.
"""

from __future__ import annotations

import copy

import jsonschema
import pytest
import yaml

from speckle.pipeline.checks import check_twin


@pytest.fixture(scope="module")
def twin(repo_root):
    cfg = yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())["twin"]
    cfg["image"] = str(repo_root / cfg["image"])
    return cfg


def over(cfg: dict, **changes) -> dict:
    out = copy.deepcopy(cfg)
    out.update(changes)
    return out


def test_default_twin_section_passes(twin):
    check_twin(twin)


@pytest.mark.parametrize(
    ("changes", "key"),
    [
        ({"region": {"depth": [95, 600], "x": [0, 512]}}, r"twin\.region\.depth"),
        ({"region": {"depth": [95, 135], "x": [10, 5]}}, r"twin\.region\.x"),
        ({"region": {"depth": [95, 100], "x": [0, 512]}}, r"too small for twin\.max_lag"),
        ({"noise_rows": [510, 600]}, r"twin\.noise_rows"),
        ({"n_bands": 30}, r"twin\.n_bands"),
        ({"image": "no/such/file.npy"}, r"twin\.image"),
        ({"dims": ["depth", "x", "frame"]}, r"twin\.dims"),
        ({"failure": {"strains": [0.01], "methods": ["vector"], "shape": [64, 16],
                      "window": [128, 4]}}, r"twin\.failure\.window"),
    ],
)  # fmt: skip
def test_bad_twin_sections_name_the_key(twin, changes, key):
    with pytest.raises(ValueError, match=key):
        check_twin(over(twin, **changes))


def test_schema_refuses_unknown_kind_and_methods(repo_root):
    schema = yaml.safe_load((repo_root / "workflow/schemas/config.schema.yaml").read_text())
    sub = schema["properties"]["twin"]
    cfg = yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())["twin"]
    jsonschema.validate(cfg, sub)
    for bad in ({"kind": "decibel"}, {"failure": {**cfg["failure"], "methods": ["fastest"]}}):
        with pytest.raises(jsonschema.ValidationError):
            jsonschema.validate({**cfg, **bad}, sub)
