"""Helpers shared by the benchmark scripts: timing, relative error, machine description."""

from __future__ import annotations

import os
import platform
import subprocess
import time

import numpy as np

PIXEL = 8.0  # µm: the strain benchmarks' pixel size


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


def strain_pair(
    strain: float, n: int = 1024, lines: int = 256
) -> tuple[np.ndarray, np.ndarray, float]:
    """The strain benchmarks' image pair: reference and uniformly compressed complex B-scans
    ``(depth, x)`` of a Gaussian-spectrum scene (FWHM 0.5 delta_k, k0/delta_k 10, 4
    scatterers per pixel, :data:`PIXEL` µm pixels, seed 1) and ``k0`` (rad/µm)."""
    import speckle

    h = n * PIXEL
    src = speckle.spectrum(n, h, k0_dk=10.0, shape="gaussian", fwhm=0.5 * n * np.pi / h)
    scene = speckle.deformable_scene(lines, 4.0, n_pixels=n, depth_range=h, seed=1, strain=strain)
    img = (
        speckle.bscan(speckle.uniaxial_strain(scene, [0.0, strain]), src, method="nufft", tol=1e-9)
        .field.transpose("strain", "depth", "x")
        .values
    )
    return img[0], img[1], float(src.attrs["k0"])
