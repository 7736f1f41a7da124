"""Forming images: the paper's Eq. 4 (``aline``), its fast methods, the beam, B-scans and scans.

``aline.ascan`` is Eq. 4 for independent A-lines, computed by the method ``synthesis`` chooses
(direct sums, NUFFT, PSF tables: the private folder ``_methods``, whose methods are named in
the tables of ``methods``); ``bscan`` stacks A-lines; ``beam.beam_scan`` images a shared
scene under a scanned, optionally focused Gaussian beam; ``scan`` ties scenes, beam and system
effects into labelled images; ``timeseries`` images moved scenes in time (M-mode,
repeated B-scans, raster timing); ``truth`` gives the speckle-free image (the expected intensity
over scatterer phases through the same spectrum and beam).
Names load on first use (SPEC 1, ``lazy_loader``).
"""

from .._deprecate import retired_names
from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, __file__)
__getattr__ = retired_names(__name__, __getattr__)
