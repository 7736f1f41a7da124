"""Benchmark of the scanned-beam B-scan (`speckle.beam_scan`) against FINUFFT called directly.

Run from the repository root::

    python benchmarks/bench_beam.py            # 512 px x 512 lines x 4/px (1 M scatterers)
    python benchmarks/bench_beam.py --quick    # 128 x 128, smoke test

Scene: a shared 2-D scene, scatterers uniform over the scanned span (x) and one unambiguous
depth, complex Gaussian amplitudes, rectangular spectrum, k0/dk = 10, 8 µm pixels, lines every
4 µm, w0 = 2 pitches (8 µm), 4 scatterers per pixel per line. Every method images the same scene
in the same run; times are the best of ``--repeat`` runs (wall clock, and process CPU time over
all threads: on a shared machine the CPU time is the steadier of the two), numba compilation
excluded. Relative error ``||A - A_direct||_2 / ||A_direct||_2`` on ``--ref-lines`` lines spread
over the scan (the exact direct reference costs seconds per line here).

``beam_scan`` rows: the row path (:mod:`speckle.imaging._methods.beam_row`, taken by a row or raster
of lines without focus) and, as its baseline in the same run, the general code of
:mod:`speckle.imaging._methods.beam_nufft` (``(general path)``: the method of
:data:`speckle.imaging.methods.BEAM_METHODS` called with ``path="general"``, as before the row
path existed).

FINUFFT baseline: the depth-independent beam is a Gaussian in ``x - X_i``, so one 2-D type-1
transform of the scene (depth frequency x lateral frequency over a lateral period padded by the
beam reach) times the beam's lateral Fourier transform, folded onto the line grid and
transformed back (:func:`speckle.imaging._methods.beam_nufft.finufft_beam_scan`), at FINUFFT's own
``eps = tol`` (its loosest setting that still met tol here), on 1 or 2 threads and at
upsampling factors 2 and 1.25; the fastest of these is the baseline of the ratio column.
"""

from __future__ import annotations

import argparse
import functools
import platform
import time

import finufft
import numba
import numpy as np
from _common import best_time, cpu_model, rel_err

import speckle

# private: the beam methods' internals (line grid, FINUFFT reference)
from speckle.imaging._methods.beam_nufft import choose_beam_method, finufft_beam_scan, line_grid
from speckle.imaging.beam import beam_problem
from speckle.imaging.methods import BEAM_METHODS


def scene(n_pixels, n_lines, density, pitch, seed=1):
    """Uniform shared scene over the scanned span (µm), complex Gaussian amplitudes."""
    rng = np.random.default_rng(seed)
    depth = 8.0 * n_pixels
    m = round(density * n_pixels * n_lines)
    x = rng.uniform(-0.5 * pitch, (n_lines - 0.5) * pitch, m)
    z = rng.uniform(0.0, depth, m)
    a = (rng.normal(size=m) + 1j * rng.normal(size=m)) / np.sqrt(2)
    k0 = 10.0 * n_pixels * np.pi / depth  # k0/delta_k = 10
    return z, x, a, depth, k0


