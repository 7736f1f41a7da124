"""What is measured on images: statistics, correlation, tracking, strain, measured images.

Also speckle suppression: physical compounding (``compounding``), digital filters
(``filters``) and image-quality metrics against a known truth (``image_quality``). Their
public names are listed in ``__all__`` and imported on first use.
"""

import importlib

#: Public name -> module of this subpackage that defines it (imported on first access).
_LAZY = {
    **{
        name: "compounding"
        for name in (
            "AVERAGING",
            "WINDOWS",
            "angular_looks",
            "brownian_frames",
            "brownian_g1",
            "compound",
            "compounded_contrast",
            "frequency_looks",
            "noisy_looks",
            "polarization_looks",
            "spatial_looks",
            "split_spectrum_contrast",
            "subband_fwhm",
            "subband_windows",
            "temporal_looks",
            "window_correlation",
        )
    },
    **{
        name: "filters"
        for name in (
            "DOMAINS",
            "FILTERS",
            "check_filter",
            "despeckle",
            "filter_available",
            "frost",
            "kuan",
            "lee",
        )
    },
    **{
        name: "image_quality"
        for name in (
            "bandlimited",
            "cnr",
            "contrast",
            "edge_width",
            "enl",
            "peak_fwhm",
            "psnr_db",
            "ssim_db",
            "time_per_megapixel",
            "to_db",
        )
    },
}

__all__ = sorted(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
