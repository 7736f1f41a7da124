"""Running Snakemake on a copy of the repository, shared by the pipeline tests.

Not a test module: ``pytest`` puts ``tests/`` on ``sys.path`` (``pythonpath`` in
``pyproject.toml``), so test modules in every folder import it as ``workflow_run``.
"""

from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

CI_CONFIG = "workflow/config/ci.yaml"
#: Where the CI config writes (its ``results`` key), apart from the default ``results/``.
CI_RESULTS = "results_ci"
IGNORE = shutil.ignore_patterns(
    ".git",
    ".snakemake",
    "results",
    "results_*",
    "__pycache__",
    ".pytest_cache",
    ".hypothesis",
    "*.egg-info",
    ".benchmarks",
    "report.html",
    ".ruff_cache",
)


def snakemake(repo: Path, *args: str, check: bool = True) -> subprocess.CompletedProcess:
    """Run snakemake in ``repo`` (the copy's package first on the path); output in stdout."""
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(repo), *filter(None, [os.environ.get("PYTHONPATH")])]),
    }
    cmd = [
        sys.executable,
        "-m",
        "snakemake",
        "--directory",
        str(repo),
        "--snakefile",
        str(repo / "Snakefile"),
        *args,
    ]
    proc = subprocess.run(cmd, cwd=repo, env=env, capture_output=True, text=True)
    proc.stdout = proc.stdout + proc.stderr
    if check and proc.returncode != 0:
        raise AssertionError(f"{' '.join(cmd)} failed ({proc.returncode}):\n{proc.stdout}")
    return proc
