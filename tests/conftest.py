"""Shared fixtures and hypothesis profile."""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib
import numpy  # noqa: F401  (numpy's and scipy's OpenBLAS loaded, then limited below)
import pytest
import scipy.linalg  # noqa: F401
from hypothesis import settings
from threadpoolctl import threadpool_limits

matplotlib.use("Agg")
# One BLAS thread per test process: `pytest -n 2` runs two processes on two cores, where
# OpenBLAS's second thread only spins (a 49 x 49 eigh: 0.17 ms of CPU on one thread, 11.5 ms on
# two on the loaded machine). In this process only: Snakemake jobs set their own thread counts.
threadpool_limits(1, user_api="blas")

settings.register_profile("ci", max_examples=30, deadline=None, derandomize=True)
settings.register_profile("dev", max_examples=30, deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def repo_root() -> Path:
    """Repository root (the folder holding the Snakefile)."""
    return REPO


# --- malformed-input property tests (issue 21): one checker shared by the feature groups ---
#: Values a hostile user passes for any parameter: wrong types, strings that look like
#: numbers or booleans, non-finite and out-of-range numbers, wrong shapes.
MALFORMED = (None, "8", "False", True, -1, 0, 0.5, 1.5, float("nan"), float("inf"), -1e300,
             1e300, [], [1.0, 2.0, 3.0], {"a": 1}, 1j)  # fmt: skip


def _finite_result(out) -> bool:
    import numpy as np
    import xarray as xr

    if isinstance(out, tuple):
        return all(_finite_result(o) for o in out)
    if isinstance(out, np.ndarray | float | int | complex):
        return bool(np.all(np.isfinite(out)))
    if isinstance(out, xr.DataArray | xr.Dataset):
        arrays = [out] if isinstance(out, xr.DataArray) else list(out.data_vars.values())
        return all(a.dtype.kind in "fcbiu" and bool(np.all(np.isfinite(a.values))) for a in arrays)
    return out is not None


class Malformed:
    """Drives the malformed-input property tests of a module with ``VALID`` (call name ->
    valid keyword arguments) and ``_call(name, kwargs)``."""

    values = MALFORMED

    @staticmethod
    def check(call, param: str, value) -> None:
        """``call()`` raises TypeError/ValueError naming ``param`` (or its first word) or
        returns a finite answer; any other exception fails the test."""
        try:
            out = call()
        except (TypeError, ValueError) as err:
            msg, first = str(err), param.split("_")[0]
            assert param in msg or (len(first) > 2 and first in msg), (param, value, msg)
        else:
            assert _finite_result(out), (param, value)

    def run(self, valid: dict, call, target: tuple[str, str], data) -> None:
        """One drawn malformed value for parameter ``target = (name, param)``."""
        from hypothesis import strategies as st

        name, param = target
        value = data.draw(st.sampled_from(self.values), label=param)
        kw = {**valid[name], param: value}
        self.check(lambda: call(name, kw), param, value)


def pytest_generate_tests(metafunc):
    """``malformed_target``: every (call, parameter) of the test module's ``VALID``."""
    if "malformed_target" in metafunc.fixturenames:
        targets = [(n, p) for n, kw in metafunc.module.VALID.items() for p in kw]
        metafunc.parametrize("malformed_target", targets, ids=[f"{n}-{p}" for n, p in targets])


@pytest.fixture(scope="session")
def malformed() -> Malformed:
    """The malformed-input driver (:class:`Malformed`)."""
    return Malformed()


# --- bad configurations through `snakemake -n` (issues 13 and 21) ---------------------------
class ConfigRuns:
    """Merge config overrides and dry-run the workflow on a copy of the repository."""

    ignore = staticmethod(__import__("workflow_run").IGNORE)  # tests/ is on sys.path

    @classmethod
    def merge(cls, base: dict, over: dict) -> dict:
        """``over`` merged into a copy of ``base`` as Snakemake layers config files."""
        import copy

        out = copy.deepcopy(base)
        for key, value in over.items():
            if isinstance(value, dict) and isinstance(out.get(key), dict):
                out[key] = cls.merge(out[key], value)
            else:
                out[key] = value
        return out

    def copy_repo(self, dest: Path) -> Path:
        """A copy of the repository (dry runs write .snakemake metadata)."""
        import shutil

        shutil.copytree(REPO, dest, ignore=self.ignore)
        return dest

    @staticmethod
    def dry_run(repo: Path, *configfiles: str):
        """``snakemake -n`` with the CI config and ``configfiles`` layered over it."""
        import subprocess
        import sys

        paths = [str(repo), *filter(None, [os.environ.get("PYTHONPATH")])]
        env = {**os.environ, "PYTHONPATH": os.pathsep.join(paths)}
        cmd = [sys.executable, "-m", "snakemake", "-n", "--directory", str(repo)]
        cmd += ["--snakefile", str(repo / "Snakefile"), "--configfile", "workflow/config/ci.yaml"]
        proc = subprocess.run([*cmd, *configfiles], cwd=repo, env=env, capture_output=True,
                              text=True)  # fmt: skip
        proc.stdout += proc.stderr
        return proc

    @staticmethod
    def assert_refused(proc, key: str) -> None:
        """The run stopped before planning any job, naming ``key`` (a schema error names the
        path in parts, a load check in full)."""
        assert proc.returncode != 0, proc.stdout[-3000:]
        assert "Job stats" not in proc.stdout, "jobs were planned"
        key = key.split(" ")[0]
        if "ValidationError" in proc.stdout:
            parts = key.replace("[", ".").replace("]", "").split(".")
            assert all(p in proc.stdout for p in parts), proc.stdout[-3000:]
        else:
            assert key in proc.stdout, proc.stdout[-3000:]


@pytest.fixture(scope="session")
def config_runs() -> ConfigRuns:
    return ConfigRuns()


@pytest.fixture(scope="session")
def compressed_pair():
    """One scene at 0 and 0.4 % compression, 64 x 16 px over 512 µm (pixel 8 µm), k0/dk 10:
    ``(spectrum, bscan)`` (the README's strain call, small)."""
    import speckle

    src = speckle.spectrum(64, 512.0, k0_dk=10)
    scene = speckle.deformable_scene(16, 4.0, n_pixels=64, depth_range=512.0, seed=1, strain=4e-3)
    img = speckle.bscan(speckle.uniaxial_strain(scene, [0.0, 4e-3]), src, normalise="density")
    return src, img
