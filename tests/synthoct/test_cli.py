"""The ``speckle-scan`` command (issue 33): official argument order, refusals, light imports.

The console script cannot be installed here (the editable install belongs to the main
checkout), so the entry point is checked in pyproject.toml and the command is run as
``python -m speckle.synthoct`` in a subprocess.
"""

from __future__ import annotations

import importlib
import os
import subprocess
import sys
from importlib.resources import files
from pathlib import Path

import numpy as np
import pytest

import speckle
from speckle.synthoct.files import ScannerConfig, baseline_table, read_png
from speckle.synthoct.scanner import scan_agreement

REPO = Path(__file__).resolve().parents[2]
DATA = files("speckle.data") / "synthoct"
#: Modules the command must not import (each costs a fresh process seconds, or compiles).
HEAVY = ("xarray", "scipy", "numba", "dask", "pandas", "matplotlib", "skimage", "netCDF4")


def _run(*args, cwd=None, importtime=False):
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    flags = ["-X", "importtime"] if importtime else []
    return subprocess.run(
        [sys.executable, *flags, "-m", "speckle.synthoct", *map(str, args)],
        capture_output=True, text=True, env=env, cwd=cwd, check=False,
    )  # fmt: skip


def test_entry_point_is_declared():
    tomllib = pytest.importorskip("tomllib")  # Python >= 3.11
    project = tomllib.loads((REPO / "pyproject.toml").read_text())
    target = project["project"]["scripts"]["speckle-scan"]
    module, name = target.split(":")
    assert callable(getattr(importlib.import_module(module), name))
    assert module == "speckle.synthoct.cli"


@pytest.fixture(scope="module")
def challenge(tmp_path_factory):
    """The published two-layer phantom A and the challenge's INI, as files."""
    d = tmp_path_factory.mktemp("challenge")
    speckle.write_scanner_config(ScannerConfig(), d / "Configuration.ini")
    speckle.write_phantom(baseline_table("layers", 42), d / "Scatterers_Exp2_Layers_A.txt")
    return d


def test_command_reproduces_the_published_scan(challenge):
    out = challenge / "Scan.png"
    r = _run(challenge / "Configuration.ini", challenge / "Scatterers_Exp2_Layers_A.txt", out,
             importtime=True)  # fmt: skip
    assert r.returncode == 0, r.stderr
    got = scan_agreement(read_png(out), read_png(DATA / "Scan_Exp2_Layers_A.png"))
    assert got["correlation"] >= 0.95 and got["row_mean_error"] <= 0.5
    # same bytes of levels as the function (one implementation)
    fn = speckle.synthoct_scan(challenge / "Scatterers_Exp2_Layers_A.txt", ScannerConfig())
    np.testing.assert_array_equal(read_png(out), fn.values)
    imported = {line.split("|")[-1].strip() for line in r.stderr.splitlines() if "|" in line}
    heavy = sorted(m for m in imported if m.split(".")[0] in HEAVY)
    assert not heavy, f"the command imported {heavy[:5]}"


def _bad(tmp_path, ini=None, phantom="0 0 10 1\n1 0 20 1\n"):
    cfg = ScannerConfig(n_scatterers=2, n_pixels=16, n_lines=8, x_max=48.0)
    speckle.write_scanner_config(cfg, tmp_path / "c.ini")
    if ini is not None:
        (tmp_path / "c.ini").write_text(ini((tmp_path / "c.ini").read_text()))
    (tmp_path / "p.txt").write_text(phantom)
    return _run(tmp_path / "c.ini", tmp_path / "p.txt", tmp_path / "o.png")


@pytest.mark.parametrize(
    ("ini", "phantom", "message"),
    [
        (None, "0 0 10 1\n1 0 20\n", "p.txt, line 2: 3 columns, expected 4"),
        (None, "0 0 10 1\n1 0 x 1\n", "p.txt, line 2: 'x' is not a number"),
        (None, "0 0 10 1\n1 0 nan 1\n", "p.txt, line 2: NaN or infinite"),
        (None, "0 0 10 1\n1 0 20 101\n", "p.txt, line 2: energy 101 % outside 0..100"),
        (None, "0 0 10 1\n", "1 scatterers, but the configuration's 'number of scatterers"),
        (lambda s: s.replace("ymax mcm", "zmax mcm"), None, "unknown key 'zmax mcm'"),
        (lambda s: s.replace("xmax mcm = 48.0\n", ""), None, "missing key 'xmax mcm'"),
    ],
)
def test_command_refusals(tmp_path, ini, phantom, message):
    r = _bad(tmp_path, ini, *(() if phantom is None else (phantom,)))
    assert r.returncode == 2
    assert message in r.stderr and r.stderr.startswith("speckle-scan: error:")
    assert not (tmp_path / "o.png").exists()


def test_command_missing_file_and_usage(tmp_path):
    r = _run(tmp_path / "none.ini", tmp_path / "p.txt", tmp_path / "o.png")
    assert r.returncode == 2 and "none.ini" in r.stderr
    r = _run(tmp_path / "only-one-argument.ini")
    assert r.returncode == 2 and "usage: speckle-scan" in r.stderr


def test_batch_mode(tmp_path):
    """Several SCATTERERS OUTPUT pairs in one process: each scan equals its single call."""
    cfg = ScannerConfig(n_scatterers=300, n_pixels=32, n_lines=16, x_max=96.0)
    speckle.write_scanner_config(cfg, tmp_path / "c.ini")
    rng = np.random.default_rng(4)
    for k in range(2):
        t = np.column_stack([rng.uniform(-48, 48, 300), rng.uniform(-10, 10, 300),
                             rng.uniform(0, 192, 300), np.full(300, 1.0 + k)])  # fmt: skip
        speckle.write_phantom(t, tmp_path / f"p{k}.txt")
    r = _run(tmp_path / "c.ini", tmp_path / "p0.txt", tmp_path / "o0.png",
             tmp_path / "p1.txt", tmp_path / "o1.png")  # fmt: skip
    assert r.returncode == 0, r.stderr
    for k in range(2):
        single = speckle.synthoct_scan(tmp_path / f"p{k}.txt", cfg)
        np.testing.assert_array_equal(read_png(tmp_path / f"o{k}.png"), single.values)
    r = _run(tmp_path / "c.ini", tmp_path / "p0.txt", tmp_path / "o0.png", tmp_path / "p1.txt")
    assert r.returncode == 2 and "has no output" in r.stderr
