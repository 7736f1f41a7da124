"""Wall time of the reduced pipeline under each Dask scheduler and Snakemake executor.

Run from the repository root::

    python benchmarks/bench_scaleout.py                 # whole reduced pipeline, every way
    python benchmarks/bench_scaleout.py --sweeps-only   # only the sweeps of Figs. 2, 3, 5

Each way runs in a fresh copy of the repository (no ``.snakemake``, no results) with
``workflow/config/ci.yaml`` and ``--cores 2`` (executors: ``--jobs 2``): synchronous, threads,
processes, a local ``dask.distributed`` cluster, a ``dask scheduler`` / ``dask worker`` pair
started here (2 worker processes, 1 thread each), and the ``cluster-generic`` executor with
``.ci/submit-local`` (each job its own process). The SLURM executor is timed by
``.ci/slurm.sh`` (it needs root and a SLURM installation). Times include Snakemake's start-up
and every job's Python start-up; only ratios within one run are comparable.
"""

from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parents[1]
CI = "workflow/config/ci.yaml"
SWEEPS = ["results_ci/fig2/fig2.nc", "results_ci/fig3/fig3.nc", "results_ci/fig5/fig5.nc"]
IGNORE = shutil.ignore_patterns(".git", ".snakemake", "results", "results_*", "__pycache__")


def dask_pair(tmp: Path, env: dict) -> tuple[str, list[subprocess.Popen]]:
    """Start ``dask scheduler`` and ``dask worker`` on localhost; (address, processes)."""
    file = tmp / "scheduler.json"
    cli = [sys.executable, "-m", "dask"]
    out = {"env": env, "cwd": tmp, "stdout": subprocess.DEVNULL, "stderr": subprocess.DEVNULL}
    scheduler = ["scheduler", "--host", "127.0.0.1", "--port", "0", "--no-dashboard"]
    procs = [subprocess.Popen([*cli, *scheduler, "--scheduler-file", str(file)], **out)]
    while not (file.exists() and file.stat().st_size):
        time.sleep(0.1)
    worker = ["worker", "--scheduler-file", str(file), "--nworkers", "2", "--nthreads", "1"]
    procs.append(subprocess.Popen([*cli, *worker, "--no-dashboard"], **out))
    address = json.loads(file.read_text())["address"]
    from dask.distributed import Client

    with Client(address, timeout=60) as client:
        client.wait_for_workers(2, timeout=120)
    return address, procs


def run(name: str, dask: dict, extra: list[str], targets: list[str]) -> float:
    """Wall time (s) of the reduced pipeline in a fresh copy of the repository."""
    with tempfile.TemporaryDirectory() as tmp:
        repo = Path(tmp) / "repo"
        shutil.copytree(ROOT, repo, ignore=IGNORE)
        shared = ROOT.parent / "shared"
        if shared.is_dir():
            (Path(tmp) / "shared").symlink_to(shared, target_is_directory=True)
        env = {**os.environ, "PYTHONPATH": str(repo)}
        procs: list[subprocess.Popen] = []
        if dask.get("address") == "start":
            dask["address"], procs = dask_pair(Path(tmp), env)
        (repo / "dask.yaml").write_text(yaml.safe_dump({"dask": dask}))
        cmd = [sys.executable, "-m", "snakemake", *targets, *extra, "--configfile", CI, "dask.yaml"]
        try:
            start = time.perf_counter()
            subprocess.run(cmd, cwd=repo, env=env, check=True, capture_output=True)
            return time.perf_counter() - start
        finally:
            for p in procs:
                p.send_signal(signal.SIGINT)
                p.wait(timeout=30)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--sweeps-only", action="store_true", help="only Figs. 2, 3, 5")
    args = parser.parse_args()
    targets = SWEEPS if args.sweeps_only else []
    local = ["--cores", "2"]
    submit = ["--executor", "cluster-generic", "--jobs", "2"]
    submit += ["--cluster-generic-submit-cmd", ".ci/submit-local"]
    ways = {
        "threads": ({"scheduler": "threads", "address": None, "n_workers": 2}, local),
        "synchronous": ({"scheduler": "synchronous", "address": None, "n_workers": 1}, local),
        "processes": ({"scheduler": "processes", "address": None, "n_workers": 2}, local),
        "local cluster": ({"scheduler": "distributed", "address": None, "n_workers": 2}, local),
        "dask scheduler + worker": (
            {"scheduler": "distributed", "address": "start", "n_workers": 2},
            local,
        ),
        "cluster-generic executor (threads)": (
            {"scheduler": "threads", "address": None, "n_workers": 2},
            submit,
        ),
    }
    what = "sweep targets (Figs. 2, 3, 5)" if args.sweeps_only else "whole reduced pipeline"
    print(f"{what}, {CI}, {os.cpu_count()} CPUs; wall time")
    times = {}
    for name, (dask, extra) in ways.items():
        times[name] = run(name, dict(dask), extra, targets)
        print(
            f"| {name} | {times[name]:.0f} s | {times[name] / times['threads']:.2f} |", flush=True
        )


if __name__ == "__main__":
    main()