def row(name, t, cpu, err, n_scat, base=None, base_cpu=None, extra=""):
    ratio = f"{base / t:6.2f}x" if base else " " * 7
    ratio_cpu = f"{base_cpu / cpu:6.2f}x" if base_cpu else " " * 7
    print(
        f"  {name:<42s} {t * 1e3:8.0f} ms {ratio} {cpu * 1e3:8.0f} ms {ratio_cpu} "
        f"{err:9.2e} {n_scat / t / 1e6:7.2f} M/s {extra}"
    )


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="128 px x 128 lines (smoke test)")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--tol", type=float, default=1e-6)
    p.add_argument("--ref-lines", type=int, default=6)
    p.add_argument(
        "--tile", type=int, default=0, help="also time one 3-D tile of T x T lines (C-scan)"
    )
    args = p.parse_args()
    tol = args.tol
    if args.tile:
        tile_3d(args.tile, tol, args.repeat)
        return
    n_pix, n_lines, rho, pitch = (128, 128, 4, 4.0) if args.quick else (512, 512, 4, 4.0)
    w0 = 2 * pitch
    z, x, a, depth, k0 = scene(n_pix, n_lines, rho, pitch)
    lines = np.arange(n_lines) * pitch
    n_scat = z.size
    print(
        f"machine: {cpu_model()}, {numba.get_num_threads()} numba threads, python "
        f"{platform.python_version()}, numpy {np.__version__}, numba {numba.__version__}, "
        f"finufft {finufft.__version__}"
    )
    print(
        f"scene: {n_pix} px x {n_lines} lines x {rho}/px/line = {n_scat} scatterers, pitch "
        f"{pitch} µm, w0 = {w0} µm (2 pitches), rectangular spectrum, k0/dk = 10; tol = {tol:g}"
    )
    kw = dict(lines=lines, waist=w0, n_pixels=n_pix, depth_range=depth, k0=k0)
    # warm-up: numba compilation is not part of any timing
    for name in ("nufft", "nufft32"):
        speckle.beam_scan(z[:64], x[:64], a[:64], method=name, tol=1e-3, **kw)
    ref_idx = np.linspace(0, n_lines - 1, min(args.ref_lines, n_lines)).round().astype(int)
    t0 = time.perf_counter()
    ref = speckle.beam_scan(z, x, a, **{**kw, "lines": lines[ref_idx]})
    print(f"direct reference on {ref_idx.size} lines: {time.perf_counter() - t0:.1f} s")

    sc, beam, _ = beam_problem(z, x, a, tol=tol, **kw)
    grid = line_grid(sc.lines, w0)
    ways = {}
    for threads in (1, 2):
        for up in (2.0, 1.25):
            ways[f"FINUFFT 2-D, {threads} thr, upsamp {up}"] = functools.partial(
                finufft_beam_scan, sc, beam, grid, tol=tol, eps=tol, nthreads=threads, upsampfac=up
            )
    print(
        f"\n  {'method':<42s} {'wall':>11s} {'ratio':>7s} {'CPU':>11s} {'ratio':>7s} "
        f"{'rel.err':>9s} {'scat/s':>11s}"
    )
    res = {}
    for label, func in ways.items():
        t, c, out = best_time(func, args.repeat)
        res[label] = (t, c, rel_err(out[ref_idx], ref))
    best = min(res, key=lambda k: res[k][0])
    base, base_cpu = res[best][0], res[best][1]
    for label, (t, c, err) in res.items():
        row(label + (" *" if label == best else ""), t, c, err, n_scat, base, base_cpu)
    threads = numba.get_num_threads()
    for nthr in sorted({1, threads}):
        numba.set_num_threads(nthr)
        for name, path in (("nufft", "general"), ("nufft", "row"), ("nufft32", "row"),
                           ("auto", "row")):  # fmt: skip
            run = functools.partial(scan, z, x, a, name, path, tol, kw)
            t, c, out = best_time(run, args.repeat)
            extra = f"(auto -> {choose_beam_method(sc, beam, tol)})" if name == "auto" else ""
            label = f"beam_scan {name}{' (general path)' if path == 'general' else ''}, {nthr} thr"
            row(label, t, c, rel_err(out[ref_idx], ref), n_scat, base, base_cpu, extra)
    numba.set_num_threads(threads)
    print("  * fastest FINUFFT call (wall): the baseline of both ratio columns")


def scan(z, x, a, name, path, tol, kw):
    """``speckle.beam_scan(method=name)``, or on ``path="general"`` the same validation and
    method on the general code of ``beam_nufft`` (no row path): the baseline of the row path
    (:mod:`speckle.imaging._methods.beam_row`) in the same run."""
    if path == "general":
        return BEAM_METHODS[name](*beam_problem(z, x, a, tol=tol, **kw), path="general")
    return speckle.beam_scan(z, x, a, method=name, tol=tol, **kw)


def tile_3d(n_tile, tol, repeat, n_pix=512, pitch=4.0):
    """One tile of a 3-D volume: T x T lines over a scene of 1 scatterer per voxel (pixel x
    pitch x pitch) covering the tile plus the beam reach on every side, as a streamed volume
    computes it tile by tile."""
    w0 = 2 * pitch
    depth = 8.0 * n_pix
    k0 = 10.0 * n_pix * np.pi / depth
    halo = 3 * w0  # beyond the reach of the weight cut at tol = 1e-6 (2.7 w0)
    span = n_tile * pitch + 2 * halo
    m = round(n_pix * (span / pitch) ** 2)
    rng = np.random.default_rng(3)
    x = rng.uniform(-halo, n_tile * pitch + halo, m)
    y = rng.uniform(-halo, n_tile * pitch + halo, m)
    z = rng.uniform(0.0, depth, m)
    a = (rng.normal(size=m) + 1j * rng.normal(size=m)) / np.sqrt(2)
    gx, gy = np.meshgrid(np.arange(n_tile) * pitch, np.arange(n_tile) * pitch)
    lines = np.stack([gx.ravel(), gy.ravel()], 1)
    kw = dict(y=y, lines=lines, waist=w0, n_pixels=n_pix, depth_range=depth, k0=k0)
    sl = slice(0, 64)
    speckle.beam_scan(z[sl], x[sl], a[sl], **{**kw, "y": y[sl]}, method="nufft32", tol=1e-3)
    ref_lines = lines[[0, n_tile * n_tile // 2 + n_tile // 2]]
    ref = speckle.beam_scan(z, x, a, **{**kw, "lines": ref_lines})
    print(
        f"3-D tile: {n_tile} x {n_tile} lines x {n_pix} px, {m} scatterers (1 per voxel, tile "
        f"+ {halo} µm halo), pitch {pitch} µm, w0 = {w0} µm, tol = {tol:g}"
    )
    for name in ("nufft", "nufft32"):
        for path in ("general", "row"):
            t, c, out = best_time(functools.partial(scan, z, x, a, name, path, tol, kw), repeat)
            pick = [0, n_tile * n_tile // 2 + n_tile // 2]
            err = rel_err(out[pick], ref)
            print(
                f"  {name:<8s} {path:<8s} path: wall {t:6.2f} s, CPU {c:6.2f} s, rel. error "
                f"{err:.1e} (2 lines), {m / t / 1e6:.2f} M scatterers/s"
            )


if __name__ == "__main__":
    main()
