"""Benchmark of the strain estimators and the tracker: time per megapixel against rms error.

Run from the repository root::

    python benchmarks/bench_strain.py            # 1024 px x 256 A-lines (a few minutes)
    python benchmarks/bench_strain.py --quick    # 256 x 64, smoke test

Uniform compression (default 2e-3: up to 2 px displacement at 1024 px, so alignment is needed)
of a Gaussian-spectrum image (FWHM 0.5 delta_k, k0/delta_k 10, 4 scatterers per pixel, 8 µm
pixels). Every time is the best of ``--repeat`` runs, as wall clock and as this process's CPU
time (the machine is shared: CPU time is the steadier of the two), and every ratio is against
the ten-line numpy baseline (vector method at fixed lag 3, ``scipy.ndimage.uniform_filter``
windows (32, 4), no alignment), timed in rounds interleaved with each method (baseline,
method, baseline, ...; the median of the rounds' ratios, after one warm-up call). The
tracker table compares ``speckle.track`` (``method="fft"``) with the per-window
``phase_cross_correlation`` reference on the same pair (default windows (32, 16), steps
(16, 8); the median of the speed-ups of ``--repeat`` interleaved rounds after a warm-up call
of each), and lists ``track_axial`` (the alignment tracker of the phase methods: lateral
offset 0, windows (64, 8) every (64, 8)).
Each row's ``target`` is issue 18's bound on the CPU ratio (tracker: the speed-up).
"""

from __future__ import annotations

import argparse
import inspect
import platform
import time

import numpy as np
from _common import PIXEL, cpu_model, strain_pair
from scipy import ndimage

import speckle
from speckle.analysis import sample_field, track_array
from speckle.analysis.strain import ALIGN_TRACKING
from speckle.analysis.tracking import track_axial

#: Issue 18's bound on the CPU time ratio to the numpy baseline, per row.
TARGETS = {"vector (default)": 3.0, "vector (unaligned)": 1.5}
METHODS = [
    ("vector", {}),
    ("vector", {"align": False}),
    ("vector", {"align": True}),
    ("wls", {}),
    ("wls", {"align": False}),
    ("wls", {"align": True}),
    ("tracking", {}),
    ("correlation", {}),
]


def baseline(ref: np.ndarray, dfm: np.ndarray, k0: float, pixel: float) -> np.ndarray:
    """The ten lines of numpy: vector method, fixed lag 3, (32, 4) windows, no alignment."""
    lag = 3
    c = ref[:-lag] * np.conj(dfm[:-lag]) * np.conj(ref[lag:]) * dfm[lag:]
    s = ndimage.uniform_filter(c.real, (32, 4)) + 1j * ndimage.uniform_filter(c.imag, (32, 4))
    return -np.angle(s) / (2 * k0 * lag * pixel)


def _once(func):
    w0, c0 = time.perf_counter(), time.process_time()
    out = func()
    return time.perf_counter() - w0, time.process_time() - c0, out


def timed(func, repeat: int, warmup: bool = True):
    """(best wall time, best CPU time, last result); ``warmup``: one untimed call first (numba
    kernels compiled or loaded from their cache, FFT plans made)."""
    out = func() if warmup else None
    runs = [_once(func) for _ in range(repeat)]
    if runs:
        out = runs[-1][2]
    return min(r[0] for r in runs), min(r[1] for r in runs), out


def rounds(func, base, repeat: int):
    """``func`` timed in rounds interleaved with ``base`` (base, func, base, ...) after one
    warm-up call of each (lazy imports, compiled kernels, FFT plans): times of shape
    (repeat, 4), each round's (base wall, base CPU, func wall, func CPU), and the last results
    of ``func`` and ``base``. A load that comes and
    goes hits both calls of a round alike, so the rounds' ratios are steadier than the ratio of
    two best times measured minutes apart."""
    func()
    base()
    times, out, base_out = [], None, None
    for _ in range(repeat):
        bw, bc, base_out = _once(base)
        w, c, out = _once(func)
        times.append((bw, bc, w, c))
    return np.array(times), out, base_out


def paired(func, base, repeat: int):
    """``func`` against the baseline ``base`` (:func:`rounds`): (best wall, best CPU, median of
    the rounds' wall ratios func/base, of their CPU ratios, result)."""
    t, out, _ = rounds(func, base, repeat)
    rw, rc = np.median(t[:, 2:] / t[:, :2], axis=0)
    return t[:, 2].min(), t[:, 3].min(), float(rw), float(rc), out


def speedup(fast, slow, repeat: int):
    """``fast`` against ``slow`` (:func:`rounds`): best (slow wall, slow CPU, fast wall, fast
    CPU), the median of the rounds' slow/fast wall and CPU ratios, and the last (slow, fast)
    results."""
    t, fast_out, slow_out = rounds(fast, slow, repeat)
    ratio_wall, ratio_cpu = np.median(t[:, :2] / t[:, 2:], axis=0)
    return t.min(axis=0), float(ratio_wall), float(ratio_cpu), (slow_out, fast_out)


