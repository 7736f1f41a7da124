"""Helpers shared by the benchmark scripts: timing, relative error, machine description."""

from __future__ import annotations

import os
import platform
import subprocess
import time

import numpy as np


def best_time(func, repeat: int, *, warmup: bool = False):
    """``(best wall time, CPU time of that run, its result)`` over ``repeat`` calls of ``func``.

    ``warmup`` makes one untimed call first (JIT compilation, caches).
    """
    if warmup:
        func()
    best, cpu, out = np.inf, np.inf, None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = func()
        t, c = time.perf_counter() - t0, time.process_time() - c0
        if t < best:
            best, cpu = t, c
    return best, cpu, out


def rel_err(a, ref) -> float:
    """``||a - ref||_2 / ||ref||_2``."""
    return float(np.linalg.norm(a - ref) / np.linalg.norm(ref))


def cpu_model() -> str:
    """CPU model name (from ``lscpu``) and the number of cores this process may use."""
    cores = f"{len(os.sched_getaffinity(0))} cores"
    try:
        out = subprocess.run(["lscpu"], capture_output=True, text=True).stdout
        for line in out.splitlines():
            if line.startswith("Model name"):
                return f"{line.split(':', 1)[1].strip()}, {cores}"
    except OSError:
        pass
    return f"{platform.processor() or platform.machine()}, {cores}"
