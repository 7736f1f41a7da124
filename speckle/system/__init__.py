"""The OCT system: light source and spectrum, spectrometer, noise, detection and sample optics.

``source`` gives the spectrum S(k_n) and the wavenumber grid; ``datasheet`` describes a system
from its datasheet and ``spectrometer`` follows the signal through camera, resampling and
processing; ``noise``, ``detection``, ``rolloff``, ``attenuation``, ``backscatter``,
``polarization`` and ``phase`` are the optional system and sample effects, each applied to an
image. Names load on first use (SPEC 1, ``lazy_loader``).
"""

from .._deprecate import retired_names
from .._lazy import attach

__getattr__, __dir__, __all__ = attach(
    __name__,
    {
        "attenuation": ["attenuate", "attenuate_regions", "attenuation_map", "optical_depth"],
        "backscatter": ["backscatter", "backscatter_regions"],
        "datasheet": ["EXAMPLE_SYSTEMS", "System", "datasheet", "example_system"],
        "detection": ["add_floor", "log_compress", "log_expand"],
        "noise": ["add_complex_noise", "add_noise"],
        "phase": ["phase_perturb"],
        "polarization": ["degree_of_polarization", "depolarize"],
        "rolloff": ["rolloff"],
        "source": ["delta_k", "k0_from_wavelength", "spectrum", "wavelength_from_k0"],
        "spectrometer": [
            "interferogram",
            "interferogram_bytes",
            "interpolation_gain",
            "process_interferogram",
            "resampling_response",
            "system_ascan",
        ],
    },
)
__getattr__ = retired_names(__name__, __getattr__)
