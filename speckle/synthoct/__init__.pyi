"""Public names of :mod:`speckle.synthoct` (``lazy_loader.attach_stub``, type checkers)."""

from . import cli as cli
from . import configs as configs
from . import files as files
from . import maps as maps
from . import metrics as metrics
from . import scanner as scanner
from .configs import (
    synthoct_config,
)
from .files import (
    ScannerConfig,
    baseline_phantom,
    read_phantom,
    read_scan,
    read_scanner_config,
    write_phantom,
    write_scan,
    write_scanner_config,
)
from .maps import (
    MAP_NAMES,
    OFFICIAL_DYNAMIC_RANGE,
    SCAN_DYNAMIC_RANGE,
    SYNTHOCT_PIXEL_SIZE,
    synthoct_maps,
)
from .metrics import (
    METRIC_NAMES,
    SYNTHOCT_EXPERIMENTS,
    SYNTHOCT_MAPS,
    read_metrics_report,
    synthoct_metrics,
)
from .scanner import (
    synthoct_scan,
)

__all__ = [
    "MAP_NAMES",
    "METRIC_NAMES",
    "OFFICIAL_DYNAMIC_RANGE",
    "SCAN_DYNAMIC_RANGE",
    "SYNTHOCT_EXPERIMENTS",
    "SYNTHOCT_MAPS",
    "SYNTHOCT_PIXEL_SIZE",
    "ScannerConfig",
    "baseline_phantom",
    "read_metrics_report",
    "read_phantom",
    "read_scan",
    "read_scanner_config",
    "synthoct_config",
    "synthoct_maps",
    "synthoct_metrics",
    "synthoct_scan",
    "write_phantom",
    "write_scan",
    "write_scanner_config",
]
