"""Forming images: the paper's Eq. 4 (``aline``), its fast methods, the beam, B-scans and scans.

``aline.ascan`` is Eq. 4 for independent A-lines, computed by the method ``synthesis`` chooses
(direct sums, NUFFT, PSF tables); ``bscan`` stacks A-lines; ``beam.beam_scan`` images a shared
scene under a scanned, optionally focused Gaussian beam; ``scan`` ties scenes, beam and system
effects into labelled images; ``timeseries`` images moved scenes in time (M-mode,
repeated B-scans, raster timing); ``truth`` gives the speckle-free image (the expected intensity
over scatterer phases through the same spectrum and beam).
Names load on first use (SPEC 1, ``lazy_loader``).
"""

from .._deprecate import retired_names
from .._lazy import attach

__getattr__, __dir__, __all__ = attach(
    __name__,
    {
        "aline": ["ascan", "pixel_depths", "stream_ascans"],
        "beam": ["beam_scan"],
        "beam_nufft": ["beam_estimates", "choose_beam_method"],
        "bscan": ["bscan", "expected_intensity"],
        "gaussian_beam": ["Beam", "BeamScene", "beam_problem", "beam_weight"],
        "methods": ["ASCAN_METHODS", "BEAM_METHODS"],
        "scan": ["beam_reach", "image_regions", "scan_image", "scan_kernel", "scan_lines"],
        "synthesis": ["choose_method", "method_estimates"],
        "timeseries": ["bscan_series", "mmode", "raster_times"],
        "truth": ["intensity_spectrum", "speckle_free_image", "speckle_free_lines"],
    },
)
__getattr__ = retired_names(__name__, __getattr__)
