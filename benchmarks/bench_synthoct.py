"""Benchmark of the SynthOCT scanner drop-in: ``speckle-scan`` per challenge phantom.

Run from the repository root::

    python benchmarks/bench_synthoct.py              # 300,000 scatterers, 512 x 256
    python benchmarks/bench_synthoct.py --warm 3 --direct-lines 2

Phantom: the challenge baseline's two-layer phantom A (``speckle.baseline_phantom("layers",
"A")``, regenerated exactly), with the challenge's INI, written as files. Rows:

* ``speckle-scan`` from the command line (``python -m speckle.synthoct``, i.e. the installed
  console script's code) as a fresh process per phantom, the way a participant's search loop
  calls the official scanner: **cold** = the first call with an empty bytecode cache
  (``PYTHONPYCACHEPREFIX`` in a new folder: every module byte-compiled, as on the first call
  after installing), **warm** = the median of later fresh processes. Nothing is compiled at
  call time (no numba on this path), so cold and warm differ only by byte-compilation and
  the operating system's file cache;
* the same scan in one process (the numpy + FINUFFT core, :func:`speckle.synthoct_scan`'s);
* the same scene through the project's general beam machinery, in the same run:
  ``speckle.beam_scan`` with ``method="finufft"`` (FINUFFT 2-D type 1 with the Gaussian lateral
  transfer function) and ``method="direct"`` (the exact double sum, timed on
  ``--direct-lines`` lines and scaled to 512: it costs seconds per line), and a fresh process
  that reads the phantom with ``numpy.loadtxt``, images it with ``beam_scan(method="finufft")``
  and writes the PNG (what a script built on the package's general API costs per call: imports
  of xarray, scipy, numba...). ``beam_scan`` has no per-line shadowing: its scene carries the
  mean-field shadowing ``exp(-C(z))`` and the ``y`` weight in its amplitudes (a 2-D scene at
  ``y = 0``, waist ``sqrt(2) r``, Hann spectrum), i.e. the same work, not the same image.

Times are wall clock (median, and best) with the process CPU time; the ratio column divides by
the warm command. On a shared machine report the ratios and medians and say it was loaded.
"""

from __future__ import annotations

import argparse
import os
import statistics
import subprocess
import sys
import tempfile
import textwrap
import time
from pathlib import Path

import numpy as np
from _common import cpu_model, rel_err

import speckle
from speckle.synthoct import _scan  # private: the command's numpy core, timed alone
from speckle.synthoct.files import ScannerConfig, baseline_table

REPO = Path(__file__).resolve().parents[1]

GENERAL_API_SCRIPT = textwrap.dedent(
    """
    import sys, numpy as np, speckle
    from PIL import Image
    from speckle.synthoct import _scan  # private: the 51 dB mapping, as the command's
    t = np.loadtxt(sys.argv[2])
    cfg = speckle.read_scanner_config(sys.argv[1])
    r = cfg.beam_radius
    amp = np.sqrt(t[:, 3] / 100) * np.exp(-t[:, 1] ** 2 / r**2)
    a = speckle.beam_scan(t[:, 2], t[:, 0], amp, lines=cfg.line_positions,
                          waist=np.sqrt(2) * r, n_pixels=cfg.n_pixels,
                          depth_range=cfg.depth_range, k0=cfg.k0,
                          spectrum=np.hanning(cfg.n_pixels), method="finufft", tol=1e-4)
    Image.fromarray(_scan.to_levels(a.T), mode="L").save(sys.argv[3])
    """
)


def _process(args, env=None):
    """Wall and CPU (children) time of one fresh process."""
    c0 = os.times()
    t0 = time.perf_counter()
    r = subprocess.run(args, capture_output=True, text=True, env=env, check=False)
    wall = time.perf_counter() - t0
    c1 = os.times()
    if r.returncode != 0:
        raise RuntimeError(r.stderr)
    return wall, (c1.children_user - c0.children_user) + (c1.children_system - c0.children_system)


def _timed(func, repeat):
    walls, cpus, out = [], [], None
    for _ in range(repeat):
        t0, c0 = time.perf_counter(), time.process_time()
        out = func()
        walls.append(time.perf_counter() - t0)
        cpus.append(time.process_time() - c0)
    return walls, cpus, out


def mean_field_amplitudes(table, cfg):
    """``sqrt(E/100) exp(-y^2/r^2) exp(-C(z))``: the mean-field shadowing of the lines."""
    order = np.argsort(table[:, 2], kind="stable")
    x, y, z, e = (np.ascontiguousarray(table[order, c]) for c in range(4))
    j, line, w = _scan.beam_pairs(x, y, cfg.line_positions, 0.0, cfg.beam_radius, _scan.TOL)
    t = _scan.shadowing(z, e, j, line, w, cfg.n_lines, "mean")
    per = np.ones(z.size)
    per[j] = t
    amp = np.sqrt(e / 100) * np.exp(-(y**2) / cfg.beam_radius**2) * per
    return x, z, amp


