"""The despeckle config section: what the schema cannot say is refused, naming the key."""

from __future__ import annotations

import copy

import pytest
import yaml

from speckle.pipeline.checks import check_despeckle


@pytest.fixture(scope="module")
def section(repo_root):
    return yaml.safe_load((repo_root / "workflow/config/config.yaml").read_text())["despeckle"]


def test_default_section_passes(section):
    check_despeckle(section)


@pytest.mark.parametrize(
    "path,value,message",
    [
        (("physical", "frequency", "looks"), [129], "n_looks"),
        (("physical", "frequency", "overlap"), [1.2], "overlap"),
        (("physical", "angular", "sets"), [4], "sets"),
        (("physical", "temporal", "sets"), [16], "sets"),
        (("filters", "median", "size"), [4], "size"),
        (("filters", "nlm", "h"), [-1.0], "h"),
        (("filters", "frost", "damping"), [0.0], "damping"),
        (("failure", "methods", "temporal", "diffusion"), -0.5, "diffusion"),
        (("failure", "methods", "median", "params"), {"size": 2}, "size"),
        (("phantom", "layer_row"), 200, "layer_row"),
        (("frequency_compounding", "looks"), [1, 3], "multiple"),
        (("frequency_compounding", "looks"), [512], "n_looks"),
    ],
)
def test_bad_values_are_named(section, path, value, message):
    cfg = copy.deepcopy(section)
    node = cfg
    for key in path[:-1]:
        node = node[key]
    node[path[-1]] = value
    with pytest.raises(ValueError, match=message) as err:
        check_despeckle(cfg)
    assert "despeckle." in str(err.value)
