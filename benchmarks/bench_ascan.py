"""Benchmark of the A-scan synthesis methods: prints the speed/accuracy table.

Run from the repository root::

    python benchmarks/bench_ascan.py            # full run (~3-5 min on 2 cores)
    python benchmarks/bench_ascan.py --quick    # smaller scenes, smoke test

Every ratio is against a baseline measured in the same run. Times are the best of ``--repeat``
runs (wall clock, 2 cores). Relative error is ``||A - A_direct||_2 / ||A_direct||_2`` over the
B-scan (on scene B over the first ``--ref-lines`` lines, because the direct reference takes
minutes there). Peak RSS is measured in a fresh child process per scene.
"""

from __future__ import annotations

import argparse
import concurrent.futures
import platform
import resource
import subprocess
import sys

import finufft
import numpy as np
from _common import best_time, cpu_model, rel_err

# private: FINUFFT's own A-scan, the baseline of the fast methods
from speckle.imaging._methods.nufft import finufft_ascan
from speckle.imaging.aline import ascan, stream_ascans
from speckle.imaging.synthesis import choose_method


def scene(n_pixels, n_lines, density, seed=1):
    """Random scene: uniform depths over [0, 2H) (wrap-around), complex amplitudes."""
    rng = np.random.default_rng(seed)
    m = round(density * n_pixels)
    depth = 8.0 * n_pixels
    z = rng.uniform(0.0, 2 * depth, (n_lines, m))
    a = (rng.normal(size=(n_lines, m)) + 1j * rng.normal(size=(n_lines, m))) / np.sqrt(2)
    k0 = 10.0 * n_pixels * np.pi / depth  # k0/delta_k = 10
    return z, a, depth, k0


def numpy_eq4(z, a, n_pixels, depth_range, k0, spectrum):
    """The literal Eq. 4: an (M, N) phase matrix and an (N, N) DFT matrix per A-line."""
    n = np.arange(n_pixels) - n_pixels // 2
    k = k0 + n * np.pi / depth_range
    q = np.arange(n_pixels)
    dft = np.exp(-2j * np.pi * np.outer(q, n) / n_pixels)  # (N pixels, N wavenumbers)
    out = np.empty((z.shape[0], n_pixels), dtype=complex)
    for b in range(z.shape[0]):
        phase = np.exp(2j * np.outer(z[b], k))  # (M, N)
        field = (a[b] @ phase) * spectrum
        out[b] = dft @ field
    return out


# --- FINUFFT called directly on a whole B-scan, every way we found -----------------------


def finufft_guru_threads(z, a, n_pixels, depth_range, k0, spectrum, tol, workers=2):
    """Lines split over ``workers`` Python threads, one guru plan each (ctypes drops the GIL)."""
    parts = np.array_split(np.arange(z.shape[0]), workers)
    with concurrent.futures.ThreadPoolExecutor(workers) as ex:
        res = ex.map(
            lambda idx: finufft_ascan(z[idx], a[idx], n_pixels, depth_range, k0, spectrum, eps=tol),
            parts,
        )
        return np.concatenate(list(res))


