"""A 100-frame series of a moving phantom under every Dask scheduler: time per frame, memory.

Run from the repository root::

    python benchmarks/bench_dynamics.py                    # 100 frames of 512 x 256 pixels
    python benchmarks/bench_dynamics.py --frames 20 --pixels 128 --lines 64   # quick look

The phantom (static layer, a disc of Brownian "cells", a vessel with Poiseuille flow along x;
shared 2-D scene, scanned Gaussian beam, FINUFFT at tol 1e-9) is moved over ``--frames`` times
(``speckle.scene.motion``), imaged as repeated snapshot B-scans
(``speckle.imaging.timeseries.bscan_series``, one Dask task per frame and chunk of lines) and
streamed to NetCDF (``speckle.io.stream_to_netcdf``) under the synchronous and threads
schedulers and a local ``dask.distributed`` cluster; under the processes scheduler (whose
workers cannot share xarray's netCDF lock) in blocks of ``--block`` frames, each computed and
written as it comes. The baseline, measured in the
same process first, is one B-scan of the same scene at rest (``speckle.scan_image``, synchronous).
Every scheduler's file must hold the same numbers, bit for bit (asserted). Printed: wall time,
time per frame, its ratio to the single B-scan, the ratio to the synchronous run, and the peak
memory traced in this process (``tracemalloc``: the scene, the graph and what the local
schedulers compute here; the workers of ``processes`` and of the cluster hold their own).
FINUFFT runs on one thread per task (``NUMBA_NUM_THREADS=1``): its multi-threaded spreading
sums in an order that changes from call to call (the threads scheduler then differed from the
synchronous one in the last bits), and the parallelism compared here is Dask's.
The machine may be shared: compare ratios, not seconds.
"""

from __future__ import annotations

import argparse
import os
import tempfile
import time
import tracemalloc
from pathlib import Path

# one thread inside FINUFFT (it takes numba's thread count): its multi-threaded spreading sums
# in an order that varies, and the parallelism under test is Dask's; set before numba loads
# (worker processes inherit it)
os.environ["NUMBA_NUM_THREADS"] = "1"

import numpy as np
from _common import cpu_model


