"""Public names of :mod:`speckle.imaging` (``lazy_loader.attach_stub``, type checkers)."""

from . import aline as aline
from . import beam as beam
from . import beam_lines as beam_lines
from . import gaussian_beam as gaussian_beam
from . import methods as methods
from . import scan as scan
from . import speed as speed
from . import synthesis as synthesis
from . import timeseries as timeseries
from . import truth as truth
from ._bscan import (
    bscan,
    expected_intensity,
)
from ._methods.beam_nufft import (
    beam_estimates,
    choose_beam_method,
)
from .aline import (
    ascan,
    pixel_depths,
    stream_ascans,
)
from .beam import (
    beam_scan,
)
from .gaussian_beam import (
    Beam,
    BeamScene,
    beam_problem,
    beam_weight,
)
from .methods import (
    ASCAN_METHODS,
    BEAM_METHODS,
)
from .scan import (
    beam_reach,
    image_regions,
    scan_image,
    scan_kernel,
    scan_lines,
)
from .synthesis import (
    choose_method,
    method_estimates,
)
from .timeseries import (
    bscan_series,
    mmode,
    raster_times,
)
from .truth import (
    intensity_spectrum,
    speckle_free_image,
    speckle_free_lines,
)

__all__ = [
    "ASCAN_METHODS",
    "BEAM_METHODS",
    "Beam",
    "BeamScene",
    "ascan",
    "beam_estimates",
    "beam_problem",
    "beam_reach",
    "beam_scan",
    "beam_weight",
    "bscan",
    "bscan_series",
    "choose_beam_method",
    "choose_method",
    "expected_intensity",
    "image_regions",
    "intensity_spectrum",
    "method_estimates",
    "mmode",
    "pixel_depths",
    "raster_times",
    "scan_image",
    "scan_kernel",
    "scan_lines",
    "speckle_free_image",
    "speckle_free_lines",
    "stream_ascans",
]
