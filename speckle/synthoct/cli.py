"""``speckle-scan CONFIG.ini SCATTERERS.txt OUTPUT.png``: the SynthOCT scanner as a command.

The official ``Part2_Scanner.exe``'s argument order and files. One call on a challenge phantom
(300,000 scatterers, 512 x 256) must stay within 2 s on an idle 2-core machine: this path
imports numpy, finufft and Pillow only (no xarray, scipy, numba or dask: checked by
``tests/synthoct/test_cli.py`` with ``python -X importtime``), parses the phantom with numpy's C
reader and compiles nothing. Also ``python -m speckle.synthoct``.

Batch mode: more ``SCATTERERS OUTPUT`` pairs after the first scan more phantoms in the same
process (same configuration), in order; the first refused phantom stops the command (the scans
before it are written).

Exit status 0 on success; 2 on a refused input (the message names the file and the line or
key), 1 on an unexpected failure.
"""

from __future__ import annotations

import argparse
import sys

from . import _scan
from .files import read_phantom_table, read_scanner_config, write_png

__all__ = ["main"]

PROG = "speckle-scan"


def _parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog=PROG,
        description="Render a SynthOCT phantom as the challenge's virtual scanner does "
        "(an open drop-in for Part2_Scanner.exe): 8-bit PNG, 51 dB.",
    )
    parser.add_argument("config", help="scanner configuration (INI, [Parameters] section)")
    parser.add_argument("scatterers", help="phantom: X Y Z (µm) Energy (%%) per line")
    parser.add_argument("output", help="output PNG (8-bit grayscale, written atomically)")
    parser.add_argument(
        "more", nargs="*", metavar="SCATTERERS OUTPUT",
        help="batch mode: further phantom/PNG pairs, scanned in the same process",
    )  # fmt: skip
    parser.add_argument("--threads", type=int, default=None, help="FINUFFT threads")
    return parser


def main(argv: list[str] | None = None) -> int:
    """Run the command; returns the exit status (see the module docstring)."""
    args = _parser().parse_args(argv)
    if args.threads is not None and args.threads < 1:
        print(f"{PROG}: error: --threads must be >= 1, got {args.threads}", file=sys.stderr)
        return 2
    if len(args.more) % 2:
        print(f"{PROG}: error: batch mode takes SCATTERERS OUTPUT pairs; "
              f"{args.more[-1]!r} has no output", file=sys.stderr)  # fmt: skip
        return 2
    jobs = [(args.scatterers, args.output), *zip(args.more[::2], args.more[1::2], strict=True)]
    try:
        config = read_scanner_config(args.config)
        for scatterers, output in jobs:
            table = read_phantom_table(scatterers, n_scatterers=config.n_scatterers)
            levels = _scan.scan_levels(table, config, nthreads=args.threads)
            write_png(levels, output)
    except (ValueError, TypeError, OSError) as err:
        print(f"{PROG}: error: {err}", file=sys.stderr)
        return 2
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
