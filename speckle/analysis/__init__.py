"""What is measured on images: statistics, correlation, tracking, strain, measured images."""

from .correlation import (
    correlation_array,
    oversample_depth,
    resample_depth,
    sample_field,
)
from .strain import accumulate_strain, estimate_displacement, estimate_strain
from .tracking import (
    TRACK_METHODS,
    interpolate_displacement,
    interpolate_windows,
    track,
    track_array,
)

__all__ = [
    "TRACK_METHODS",
    "accumulate_strain",
    "correlation_array",
    "estimate_displacement",
    "estimate_strain",
    "interpolate_displacement",
    "interpolate_windows",
    "oversample_depth",
    "resample_depth",
    "sample_field",
    "track",
    "track_array",
]
