"""Provenance and code tracking."""

from __future__ import annotations

from pathlib import Path

import pytest

from speckle.provenance import config_hash, module_sources, provenance_attrs


def test_config_hash_ignores_key_order():
    assert config_hash({"a": 1, "b": [1, 2]}) == config_hash({"b": [1, 2], "a": 1})
    assert config_hash({"a": 1}) != config_hash({"a": 2})
    attrs = provenance_attrs({"a": 1}, seed=4)
    assert attrs["seed"] == 4 and len(attrs["config_sha256"]) == 64


def test_module_sources_follow_package_imports_only():
    names = {Path(p).name for p in module_sources("speckle.imaging.bscan")}
    assert {"bscan.py", "aline.py", "scatterers.py", "source.py", "_validate.py"} <= names
    assert "sweep.py" not in names  # __init__ re-exports are not followed
    names = {Path(p).name for p in module_sources("speckle.sweep")}
    assert "aline.py" not in names


def test_unknown_module_raises():
    with pytest.raises(ValueError, match="not found"):
        module_sources("speckle.nonexistent")
