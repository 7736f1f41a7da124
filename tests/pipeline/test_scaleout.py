"""The documented ways of running the pipeline, run as users run them: through Snakemake.

* Every ``dask`` scheduler of the config schema (synchronous, threads, processes, a local
  ``dask.distributed`` cluster, and a ``dask scheduler`` / ``dask worker`` pair started here and
  passed as ``address``) builds the reduced pipeline's sweep targets (Figs. 2, 3, 5) with
  identical data: every variable, coordinate and attribute of the NetCDF files.
* A rule that fails leaves its traceback in its own log file.
* A Snakemake executor plugin (``cluster-generic``, each job submitted as its own process with
  the job script Snakemake writes) builds the sweep targets with the same data.
* The shipped default profile restarts an interrupted run as the README says.

Wall times of each run are printed (``pytest -s``); they include Snakemake's start-up.
"""

from __future__ import annotations

import json
import os
import re
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest
import xarray as xr
import yaml
from workflow_run import CI_CONFIG, IGNORE, snakemake

from speckle.io import open_dataset

pytestmark = [pytest.mark.pipeline, pytest.mark.slow]

#: Pipeline outputs computed with ``speckle.sweep`` (the Dask scheduler matters for them).
SWEEP_TARGETS = ("fig2/fig2.nc", "fig3/fig3.nc", "fig5/fig5.nc")
LOCAL = {
    "synchronous": {"scheduler": "synchronous", "address": None, "n_workers": 1},
    "processes": {"scheduler": "processes", "address": None, "n_workers": 2},
    "local_cluster": {"scheduler": "distributed", "address": None, "n_workers": 2},
}


def copy_repo(tmp: Path, repo_root: Path) -> Path:
    import shutil

    repo = tmp / "repo"
    shutil.copytree(repo_root, repo, ignore=IGNORE)
    return repo


def configure(repo: Path, name: str, dask: dict) -> tuple[str, list[str]]:
    """A config file sending results to ``results_<name>`` with ``dask``; (file, targets)."""
    results = f"results_{name}"
    (repo / f"{name}.yaml").write_text(yaml.safe_dump({"results": results, "dask": dask}))
    return f"{name}.yaml", [f"{results}/{t}" for t in SWEEP_TARGETS]


def build(repo: Path, name: str, dask: dict, *args: str) -> tuple[Path, str]:
    """Build the sweep targets into ``results_<name>``; (results dir, Snakemake's output).

    ``args`` replace the default ``--cores 2`` (e.g. executor options).
    """
    config, targets = configure(repo, name, dask)
    start = time.perf_counter()
    proc = snakemake(repo, *targets, *(args or ("--cores", "2")), "--configfile", CI_CONFIG, config)
    print(f"{name}: sweep targets built in {time.perf_counter() - start:.1f} s")
    return repo / f"results_{name}", proc.stdout


def assert_same_data(results: Path, reference: Path) -> None:
    for target in SWEEP_TARGETS:
        xr.testing.assert_identical(
            open_dataset(results / target), open_dataset(reference / target)
        )


@pytest.fixture(scope="module")
def repo(tmp_path_factory, repo_root) -> Path:
    return copy_repo(tmp_path_factory.mktemp("scaleout"), repo_root)


@pytest.fixture(scope="module")
def reference(repo) -> Path:
    """The sweep targets built with the CI config's scheduler (threads)."""
    ci = yaml.safe_load((repo / CI_CONFIG).read_text())
    assert ci["dask"]["scheduler"] == "threads"
    return build(repo, "threads", ci["dask"])[0]


@pytest.fixture(scope="module")
def dask_cluster(repo, tmp_path_factory):
    """A ``dask scheduler`` and a ``dask worker`` (2 processes) on localhost; yields the address.

    Started with the CLI as a user would, with the repository copy on ``PYTHONPATH`` so that the
    workers import the same ``speckle``.
    """
    from dask.distributed import Client

    tmp = tmp_path_factory.mktemp("dask")
    file = tmp / "scheduler.json"
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(repo), os.environ.get("PYTHONPATH", "")]),
    }
    dask_cli = [sys.executable, "-m", "dask"]  # the `dask` command of this environment
    common = {"cwd": tmp, "env": env, "stdout": subprocess.DEVNULL, "stderr": subprocess.STDOUT}
    procs = [
        subprocess.Popen(
            [
                *dask_cli,
                "scheduler",
                "--host",
                "127.0.0.1",
                "--port",
                "0",
                "--no-dashboard",
                "--scheduler-file",
                str(file),
            ],
            **common,
        )
    ]
    try:
        for _ in range(300):
            if file.exists() and file.stat().st_size:
                break
            time.sleep(0.1)
        procs.append(
            subprocess.Popen(
                [
                    *dask_cli,
                    "worker",
                    "--scheduler-file",
                    str(file),
                    "--nworkers",
                    "2",
                    "--nthreads",
                    "1",
                    "--no-dashboard",
                ],
                **common,
            )
        )
        address = json.loads(file.read_text())["address"]
        with Client(address, timeout=60) as client:
            client.wait_for_workers(2, timeout=120)
        yield address
    finally:
        for proc in reversed(procs):
            proc.send_signal(signal.SIGINT)
        for proc in reversed(procs):
            try:
                proc.wait(timeout=30)
            except subprocess.TimeoutExpired:
                proc.kill()
                proc.wait()


