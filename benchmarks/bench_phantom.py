"""Benchmark of ``speckle.fit_phantom`` on challenge-size scans (512 x 256).

Run from the repository root::

    python benchmarks/bench_phantom.py            # the four published scans, 5 repeats
    python benchmarks/bench_phantom.py --cases 4  # and the closed-loop batch on 1 and 2 workers

Rows: the fit of each published scan (``Scan_Exp*_{A,B}.png``, the challenge's INI), the
fitted phantom drawn (``PhantomFit.phantom``) and scanned (``PhantomFit.render``), and, as
the baseline measured in the same process, one scan of the baseline's two-layer phantom A by
:func:`speckle.synthoct_scan` (what one call of the official scanner costs a participant's
search loop). The fit is analytic: it calls the scanner zero times (counted by wrapping the
scanner's core); ``render`` calls it once. Times are wall-clock medians with the process CPU
time; the ratio divides by the baseline scan. On a shared machine report the ratios.

Further rows: the fit as a fresh process (``python -c`` importing the package, reading the PNG
and its INI, fitting: what a participant's script pays per scan) against ``speckle-scan`` as a
fresh process (its own baseline, in the same table); the fit of a 2025-configuration scan (601
x 975 pixels, a three-layer virtual patient); and the closed-loop batch
(:func:`speckle.phantom_closed_loop`, ``--cases`` patients of 256 x 256 pixels, each one fit and
four scans, scored) on Dask's synchronous scheduler and on 2 threads, with the scanner calls it
makes per case.
"""

from __future__ import annotations

import argparse
import os
import statistics
import sys
import tempfile
import time
from importlib.resources import files
from pathlib import Path

from _common import cpu_model
from bench_synthoct import REPO, _process

import speckle
from speckle.synthoct import _scan  # private: wrapped to count the scanner's calls

CALLS = {"n": 0}
_fields = _scan.scan_fields


def _counted(*args, **kwargs):
    CALLS["n"] += 1
    return _fields(*args, **kwargs)


