"""Accuracy of the FE phantoms (speckle.compress_phantom): a stiff circular inclusion against
Eshelby.

Run from the repository root (~2 min on 2 cores)::

    python benchmarks/mechanics_accuracy.py

Prints the relative error of the strain inside the inclusion (mean over pixels within R/2 of
its centre, against :func:`speckle.inclusion_strain`) versus the inclusion radius in pixels
(worst and mean over 4 sub-pixel positions of the circle on the pixel grid), versus the plate
size (finite-domain error) and versus the Poisson ratio (locking), and the time per solve.
The phantom is the one of ``tests/scene/test_mechanics.py`` (its helper is imported from there).
"""

from __future__ import annotations

import pathlib
import sys
import time

import numpy as np

sys.path.insert(0, str(pathlib.Path(__file__).resolve().parents[1] / "tests" / "scene"))
from test_mechanics import inclusion_error

OFFSETS = [(0.0, 0.0), (0.5, 0.0), (0.5, 0.5), (0.25, 0.25)]


def main() -> None:
    print("radius (px) | worst |err| | mean err zz | mean err xx | s per solve")
    for n in (4, 8, 16, 32):
        t0 = time.perf_counter()
        err = np.array([inclusion_error(n, o) for o in OFFSETS])
        dt = (time.perf_counter() - t0) / len(OFFSETS)
        worst, zz, xx = np.abs(err).max(), err[:, 0].mean(), err[:, 1].mean()
        print(f"{n} | {worst:.4f} | {zz:+.4f} | {xx:+.4f} | {dt:.1f}")
    print("plate / R (R = 16 px) | mean err zz | mean err xx")
    for plate in (10, 20, 40, 80):
        err = np.array([inclusion_error(16, o, plate=plate) for o in OFFSETS])
        print(f"{plate} | {err[:, 0].mean():+.4f} | {err[:, 1].mean():+.4f}")
    print("nu (R = 8, 16, 32 px, offset 0.25 px) | err zz, err xx")
    for nu in (0.3, 0.45, 0.49, 0.499, 0.49999):
        err = [inclusion_error(n, (0.25, 0.25), nu=nu) for n in (8, 16, 32)]
        print(nu, "|", ", ".join(f"({a:+.4f}, {b:+.4f})" for a, b in err))


if __name__ == "__main__":
    main()