def main():
    p = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    p.add_argument("--warm", type=int, default=5, help="warm command calls (fresh processes)")
    p.add_argument("--repeat", type=int, default=3, help="in-process repeats")
    p.add_argument("--direct-lines", type=int, default=2, help="lines of the direct sum")
    args = p.parse_args()

    cfg = ScannerConfig()
    tmp = Path(tempfile.mkdtemp(prefix="bench_synthoct_"))
    table = baseline_table("layers", 42)
    speckle.write_scanner_config(cfg, tmp / "Configuration.ini")
    speckle.write_phantom(table, tmp / "Scatterers.txt")
    files = [str(tmp / "Configuration.ini"), str(tmp / "Scatterers.txt"), str(tmp / "o.png")]
    env = {**os.environ, "PYTHONPATH": str(REPO)}
    command = [sys.executable, "-m", "speckle.synthoct", *files]

    print(f"machine: {cpu_model()}; load average {os.getloadavg()[0]:.1f} at start")
    print(f"phantom: {cfg.n_scatterers} scatterers, {cfg.n_lines} lines x {cfg.n_pixels} px\n")
    rows = []
    cold_env = {**env, "PYTHONPYCACHEPREFIX": str(tmp / "pycache")}
    cold = _process(command, cold_env)
    rows.append(("speckle-scan, cold (fresh process, empty bytecode cache)", [cold[0]], [cold[1]]))
    warm = [_process(command, env) for _ in range(args.warm)]
    rows.append(("speckle-scan, warm (fresh process)", [w for w, _ in warm], [c for _, c in warm]))
    walls, cpus, levels = _timed(lambda: _scan.scan_levels(table, cfg), args.repeat)
    rows.append(("same scan in-process (numpy + FINUFFT core)", walls, cpus))

    x, z, amp = mean_field_amplitudes(table, cfg)
    common = {
        "waist": np.sqrt(2) * cfg.beam_radius,
        "n_pixels": cfg.n_pixels,
        "depth_range": cfg.depth_range,
        "k0": cfg.k0,
        "spectrum": np.hanning(cfg.n_pixels),
    }
    walls, cpus, a_fin = _timed(
        lambda: speckle.beam_scan(
            z, x, amp, lines=cfg.line_positions, method="finufft", tol=1e-4, **common
        ),
        args.repeat,
    )
    rows.append(("project beam_scan(method='finufft'), in-process", walls, cpus))
    pick = np.linspace(0, cfg.n_lines - 1, args.direct_lines).round().astype(int)
    walls, cpus, a_dir = _timed(
        lambda: speckle.beam_scan(
            z, x, amp, lines=cfg.line_positions[pick], method="direct", **common
        ),
        1,
    )
    scale = cfg.n_lines / pick.size
    name = f"project beam_scan(method='direct'), in-process (x{scale:g} of {pick.size} lines)"
    rows.append((name, [w * scale for w in walls], [c * scale for c in cpus]))
    script = tmp / "general_api.py"
    script.write_text(GENERAL_API_SCRIPT)
    general = [_process([sys.executable, str(script), *files], env) for _ in range(2)]
    rows.append(("fresh process on the general API (loadtxt + beam_scan finufft + PNG)",
                 [w for w, _ in general], [c for _, c in general]))  # fmt: skip

    base = statistics.median(rows[1][1])
    print(f"{'path':<76} {'median s':>9} {'best s':>7} {'cpu s':>6} {'ratio':>6}")
    for name, walls, cpus in rows:
        med = statistics.median(walls)
        cpu = statistics.median(cpus)
        print(f"{name:<76} {med:9.2f} {min(walls):7.2f} {cpu:6.2f} {med / base:6.2f}")
    print(f"\nload average {os.getloadavg()[0]:.1f} at the end")
    # accuracy cross-checks: the core without shadowing against the project's direct sum
    f_none = _scan.scan_fields(table, cfg, shadow="none")[0].T  # (lines, px)
    amp0 = np.sqrt(table[:, 3] / 100) * np.exp(-(table[:, 1] ** 2) / cfg.beam_radius**2)
    d0 = speckle.beam_scan(table[:, 2], table[:, 0], amp0, lines=cfg.line_positions[pick],
                           method="direct", **common)  # fmt: skip
    print(
        f"core (shadowing off) vs project direct sum on {pick.size} lines: relative l2 "
        f"{rel_err(f_none[pick], d0):.1e}"
    )
    print(
        f"project finufft vs its direct sum (mean-field amplitudes): "
        f"{rel_err(a_fin[pick], a_dir):.1e}"
    )
    official = speckle.read_scan(REPO / "speckle/data/synthoct/Scan_Exp2_Layers_A.png")
    agreement = speckle.synthoct.scanner.scan_agreement(levels, official)
    print(f"command's scan vs the published Scan_Exp2_Layers_A: {agreement}")


if __name__ == "__main__":
    main()
