"""Benchmark of the strain estimators: time per megapixel and accuracy on one image pair.

Run from the repository root::

    python benchmarks/bench_strain.py            # 512 px x 128 A-lines (~1-2 min on 2 cores)
    python benchmarks/bench_strain.py --quick    # 256 x 32, smoke test

Uniform compression (default 2e-3) of a Gaussian-spectrum image (FWHM 0.5 delta_k, k0/delta_k
10, 4 scatterers per pixel, 8 µm pixels). Times are the best of ``--repeat`` runs (wall clock);
speed is reported as a ratio to the unaligned vector method measured in the same run (with the
default ``align="auto"`` the phase methods align here: the displacement reaches 1 px).
"""

from __future__ import annotations

import argparse
import platform
import time

import numpy as np

import speckle

METHODS = [
    ("vector", {"align": False}),
    ("wls", {"align": False}),
    ("vector", {"align": True}),
    ("wls", {"align": True}),
    ("tracking", {}),
    ("correlation", {}),
]


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--strain", type=float, default=2e-3)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    n, lines = (256, 32) if args.quick else (512, 128)
    pixel = 8.0
    h = n * pixel
    src = speckle.spectrum(n, h, k0_dk=10.0, shape="gaussian", fwhm=0.5 * n * np.pi / h)
    scene = speckle.deformable_scene(lines, 4.0, n_pixels=n, depth=h, seed=1, strain=args.strain)
    img = speckle.bscan(
        speckle.uniaxial_strain(scene, [0.0, args.strain]), src, method="nufft", tol=1e-9
    ).field.values
    ref, dfm = img
    k0 = src.attrs["k0"]
    print(f"{platform.processor() or platform.machine()}, Python {platform.python_version()}")
    print(f"image {n} x {lines} px, strain {args.strain:g}, best of {args.repeat}")
    print("| method | window | time / Mpx | vs vector | median / truth | rms / truth | answered |")
    print("|---|---|---|---|---|---|---|")
    base = None
    for method, opts in METHODS:
        best, est = np.inf, None
        for _ in range(args.repeat):
            t0 = time.perf_counter()
            est = speckle.estimate_strain(ref, dfm, k0=k0, pixel_size=pixel, method=method, **opts)
            best = min(best, time.perf_counter() - t0)
        per_mpx = best / (ref.size / 1e6)
        base = per_mpx if base is None else base
        ok = np.isfinite(est)
        label = method + {True: " (aligned)", False: " (unaligned)"}.get(opts.get("align"), "")
        window = speckle.analysis.strain.DEFAULT_WINDOWS[method]
        print(
            f"| {label} | {window} | {per_mpx:.3g} s | {per_mpx / base:.1f}x | "
            f"{np.median(est[ok]) / args.strain:.4f} | "
            f"{np.sqrt(np.mean((est[ok] - args.strain) ** 2)) / args.strain:.3f} | "
            f"{ok.mean():.2f} |"
        )


if __name__ == "__main__":
    main()