@pytest.mark.parametrize("name", sorted(LOCAL))
def test_local_scheduler_gives_identical_data(repo, reference, name):
    results, _ = build(repo, name, LOCAL[name])
    assert_same_data(results, reference)
    log = (results / "logs" / "fig3.log").read_text()
    assert "wrote" in log and "failed" not in log, log


def test_dask_cluster_address_gives_identical_data(repo, reference, dask_cluster):
    dask = {"scheduler": "distributed", "address": dask_cluster, "n_workers": 2}
    results, _ = build(repo, "address", dask)
    assert_same_data(results, reference)
    assert "6/6 points done" in (results / "logs" / "fig3.log").read_text()


def test_failing_rule_leaves_its_traceback_in_its_log(repo, monkeypatch):
    """A script error (here: no Dask scheduler at ``address``) is in the rule's log file."""
    monkeypatch.setenv("DASK_DISTRIBUTED__COMM__TIMEOUTS__CONNECT", "2s")
    dask = {"scheduler": "distributed", "address": "tcp://127.0.0.1:9", "n_workers": 2}
    config, targets = configure(repo, "unreachable", dask)
    proc = snakemake(
        repo, targets[1], "--cores", "1", "--configfile", CI_CONFIG, config, check=False
    )
    assert proc.returncode != 0
    log = (repo / "results_unreachable" / "logs" / "fig3.log").read_text()
    assert "rule fig3 failed" in log, log
    assert "Traceback (most recent call last)" in log, log
    assert "OSError" in log and "tcp://127.0.0.1:9" in log, log


def test_executor_plugin_gives_identical_data(repo, reference):
    """``cluster-generic``: each job is submitted as its own process (``.ci/submit-local``)."""
    dask = yaml.safe_load((repo / CI_CONFIG).read_text())["dask"]
    submit = str(repo / ".ci" / "submit-local")
    results, out = build(
        repo,
        "executor",
        dask,
        "--executor",
        "cluster-generic",
        "--cluster-generic-submit-cmd",
        submit,
        "--jobs",
        "2",
    )
    assert len(re.findall(r"Submitted job \d+ with external jobid '\d+'", out)) == len(
        SWEEP_TARGETS
    ), out
    assert_same_data(results, reference)


def test_interrupted_run_resumes_after_unlock(tmp_path, repo_root, reference):
    """README "After an interrupted run": SIGKILL mid-job, ``--unlock``, rerun, same data."""
    repo = copy_repo(tmp_path, repo_root)
    dask = yaml.safe_load((repo / CI_CONFIG).read_text())["dask"]
    config, targets = configure(repo, "threads", dask)
    env = {
        **os.environ,
        "PYTHONPATH": os.pathsep.join([str(repo), os.environ.get("PYTHONPATH", "")]),
    }
    cmd = [
        sys.executable,
        "-m",
        "snakemake",
        *targets,
        "--cores",
        "1",
        "--configfile",
        CI_CONFIG,
        config,
    ]
    proc = subprocess.Popen(
        cmd,
        cwd=repo,
        env=env,
        start_new_session=True,
        stdout=subprocess.DEVNULL,
        stderr=subprocess.STDOUT,
    )
    log = repo / "results_threads" / "logs"
    try:
        for _ in range(1200):
            if log.is_dir() and any(log.iterdir()):
                break
            time.sleep(0.1)
        time.sleep(1.0)
    finally:
        os.killpg(proc.pid, signal.SIGKILL)  # Snakemake and its job, as a crash would
        proc.wait()
    locked = snakemake(
        repo, *targets, "--cores", "2", "--configfile", CI_CONFIG, config, check=False
    )
    assert locked.returncode != 0 and "--unlock" in locked.stdout, locked.stdout
    snakemake(repo, "--unlock", "--configfile", CI_CONFIG, config)
    snakemake(repo, *targets, "--cores", "2", "--configfile", CI_CONFIG, config)
    assert_same_data(repo / "results_threads", reference)
