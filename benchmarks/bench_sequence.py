"""Benchmark: a long compression sequence streamed through ``speckle.accumulate_strain``.

Run from the repository root::

    python benchmarks/bench_sequence.py                 # 200 frames of 1024 x 256 px
    python benchmarks/bench_sequence.py --frames 8 --quick

The frames (fully developed speckle with a Gaussian spectrum, FWHM 0.5 delta_k, k0/delta_k 10,
compressed by ``--strain`` per frame: each frame is the first one resampled at ``q (1 + t)``
with the carrier ``exp(2i k0 u)``, ``u = -t z``) are generated lazily with Dask and written to
a chunked NetCDF file; that file is opened lazily and processed with ``accumulate_strain(...,
path=...)`` on the threads scheduler. Printed: the wall time of each stage, the peak resident
memory of the process (``ru_maxrss``) and the median cumulative strain against the truth.
"""

from __future__ import annotations

import argparse
import resource
import tempfile
import time
from pathlib import Path

import dask
import dask.array as da
import numpy as np
import xarray as xr

import speckle
from speckle.analysis import resample_depth
from speckle.io import open_dataset, stream_to_netcdf


def base_image(n: int, lines: int, seed: int) -> np.ndarray:
    """Band-limited circular Gaussian speckle: white complex noise through a Gaussian spectrum."""
    rng = np.random.default_rng(seed)
    noise = rng.normal(size=(n, lines)) + 1j * rng.normal(size=(n, lines))
    nu = np.fft.fftfreq(n)  # cycles per pixel; FWHM 0.5 delta_k = 0.5 cycle/pixel
    spec = np.exp(-4 * np.log(2) * (nu / 0.5) ** 2)
    return np.fft.ifft(np.fft.fft(noise, axis=0) * spec[:, None], axis=0)


def frame(base: np.ndarray, total: float, k0: float, pixel: float) -> np.ndarray:
    q = np.arange(base.shape[0], dtype=float)[:, None] * np.ones((1, base.shape[1]))
    return (resample_depth(base, q * (1 + total)) * np.exp(-2j * k0 * total * q * pixel))[None]


def peak_rss_gib() -> float:
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 2**20  # kB on Linux


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--frames", type=int, default=200)
    parser.add_argument("--strain", type=float, default=2e-4)
    parser.add_argument("--quick", action="store_true", help="256 x 64 px frames")
    parser.add_argument("--workers", type=int, default=2)
    args = parser.parse_args()
    n, lines = (256, 64) if args.quick else (1024, 256)
    pixel, k0 = 8.0, 10.0 * np.pi / 8.0  # k0/delta_k = 10 with delta_k = pi/p
    totals = [1 - (1 - args.strain) ** i for i in range(args.frames)]
    base = base_image(n, lines, seed=1)
    parts = [
        da.from_delayed(dask.delayed(frame)(base, t, k0, pixel), (1, n, lines), complex)
        for t in totals
    ]
    field = xr.DataArray(
        da.concatenate(parts),
        dims=("frame", "depth", "x"),
        coords={"depth": np.arange(n) * pixel, "x": np.arange(lines) * 8.0},
    )
    with tempfile.TemporaryDirectory(dir=".") as tmp:
        src, out = Path(tmp) / "frames.nc", Path(tmp) / "strain.nc"
        t0 = time.perf_counter()
        with dask.config.set(scheduler="threads", num_workers=args.workers):
            stream_to_netcdf(field.to_dataset(name="field"), src, progress=False)
        t1 = time.perf_counter()
        frames = open_dataset(src, load=False)["field"].chunk({"frame": 1})
        with dask.config.set(scheduler="threads", num_workers=args.workers):
            res = speckle.accumulate_strain(
                frames, k0=k0, pixel_size=pixel, path=out, progress=True
            )
        t2 = time.perf_counter()
        last = float(np.nanmedian(res["accumulated"].isel(frame=-1).values))
        print(f"frames: {args.frames} x {n} x {lines} px, {args.workers} threads")
        print("| stage | wall time |\n|---|---|")
        print(f"| simulate and stream the frames to NetCDF | {t1 - t0:.1f} s |")
        print(f"| accumulate_strain, lazy in, streamed out | {t2 - t1:.1f} s |")
        print(f"| per pair | {(t2 - t1) / (args.frames - 1):.2f} s |")
        print(
            f"peak RSS {peak_rss_gib():.2f} GiB; input file {src.stat().st_size / 2**30:.2f} GiB, "
            f"output {out.stat().st_size / 2**30:.2f} GiB"
        )
        print(f"last frame: median cumulative {last:.5g}, truth {totals[-1]:.5g}")


if __name__ == "__main__":
    main()
