"""The 3-D volume streamed by tiles to a chunked NetCDF file: wall time and peak RSS.

Run from the repository root (each run is a fresh process, so ``ru_maxrss`` is this run's peak)::

    python benchmarks/bench_volume.py                       # 128 x 128 lines x 512 px
    python benchmarks/bench_volume.py --lines 16 --pixels 64 --method direct   # smoke test
    python benchmarks/bench_volume.py --distributed         # the same on a dask.distributed
                                                            # LocalCluster (2 workers)

Scene: one scatterer per pixel x pitch x pitch voxel (Rayleigh amplitudes), pitch 4 µm, pixel
8 µm, beam waist 2 pitches, rectangular spectrum, k0/delta_k = 10. The scene is drawn tile by
tile inside each chunk of lines (with the beam's halo) and never held whole; each chunk is
written to the file as it is computed (progress bar on stderr).
"""

from __future__ import annotations

import argparse
import os
import resource
import sys
import tempfile
import time

import dask

import speckle
from speckle.io import stream_to_netcdf
from speckle.scene import regions as R


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--lines", type=int, default=128, help="lines along x and along y")
    ap.add_argument("--pixels", type=int, default=512, help="pixels per A-scan")
    ap.add_argument("--chunk", type=int, default=32, help="lines per chunk along x and y")
    ap.add_argument("--method", default="auto", help="speckle.beam_scan method")
    ap.add_argument("--tol", type=float, default=1e-6)
    ap.add_argument("--workers", type=int, default=2)
    ap.add_argument("--distributed", action="store_true", help="use a LocalCluster")
    ap.add_argument("--out", default=None, help="output file (default: a temporary file)")
    args = ap.parse_args()

    pitch, pixel = 4.0, 8.0
    src = speckle.spectrum(args.pixels, args.pixels * pixel, k0_dk=10)
    reg = speckle.make_regions(R.background(density=R.cell_density(1.0, pixel, pitch, 3)))
    xs = speckle.scan_lines(args.lines, pitch)
    tol = None if args.method == "direct" else args.tol
    ds = speckle.image_regions(
        reg,
        src,
        seed=1,
        tile=(512.0, 64.0, 64.0),
        waist=2 * pitch,
        lines=xs,
        y=xs,
        chunk=args.chunk,
        method=args.method,
        tol=tol,
    )[["field"]]
    out = args.out or os.path.join(tempfile.mkdtemp(), "volume.nc")
    t0 = time.perf_counter()
    if args.distributed:
        from distributed import Client, LocalCluster

        with (
            LocalCluster(
                n_workers=args.workers, threads_per_worker=1, dashboard_address=":0"
            ) as cluster,
            Client(cluster),
        ):
            stream_to_netcdf(ds, out)
    else:
        with dask.config.set(scheduler="threads", num_workers=args.workers):
            stream_to_netcdf(ds, out)
    wall = time.perf_counter() - t0
    peak = resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024
    size = os.path.getsize(out) / 2**20
    print(
        f"volume {args.lines} x {args.lines} lines x {args.pixels} px, chunk {args.chunk}, "
        f"method {args.method}, tol {tol}, {'distributed' if args.distributed else 'threads'} "
        f"x {args.workers}: wall {wall:.1f} s, peak RSS (this process) {peak:.0f} MiB, "
        f"file {size:.0f} MiB ({ds.field.data.npartitions} chunks) -> {out}",
        file=sys.stderr,
    )


if __name__ == "__main__":
    main()