def scores(est: np.ndarray, truth: float) -> tuple[float, float, float]:
    ok = np.isfinite(est)
    if not ok.any():
        return np.nan, np.nan, 0.0
    e = est[ok]
    return float(np.median(e) / truth), float(np.sqrt(np.mean((e - truth) ** 2)) / truth), ok.mean()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--quick", action="store_true")
    parser.add_argument("--strain", type=float, default=2e-3)
    parser.add_argument("--repeat", type=int, default=3)
    args = parser.parse_args()
    n, lines = (256, 64) if args.quick else (1024, 256)
    pixel = PIXEL
    ref, dfm, k0 = strain_pair(args.strain, n, lines)
    mpx = ref.size / 1e6
    print(f"{cpu_model()}, Python {platform.python_version()}, numpy {np.__version__}")
    print(f"image {n} x {lines} px, strain {args.strain:g}, best of {args.repeat}\n")
    bw, bc, best = timed(lambda: baseline(ref, dfm, k0, pixel), args.repeat)
    print(
        "| method | window | wall / Mpx | CPU / Mpx | wall vs numpy | CPU vs numpy | target | "
        "median / truth | rms / truth | answered |"
    )
    print("|---|---|---|---|---|---|---|---|---|---|")
    med, rms, ans = scores(best, args.strain)
    print(
        f"| numpy baseline (lag 3, no alignment) | (32, 4) | {bw / mpx:.3g} s | {bc / mpx:.3g} s "
        f"| 1.0x | 1.0x | | {med:.4f} | {rms:.4f} | {ans:.2f} |"
    )
    for method, opts in METHODS:
        wall, cpu, ratio_wall, ratio_cpu, est = paired(
            lambda method=method, opts=opts: speckle.estimate_strain(
                ref, dfm, k0=k0, pixel_size=pixel, method=method, **opts
            ),
            lambda: baseline(ref, dfm, k0, pixel),
            args.repeat,
        )
        label = method + {True: " (aligned)", False: " (unaligned)"}.get(
            opts.get("align"), " (default)"
        )
        window = speckle.analysis.strain.DEFAULT_WINDOWS[method]
        med, rms, ans = scores(est, args.strain)
        target = TARGETS.get(label, 10.0 if method != "vector" else None)
        print(
            f"| {label} | {window} | {wall / mpx:.3g} s | {cpu / mpx:.3g} s | {ratio_wall:.2f}x | "
            f"{ratio_cpu:.2f}x | {f'<= {target:g}x' if target else ''} | {med:.4f} | {rms:.4f} "
            f"| {ans:.2f} |"
        )
    print(
        "\n| tracker | windows | wall | CPU | speed-up vs reference (wall, CPU) | target | "
        "rms error vs truth (px) |"
    )
    print("|---|---|---|---|---|---|---|")
    align = {k: ALIGN_TRACKING[k] for k in ("window", "step")}
    best, ratio_wall, ratio_cpu, outs = speedup(
        lambda: track_array(ref, dfm),
        lambda: track_array(ref, dfm, method="reference"),
        args.repeat,
    )
    aw, ac, axial = timed(lambda: track_axial(ref, dfm, **align), args.repeat)

    def rms(tr):
        exact = -args.strain * tr["centre_depth"][:, None]  # u = -s z, in pixels
        return float(np.sqrt(np.nanmean((tr["uz"] - exact) ** 2)))

    rows = [
        ("track (fft)", "(32, 16) every (16, 8)", best[2], best[3], ratio_wall, ratio_cpu, outs[1]),
        ("track (reference)", "(32, 16) every (16, 8)", best[0], best[1], 1.0, 1.0, outs[0]),
        (
            "track_axial (alignment)",
            f"{align['window']} every {align['step']}",
            aw,
            ac,
            best[0] / aw,
            best[1] / ac,
            axial,
        ),
    ]
    for name, windows, wall, cpu, sw, sc, tr in rows:
        target = ">= 100x" if name == "track (fft)" else ""
        print(
            f"| {name} | {windows} | {wall:.3g} s | {cpu:.3g} s | {sw:.0f}x, {sc:.0f}x | {target} "
            f"| {rms(tr):.4f} |"
        )
    # the reference's own split: its per-sample interpolation of both images (the issue-time
    # track's sample_field) against its per-window registrations; the speed-up depends on how
    # fast a machine runs each
    ov = inspect.signature(track_array).parameters["oversample"].default
    fine = np.arange(0, n, 1 / ov)
    iw, ic, _ = timed(lambda: [np.abs(sample_field(x.T, fine)) for x in (ref, dfm)], args.repeat)
    print(
        f"\nThe reference's interpolation of both images (sample_field, {ov} samples/px): "
        f"{iw:.3g} s wall, {ic:.3g} s CPU, {100 * ic / best[1]:.0f} % of its CPU time; its "
        f"per-window registrations the rest ({best[1] - ic:.3g} s, "
        f"{(best[1] - ic) / best[3]:.0f}x the fft tracker's whole call)."
    )


if __name__ == "__main__":
    main()
