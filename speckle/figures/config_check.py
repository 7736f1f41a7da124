"""Moved to :mod:`speckle.pipeline.checks`; the old names warn (``FutureWarning``) for a release."""

from .._deprecate import moved
from ..pipeline import checks

__getattr__ = moved(
    __name__,
    checks,
    [
        "check_config",
        "check_scan_table",
        "check_sections",
        "check_twin",
        "figure_bytes",
        "tol_floor",
    ],
)
