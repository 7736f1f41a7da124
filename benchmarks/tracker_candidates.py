"""Dense registration candidates against ``speckle.track``: time and rms error on one pair.

Run from the repository root (~1 min on 2 cores)::

    python benchmarks/tracker_candidates.py

Issue 18 names ``skimage.registration.optical_flow_ilk`` (iterative Lucas-Kanade) as a candidate
for the tracker. On the benchmark pair of ``bench_strain.py`` (1024 x 256 px, strain 2e-3) this
times it on the amplitude at one and at two samples per pixel (the tracker's oversampled
amplitude, :func:`speckle.analysis.oversample_depth`), for two radii and 1, 3 and 10 warps (10 is
skimage's default), next to ``track_array`` (``method="fft"``, the default) and its per-window
reference, each in the same run (CPU time, best of ``--repeat``; the reference once). The dense
flow is averaged over each of the tracker's windows (32 x 16 px every 16 x 8) to compare like
with like; rms error of ``uz`` against ``u = -s z`` at the window centres, in pixels.
"""

from __future__ import annotations

import argparse
import platform

import numpy as np
from _common import best_time, cpu_model, strain_pair
from skimage.registration import optical_flow_ilk

from speckle.analysis import oversample_depth, track_array


def window_means(flow: np.ndarray, tr: dict, factor: int) -> np.ndarray:
    """Mean of a dense (depth samples, x) flow over every window of the tracker's result
    ``tr`` (window size from its centres' spacing rule: (32, 16) px), in pixels."""
    z0 = np.rint(tr["centre_depth"] - 15.5).astype(int) * factor
    x0 = np.rint(tr["centre_x"] - 7.5).astype(int)
    view = np.lib.stride_tricks.sliding_window_view(flow, (32 * factor, 16))
    return view[z0][:, x0].mean(axis=(2, 3)) / factor


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--strain", type=float, default=2e-3)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    ref, dfm, _ = strain_pair(args.strain)
    print(f"{cpu_model()}, Python {platform.python_version()}, numpy {np.__version__}")
    print(f"image {ref.shape[0]} x {ref.shape[1]} px, strain {args.strain:g}\n")
    _, fast, tr = best_time(lambda: track_array(ref, dfm), args.repeat, warmup=True)
    _, slow, tref = best_time(lambda: track_array(ref, dfm, method="reference"), 1, warmup=True)
    exact = -args.strain * tr["centre_depth"][:, None]

    def rms(uz):
        return float(np.sqrt(np.nanmean((uz - exact) ** 2)))

    print("| candidate | CPU time | vs track (fft) | vs reference | rms error (px) |")
    print("|---|---|---|---|---|")
    for name, t, uz in (
        ("track (fft, default)", fast, tr["uz"]),
        ("track (reference)", slow, tref["uz"]),
    ):
        print(f"| {name} | {t:.3g} s | {t / fast:.2g}x | {slow / t:.0f}x faster | {rms(uz):.4f} |")
    for factor in (1, 2):
        amp = [np.abs(oversample_depth(x, factor, axis=0)).astype(np.float32) for x in (ref, dfm)]
        for radius in (7, 16):
            for warps in (1, 3, 10):
                _, t, flow = best_time(
                    lambda a=amp, r=radius, w=warps: optical_flow_ilk(*a, radius=r, num_warp=w),
                    args.repeat if warps < 10 else 1,
                )
                uz = window_means(flow[0], tr, factor)
                print(
                    f"| optical_flow_ilk, {factor} sample(s)/px, radius {radius}, {warps} warps "
                    f"| {t:.3g} s | {t / fast:.2g}x | {slow / t:.0f}x faster | {rms(uz):.4f} |"
                )


if __name__ == "__main__":
    main()