def phantom(pixels: int, lines: int, frames: int, interval: float, seed: int = 1):
    """(moved scene, scene at rest, source, line positions, waist) of the benchmark phantom."""
    import speckle
    from speckle.scene.motion import brownian_motion, flow_motion, poiseuille_velocity
    from speckle.scene.regions import cell_density, circle, layer, make_regions

    p, w0 = 4.0, 8.0
    depth = pixels * p
    src = speckle.spectrum(pixels, depth, k0_dk=10.0)
    x = np.arange(lines) * p
    rho = cell_density(2.0, p, p)
    regions = make_regions(
        layer(0.0, depth, density=rho),
        circle(0.3 * depth, 0.5 * lines * p, 0.15 * depth, density=rho),
        layer(0.6 * depth, 0.7 * depth, density=rho),
    )
    reach = speckle.beam_reach(w0)
    scene = speckle.shared_scene(
        regions, z_range=(0.0, depth), x_range=(x[0] - reach, x[-1] + reach + p), seed=seed
    )
    times = np.arange(frames) * interval
    vel = poiseuille_velocity(
        scene,
        peak_velocity=2000.0,
        radius=0.05 * depth,
        centre=(0.65 * depth, 0.0),
        direction=(0.0, 1.0),
    )
    moved = brownian_motion(scene, times, diffusion=0.5, seed=seed + 1, regions=[1])
    moved = flow_motion(moved, times, velocity=vel, regions=[2])
    return moved, scene, src, x, w0


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--frames", type=int, default=100)
    parser.add_argument("--pixels", type=int, default=512)
    parser.add_argument("--lines", type=int, default=256)
    parser.add_argument("--chunk", type=int, default=64, help="lines per Dask task")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--block", type=int, default=10, help="frames per block (processes)")
    args = parser.parse_args()

    import dask
    import xarray as xr

    import speckle
    from speckle.imaging.timeseries import bscan_series
    from speckle.io import open_dataset, stream_to_netcdf, to_netcdf

    kw = {"method": "finufft", "tol": 1e-9, "chunk": args.chunk}
    tracemalloc.start()
    moved, scene, src, x, w0 = phantom(args.pixels, args.lines, args.frames, 2e-3)
    scene_mb = sum(moved[v].nbytes for v in moved.data_vars) / 2**20
    with dask.config.set(scheduler="synchronous"):
        speckle.scan_image(scene, src, waist=w0, lines=x, **kw).field.compute()  # warm-up (FINUFFT)
        t0 = time.perf_counter()
        speckle.scan_image(scene, src, waist=w0, lines=x, **kw).field.compute()
        single = time.perf_counter() - t0
    print(
        f"{args.frames} frames of {args.pixels} x {args.lines} px, {moved.sizes['scatterer']} "
        f"scatterers (moved scene {scene_mb:.0f} MiB), chunk {args.chunk} lines, "
        f"{args.workers} workers; {cpu_model()}; {time.strftime('%Y-%m-%d')}"
    )
    print(f"baseline: one B-scan at rest {single:.3f} s (synchronous, same process)\n")
    print(
        "| scheduler | wall (s) | per frame (s) | per frame / one B-scan | / synchronous "
        "| peak traced (MiB) | identical |"
    )
    print("|---|---|---|---|---|---|---|")
    reference = None
    rows = {}
    with tempfile.TemporaryDirectory() as tmp:
        for name in ("synchronous", "threads", "processes", "distributed"):
            path = Path(tmp) / f"{name}.nc"
            series = bscan_series(moved, src, waist=w0, lines=x, **kw)[["field"]]
            tracemalloc.reset_peak()
            t0 = time.perf_counter()
            if name == "distributed":
                from dask.distributed import Client, LocalCluster

                with (
                    LocalCluster(
                        n_workers=args.workers,
                        threads_per_worker=1,
                        processes=True,
                        dashboard_address=None,
                    ) as cluster,
                    Client(cluster),
                ):
                    t0 = time.perf_counter()  # the cluster's start-up is not the series'
                    stream_to_netcdf(series, path, progress=False)
                    wall = time.perf_counter() - t0
            elif name == "processes":
                # xarray's netCDF lock cannot be pickled to worker processes: the series is
                # computed in blocks of frames, each written to its own file as it comes
                with dask.config.set(scheduler=name, num_workers=args.workers):
                    for i in range(0, args.frames, args.block):
                        block = series.isel(time=slice(i, i + args.block)).compute()
                        to_netcdf(block, Path(tmp) / f"{name}_{i:05d}.nc")
                wall = time.perf_counter() - t0
                parts = sorted(Path(tmp).glob(f"{name}_*.nc"))
                to_netcdf(xr.concat([open_dataset(q) for q in parts], "time"), path)
            else:
                opts = {"scheduler": name}
                if name != "synchronous":
                    opts["num_workers"] = args.workers
                with dask.config.set(**opts):
                    stream_to_netcdf(series, path, progress=False)
                wall = time.perf_counter() - t0
            peak = tracemalloc.get_traced_memory()[1] / 2**20
            with open_dataset(path) as ds:
                values = ds.field.values
            if reference is None:
                reference = values
            same = bool(np.array_equal(values, reference))
            rows[name] = wall
            per = wall / args.frames
            print(
                f"| {name} | {wall:.1f} | {per:.3f} | {per / single:.2f} | "
                f"{wall / rows['synchronous']:.2f} | {peak:.0f} | {same} |",
                flush=True,
            )
            assert same, f"{name} gave different numbers from the synchronous run"
    print(f"\n{os.cpu_count()} CPUs visible; ratios within this run are comparable.")


if __name__ == "__main__":
    main()