def timed(fn, repeats):
    walls, cpus, out = [], [], None
    for _ in range(repeats):
        w, c = time.perf_counter(), time.process_time()
        out = fn()
        walls.append(time.perf_counter() - w)
        cpus.append(time.process_time() - c)
    return statistics.median(walls), statistics.median(cpus), out


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--repeats", type=int, default=5)
    parser.add_argument("--fresh", type=int, default=3, help="fresh processes per row")
    parser.add_argument("--cases", type=int, default=0, help="closed-loop cases (0: no batch)")
    args = parser.parse_args()
    _scan.scan_fields = _counted
    cfg = speckle.ScannerConfig()
    data = files("speckle.data") / "synthoct"
    table = speckle.synthoct.files.baseline_table("layers", 42)
    speckle.fit_phantom(data / "Scan_Exp2_Layers_A.png", cfg)  # warm caches (theory tables)
    base_wall, base_cpu, _ = timed(lambda: speckle.synthoct_scan(table, cfg), 3)
    print(f"CPU: {cpu_model()}")
    print(f"{'what':<34}{'wall s':>9}{'CPU s':>9}{'ratio':>8}{'scanner calls':>15}")
    print(f"{'synthoct_scan (baseline)':<34}{base_wall:9.3f}{base_cpu:9.3f}{1:8.2f}{1:15d}")
    fit = None
    for name in ("Exp1_Uniform_A", "Exp1_Uniform_B", "Exp2_Layers_A", "Exp2_Layers_B"):
        levels = speckle.read_scan(data / f"Scan_{name}.png")
        CALLS["n"] = 0
        wall, cpu, fit = timed(lambda lv=levels: speckle.fit_phantom(lv, cfg), args.repeats)
        calls = CALLS["n"] // args.repeats
        print(f"{'fit ' + name:<34}{wall:9.3f}{cpu:9.3f}{wall / base_wall:8.2f}{calls:15d}")
    wall, cpu, _ = timed(lambda: fit.phantom(1), 3)
    print(f"{'phantom(seed)':<34}{wall:9.3f}{cpu:9.3f}{wall / base_wall:8.2f}{0:15d}")
    CALLS["n"] = 0
    wall, cpu, _ = timed(lambda: fit.render(1), 3)
    print(f"{'render(seed)':<34}{wall:9.3f}{cpu:9.3f}{wall / base_wall:8.2f}{CALLS['n'] // 3:15d}")

    # fresh processes: the fit as a participant's script runs it, against speckle-scan
    tmp = Path(tempfile.mkdtemp(prefix="bench_phantom_"))
    ini, png = tmp / "Configuration.ini", data / "Scan_Exp2_Layers_A.png"
    speckle.write_scanner_config(cfg, ini)
    speckle.write_phantom(table, tmp / "Scatterers.txt")
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    scan_cmd = [sys.executable, "-m", "speckle.synthoct", str(ini), str(tmp / "Scatterers.txt"),
                str(tmp / "o.png")]  # fmt: skip
    fit_cmd = [sys.executable, "-c", "import sys, speckle; speckle.fit_phantom(*sys.argv[1:])",
               str(png), str(ini)]  # fmt: skip
    scan_runs = [_process(scan_cmd, env) for _ in range(args.fresh)]
    fit_runs = [_process(fit_cmd, env) for _ in range(args.fresh)]
    fresh = statistics.median(w for w, _ in scan_runs)
    print()
    print(f"{'fresh process':<34}{'wall s':>9}{'CPU s':>9}{'ratio':>8}{'scanner calls':>15}")
    for name, runs, calls in (("speckle-scan (baseline)", scan_runs, 1),
                              ("fit_phantom(PNG, INI)", fit_runs, 0)):  # fmt: skip
        wall = statistics.median(w for w, _ in runs)
        cpu = statistics.median(c for _, c in runs)
        print(f"{name:<34}{wall:9.3f}{cpu:9.3f}{wall / fresh:8.2f}{calls:15d}")

    # the 2025 configuration: 601 x 975 pixels
    cfg25 = speckle.synthoct_config("2025")
    patient, _ = speckle.virtual_patient(1, config=cfg25, layers=(3, 3), shapes=("flat",))
    w25, c25, scan25 = timed(lambda: speckle.synthoct_scan(patient, cfg25), 1)
    CALLS["n"] = 0
    wall, cpu, _ = timed(lambda: speckle.fit_phantom(scan25, cfg25), 3)
    print()
    print(f"{'2025 configuration (601 x 975)':<34}{'wall s':>9}{'CPU s':>9}{'ratio':>8}"
          f"{'scanner calls':>15}")  # fmt: skip
    print(f"{'synthoct_scan (baseline)':<34}{w25:9.3f}{c25:9.3f}{1:8.2f}{1:15d}")
    print(f"{'fit_phantom':<34}{wall:9.3f}{cpu:9.3f}{wall / w25:8.2f}{CALLS['n'] // 3:15d}")

    if args.cases:
        small = speckle.ScannerConfig(n_pixels=256, n_lines=256, x_max=1536.0,
                                      n_scatterers=150_000)  # fmt: skip
        seeds = list(range(args.cases))
        rows = []
        for label, options in (
            ("synchronous", {"scheduler": "synchronous"}),
            ("threads, 2 workers", {"scheduler": "threads", "n_workers": 2}),
        ):
            CALLS["n"] = 0
            wall, cpu, ds = timed(
                lambda o=options: speckle.phantom_closed_loop(seeds, small, shapes=("flat",), **o),
                1,
            )  # fmt: skip
            rows.append((label, wall, cpu, CALLS["n"] / args.cases, ds))
        first = rows[0][1]
        print()
        print(f"{f'closed loop, {args.cases} cases 256 x 256':<34}{'wall s':>9}{'CPU s':>9}"
              f"{'ratio':>8}{'calls/case':>15}")  # fmt: skip
        for label, wall, cpu, calls, _ in rows:
            print(f"{label:<34}{wall:9.3f}{cpu:9.3f}{wall / first:8.2f}{calls:15.1f}")
        same = rows[0][4].identical(rows[1][4])
        print(f"same table on both schedulers: {same}")


if __name__ == "__main__":
    main()
