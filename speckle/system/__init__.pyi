"""Public names of :mod:`speckle.system` (``lazy_loader.attach_stub``, type checkers)."""

from . import attenuation as attenuation
from . import detection as detection
from . import noise as noise
from . import phase as phase
from . import polarization as polarization
from . import source as source
from . import spectrometer as spectrometer
from ._backscatter import (
    backscatter,
    backscatter_regions,
)
from ._datasheet import (
    EXAMPLE_SYSTEMS,
    System,
    datasheet,
    example_system,
)
from ._rolloff import (
    rolloff,
)
from .attenuation import (
    attenuate,
    attenuate_regions,
    attenuation_map,
    optical_depth,
)
from .detection import (
    add_floor,
    log_compress,
    log_expand,
)
from .noise import (
    add_complex_noise,
    add_noise,
)
from .phase import (
    phase_perturb,
)
from .polarization import (
    degree_of_polarization,
    depolarize,
)
from .source import (
    delta_k,
    k0_from_wavelength,
    spectrum,
    wavelength_from_k0,
)
from .spectrometer import (
    interferogram,
    interferogram_bytes,
    interpolation_gain,
    process_interferogram,
    resampling_response,
    system_ascan,
)

__all__ = [
    "EXAMPLE_SYSTEMS",
    "System",
    "add_complex_noise",
    "add_floor",
    "add_noise",
    "attenuate",
    "attenuate_regions",
    "attenuation_map",
    "backscatter",
    "backscatter_regions",
    "datasheet",
    "degree_of_polarization",
    "delta_k",
    "depolarize",
    "example_system",
    "interferogram",
    "interferogram_bytes",
    "interpolation_gain",
    "k0_from_wavelength",
    "log_compress",
    "log_expand",
    "optical_depth",
    "phase_perturb",
    "process_interferogram",
    "resampling_response",
    "rolloff",
    "spectrum",
    "system_ascan",
    "wavelength_from_k0",
]
