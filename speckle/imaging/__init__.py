"""Forming images: the paper's Eq. 4 (``aline``), its fast methods, the beam, B-scans and scans.

``aline.ascan`` is Eq. 4 for independent A-lines, computed by the method ``synthesis`` chooses
(direct sums, NUFFT, PSF tables); ``bscan`` stacks A-lines; ``beam.beam_scan`` images a shared
scene under a scanned, optionally focused Gaussian beam; ``scan`` ties scenes, beam and system
effects into labelled images; ``truth`` gives the speckle-free image (the expected intensity
over scatterer phases through the same spectrum and beam).
Names load on first use (SPEC 1, ``lazy_loader``).
"""

from .._lazy import attach

__getattr__, __dir__, __all__ = attach(
    __name__,
    {
        "aline": ["METHODS", "ascan", "pixel_depths", "stream_ascans"],
        "beam": ["beam_scan"],
        "bscan": ["bscan", "expected_intensity"],
        "scan": ["image", "image_regions", "scan_lines"],
        "gaussian_beam": ["Beam"],
        "methods": ["BEAM_METHODS"],
        "synthesis": ["choose_method"],
        "truth": ["intensity_spectrum", "speckle_free_image", "speckle_free_lines"],
    },
)