def finufft_2d(z, a, n_pixels, depth_range, k0, spectrum, tol):
    """One 2-D type-1 transform: line index b as second coordinate 2 pi b/B on an integer grid.

    ``F[n, m] = sum_j c_j e^{i n x_j} e^{2i pi m b_j/B}``; an exact inverse DFT over ``m``
    separates the lines. Spreading is 2-D (w^2 per point), the price of one call.
    """
    nl, m = z.shape
    c = (a * np.exp(2j * k0 * z)).ravel()
    x = (np.mod(z, depth_range) * (2 * np.pi / depth_range)).ravel()
    y = np.repeat(2 * np.pi * np.arange(nl) / nl, m)
    f = finufft.nufft2d1(x, y, c, (n_pixels, nl), eps=tol, isign=1, nthreads=2)
    field = np.fft.fft(np.fft.ifftshift(f, axes=1), axis=1) / nl  # (N, B): back to lines
    field = field.T
    q = np.arange(n_pixels)
    shift = np.exp(2j * np.pi * (n_pixels // 2) * q / n_pixels)
    return np.fft.fft(field * spectrum, axis=-1) * shift


def finufft_calls(z, a, n_pixels, depth_range, k0, spectrum, tol):
    """One simple-interface ``nufft1d1`` call per A-line (the obvious way)."""
    c = a * np.exp(2j * k0 * z)
    x = np.mod(z, depth_range) * (2 * np.pi / depth_range)
    field = np.stack(
        [
            finufft.nufft1d1(x[b], c[b], n_pixels, eps=tol, isign=1, nthreads=1)
            for b in range(len(z))
        ]
    )
    q = np.arange(n_pixels)
    return np.fft.fft(field * spectrum, axis=-1) * np.exp(
        2j * np.pi * (n_pixels // 2) * q / n_pixels
    )


def peak_rss_child(args):
    """Peak RSS (MiB) of a child process running one synthesis (fresh interpreter)."""
    cmd = [sys.executable, __file__, "--rss-child", *map(str, args)]
    out = subprocess.run(cmd, capture_output=True, text=True, check=True)
    return float(out.stdout.strip().splitlines()[-1])


def rss_child(kind, n_pixels, n_lines, density, method, tol):
    n_pixels, n_lines, density, tol = int(n_pixels), int(n_lines), float(density), float(tol)
    depth = 8.0 * n_pixels
    k0 = 10.0 * n_pixels * np.pi / depth
    if kind == "stream":
        stream_ascans(
            n_lines,
            density,
            n_pixels=n_pixels,
            depth_range=depth,
            k0=k0,
            seed=1,
            method=method,
            tol=tol,
            chunk_lines=256,
        )
    else:
        z, a, depth, k0 = scene(n_pixels, n_lines, density)
        ascan(z, a, n_pixels=n_pixels, depth_range=depth, k0=k0, method=method, tol=tol)
    print(_peak_rss_mib())


def _peak_rss_mib():
    """Peak resident set of this process in MiB: VmHWM (reset by exec; ``ru_maxrss`` is not --
    after fork+exec it still holds the parent's peak)."""
    try:
        with open("/proc/self/status") as f:
            for line in f:
                if line.startswith("VmHWM:"):
                    return float(line.split()[1]) / 1024.0
    except OSError:
        pass
    return resource.getrusage(resource.RUSAGE_SELF).ru_maxrss / 1024.0


def row(name, t, err, n_scat, base=None, extra=""):
    speed = f"{base / t:9.1f}x" if base else " " * 10
    print(
        f"  {name:<28s} {t * 1e3:10.1f} ms {speed} {err:10.2e} {n_scat / t / 1e6:8.2f} M/s {extra}"
    )


def main():
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--quick", action="store_true", help="small scenes (smoke test)")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--tol", type=float, default=1e-6)
    p.add_argument("--ref-lines", type=int, default=16)
    p.add_argument("--rss-child", nargs=6, help=argparse.SUPPRESS)
    args = p.parse_args()
    if args.rss_child:
        rss_child(*args.rss_child)
        return
    tol = args.tol
    print(
        f"machine: {platform.processor() or platform.machine()}, {cpu_model()}, "
        f"python {platform.python_version()}, numpy {np.__version__}, finufft {finufft.__version__}"
    )
    print(f"tol = {tol:g}; error = ||A - A_direct||_2/||A_direct||_2; times best of {args.repeat}")

    # warm-up: numba compilation is not part of any timing
    zw, aw, hw_, kw = scene(32, 4, 2)
    for name in ("nufft", "nufft32", "psf", "auto"):
        try:
            ascan(
                zw,
                aw,
                n_pixels=32,
                depth_range=hw_,
                k0=kw,
                method=name,
                tol=1e-3,
                spectrum=np.exp(-(((np.arange(32) - 16) / 6.0) ** 2)),
            )
        except ValueError:
            pass

    # --- scene A: vs the plain numpy transcription of Eq. 4 ---------------------------------
    n_pix, n_lines, rho = (64, 64, 4) if args.quick else (256, 256, 4)
    z, a, depth, k0 = scene(n_pix, n_lines, rho)
    s = np.ones(n_pix)
    n_scat = z.size
    print(
        f"\nA: {n_pix} px x {n_lines} lines x {rho}/px = {n_scat} scatterers, rectangular "
        f"spectrum, depths in [0, 2H), k0/dk = 10"
    )
    print(f"  {'method':<28s} {'time':>13s} {'vs numpy':>10s} {'rel.err':>10s} {'scat/s':>10s}")
    t_np, _, a_np = best_time(lambda: numpy_eq4(z, a, n_pix, depth, k0, s), 1)
    t_ref, _, ref = best_time(lambda: ascan(z, a, n_pixels=n_pix, depth_range=depth, k0=k0), 1)
    row("numpy Eq. 4 (baseline)", t_np, rel_err(a_np, ref), n_scat, t_np)
    row("direct", t_ref, 0.0, n_scat, t_np)
    for name in ("finufft", "nufft", "nufft32", "psf", "auto"):
        try:
            t, _, out = best_time(
                lambda name=name: ascan(
                    z, a, n_pixels=n_pix, depth_range=depth, k0=k0, method=name, tol=tol
                ),
                args.repeat,
            )
        except ValueError as exc:
            print(f"  {name:<28s} refused: {str(exc)[:70]}")
            continue
        extra = (
            f"(auto -> {choose_method(n_lines, z.shape[1], n_pix, s, tol)})"
            if name == "auto"
            else ""
        )
        row(name, t, rel_err(out, ref), n_scat, t_np, extra)

    # --- scene B: vs FINUFFT called directly ------------------------------------------------
    n_pix, n_lines, rho = (256, 128, 4) if args.quick else (1024, 512, 4)
    z, a, depth, k0 = scene(n_pix, n_lines, rho, seed=2)
    s = np.ones(n_pix)
    n_scat = z.size
    nr = min(args.ref_lines, n_lines)
    ref = ascan(z[:nr], a[:nr], n_pixels=n_pix, depth_range=depth, k0=k0)
    print(
        f"\nB: {n_pix} px x {n_lines} lines x {rho}/px = {n_scat} scatterers (error on the "
        f"first {nr} lines)"
    )
    print(f"  {'method':<28s} {'time':>13s} {'vs FINUFFT':>10s} {'rel.err':>10s} {'scat/s':>10s}")
    direct_ways = {
        "FINUFFT nufft1d1 per line": finufft_calls,
        "FINUFFT guru plan, 1 thread": lambda *x: finufft_ascan(*x[:-1], eps=x[-1]),
        "FINUFFT guru plan, 2 threads": finufft_guru_threads,
        "FINUFFT 2-D (line index)": finufft_2d,
    }
    times = {}
    for label, func in direct_ways.items():
        t, _, out = best_time(lambda func=func: func(z, a, n_pix, depth, k0, s, tol), args.repeat)
        times[label] = (t, rel_err(out[:nr], ref))
    best_label = min(times, key=lambda k: times[k][0])
    t_fin = times[best_label][0]
    for label, (t, err) in times.items():
        row(label + (" *" if label == best_label else ""), t, err, n_scat, t_fin)
    for name in ("nufft", "nufft32", "auto"):
        t, _, out = best_time(
            lambda name=name: ascan(
                z, a, n_pixels=n_pix, depth_range=depth, k0=k0, method=name, tol=tol
            ),
            args.repeat,
        )
        extra = (
            f"(auto -> {choose_method(n_lines, z.shape[1], n_pix, s, tol)})"
            if name == "auto"
            else ""
        )
        row(name, t, rel_err(out[:nr], ref), n_scat, t_fin, extra)
    print("  * best direct-FINUFFT way (the baseline of the ratio column)")

    # --- memory --------------------------------------------------------------------------
    print(
        f"\nPeak RSS (fresh process, MiB; importing speckle and compiling costs "
        f"{peak_rss_child(['array', 32, 1, 1, 'auto', tol]):.0f} MiB):"
    )
    streams = [(256, 1024)] if args.quick else [(1024, 4096), (1024, 16384)]
    runs = [("array", n_pix, n_lines)] + [("stream", *b) for b in streams]
    for kind, npx, nl in runs:
        rss = peak_rss_child([kind, npx, nl, rho, "auto", tol])
        what = "whole scene in memory" if kind == "array" else "generated 256 lines at a time"
        out_mb = nl * npx * 16 / 2**20
        print(
            f"  {npx} px x {nl} lines x {rho}/px ({nl * npx * rho / 1e6:.0f} M scatterers), "
            f"{what}: {rss:5.0f} MiB (output array {out_mb:.0f} MiB)"
        )


if __name__ == "__main__":
    main()
