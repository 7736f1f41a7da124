"""Benchmark of the spectrometer chain against the ideal path (speckle.ascan): prints a table.

Run from the repository root::

    python benchmarks/bench_chain.py            # 1024 px x 64 lines x 2 scatterers/px
    python benchmarks/bench_chain.py --quick    # smaller scene, smoke test

Every ratio is against ``speckle.ascan(method="direct")`` timed in the same run (best of
``--repeat``, after one warm-up run). The camera signal is evaluated directly (``O(M K)`` per
line, like the direct method) or, for a uniform pixel response, by FINUFFT type 3; processing
costs are given per B-scan and against a bare FFT of the same lines.
"""

from __future__ import annotations

import argparse

import numpy as np
from _common import best_time

import speckle
from speckle.system import spectrometer as sp


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--quick", action="store_true")
    ap.add_argument("--repeat", type=int, default=3)
    args = ap.parse_args(argv)
    n_pixels, n_lines, density = (256, 16, 2.0) if args.quick else (1024, 64, 2.0)
    system = speckle.example_system("840nm", camera_pixels=n_pixels)
    rng = np.random.default_rng(1)
    m = round(density * n_pixels)
    z = rng.uniform(0, system.imaging_depth, (n_lines, m))
    a = np.exp(2j * np.pi * rng.uniform(size=z.shape))
    src = system.spectrum()
    grid = sp.grid_wavenumbers(system)
    cam = sp.camera_sampling(system, "wavelength")
    s_cam = sp.source_weights(system, cam["wavenumber"])
    rows = []

    def add(label, func, ref_time=None):
        t, _, out = best_time(func, args.repeat, warmup=True)
        rows.append((label, t, None if ref_time is None else t / ref_time))
        return t, out

    kw = dict(n_pixels=n_pixels, depth_range=system.depth_range, k0=system.k0, spectrum=src.values)
    t_direct, ref = add("speckle.ascan direct (ideal Eq. 4)", lambda: speckle.ascan(z, a, **kw))
    rows[-1] = (*rows[-1][:2], 1.0)
    add(
        "speckle.ascan nufft, tol 1e-10",
        lambda: speckle.ascan(z, a, method="nufft", tol=1e-10, **kw),
        t_direct,
    )

    def ideal_chain():
        sig = sp.interferogram(z, a, grid, src.values, k0=system.k0)
        return sp.process_interferogram(sig, grid=grid, k0=system.k0)

    _, out = add("chain, ideal (k-linear, delta pixels, complex)", ideal_chain, t_direct)
    err = np.linalg.norm(out - ref) / np.linalg.norm(ref)

    def ideal_chain_nufft():
        sig = sp.interferogram(z, a, grid, src.values, k0=system.k0, method="finufft", tol=1e-10)
        return sp.process_interferogram(sig, grid=grid, k0=system.k0)

    _, out = add("chain, ideal, camera by FINUFFT type 3 (tol 1e-10)", ideal_chain_nufft,
                 t_direct)  # fmt: skip
    err_nufft = np.linalg.norm(out - ref) / np.linalg.norm(ref)
    klin = sp.camera_sampling(system, "wavenumber")
    add("camera: k-linear, pixel width + line, real, FINUFFT (tol 1e-10)",
        lambda: sp.interferogram(z, a, klin["wavenumber"], src.values, k0=system.k0,
                                 pixel_width=klin["pixel_width"], resolution=klin["resolution"],
                                 detection="real", dc=True, method="finufft", tol=1e-10),
        t_direct)  # fmt: skip
    _, sig = add(
        "camera: wavelength-linear, pixel width + line, real",
        lambda: sp.interferogram(z, a, cam["wavenumber"], s_cam, k0=system.k0,
                                 pixel_width=cam["pixel_width"], resolution=cam["resolution"],
                                 detection="real", dc=True, dispersion={2: 20.0}),
        t_direct,
    )  # fmt: skip
    add("camera: wavelength-linear, pixel width + line, real, FINUFFT + Chebyshev (tol 1e-8)",
        lambda: sp.interferogram(z, a, cam["wavenumber"], s_cam, k0=system.k0,
                                 pixel_width=cam["pixel_width"], resolution=cam["resolution"],
                                 detection="real", dc=True, dispersion={2: 20.0},
                                 method="finufft", tol=1e-8),
        t_direct)  # fmt: skip
    t_fft, _ = add("processing: FFT only", lambda: sp.to_pixels(sig.astype(complex)), t_direct)
    full = dict(grid=grid, k0=system.k0, wavenumber=cam["wavenumber"],
                background=s_cam, dispersion={2: 20.0}, window="hann")  # fmt: skip
    add("processing: linear resampling + compensation + window + FFT",
        lambda: sp.process_interferogram(sig, resample="linear", **full), t_direct)  # fmt: skip
    add("processing: cubic resampling + compensation + window + FFT",
        lambda: sp.process_interferogram(sig, resample="cubic", **full), t_direct)  # fmt: skip
    few = z[:, :64], a[:, :64]
    add("camera, 64 scatterers/line, no autocorrelation",
                     lambda: sp.interferogram(*few, cam["wavenumber"], s_cam,
                                              pixel_width=cam["pixel_width"], detection="real"),
                     t_direct)  # fmt: skip
    add("camera, 64 scatterers/line, with autocorrelation (pair sum)",
        lambda: sp.interferogram(*few, cam["wavenumber"], s_cam, pixel_width=cam["pixel_width"],
                                 detection="real", autocorrelation=True), t_direct)  # fmt: skip
    add("camera, 64 scatterers/line, with autocorrelation, FINUFFT (tol 1e-8)",
        lambda: sp.interferogram(*few, cam["wavenumber"], s_cam, pixel_width=cam["pixel_width"],
                                 detection="real", autocorrelation=True, method="finufft",
                                 tol=1e-8), t_direct)  # fmt: skip

    print(f"scene: {n_pixels} px x {n_lines} lines x {density:g} scatterers/px "
          f"(M = {m}/line), best of {args.repeat}")  # fmt: skip
    print(f"ideal chain vs speckle.ascan: relative error {err:.1e} (direct camera), "
          f"{err_nufft:.1e} (FINUFFT camera, tol 1e-10)")  # fmt: skip
    print("| step | time | / ascan direct | / FFT only |\n|---|---|---|---|")
    for label, t, ratio in rows:
        r = "" if ratio is None else f"{ratio:.3g}x"
        print(f"| {label} | {t * 1e3:.1f} ms | {r} | {t / t_fft:.3g}x |")


if __name__ == "__main__":
    main()
