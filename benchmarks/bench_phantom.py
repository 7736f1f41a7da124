"""Benchmark of ``speckle.fit_phantom`` on challenge-size scans (512 x 256).

Run from the repository root::

    python benchmarks/bench_phantom.py            # the four published scans, 5 repeats

Rows: the fit of each published scan (``Scan_Exp*_{A,B}.png``, the challenge's INI), the
fitted phantom drawn (``PhantomFit.phantom``) and scanned (``PhantomFit.render``), and, as
the baseline measured in the same process, one scan of the baseline's two-layer phantom A by
:func:`speckle.synthoct_scan` (what one call of the official scanner costs a participant's
search loop). The fit is analytic: it calls the scanner zero times (counted by wrapping the
scanner's core); ``render`` calls it once. Times are wall-clock medians with the process CPU
time; the ratio divides by the baseline scan. On a shared machine report the ratios.
"""

from __future__ import annotations

import argparse
import statistics
import time
from importlib.resources import files

from _common import cpu_model

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


if __name__ == "__main__":
    main()
