"""An open drop-in for the SynthOCT 2026 challenge's virtual scanner.

The challenge's scanner (``Part2_Scanner.exe``) runs the paper's model as a closed program.
This package reads and writes its files (the INI configuration, the four-column phantom text
files and the 8-bit logarithmic PNG scans), renders the same scans from the same phantoms, and
computes the challenge's maps (attenuation, speckle contrast) and metrics. Lengths are in
micrometres. Names load on first use (SPEC 1, ``lazy_loader``).
"""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(
    __name__,
    {
        "configs": ["synthoct_config"],
        "files": [
            "ScannerConfig",
            "baseline_phantom",
            "read_phantom",
            "read_scan",
            "read_scanner_config",
            "write_phantom",
            "write_scan",
            "write_scanner_config",
        ],
        "maps": [
            "MAP_NAMES",
            "OFFICIAL_DYNAMIC_RANGE",
            "SCAN_DYNAMIC_RANGE",
            "SYNTHOCT_PIXEL_SIZE",
            "synthoct_maps",
        ],
        "metrics": [
            "METRIC_NAMES",
            "SYNTHOCT_EXPERIMENTS",
            "SYNTHOCT_MAPS",
            "read_metrics_report",
            "synthoct_metrics",
        ],
        "scanner": ["synthoct_scan"],
    },
)
