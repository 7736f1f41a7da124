"""The OCT system: light source and spectrum, spectrometer, noise, detection and sample optics.

``source`` gives the spectrum S(k_n) and the wavenumber grid; ``datasheet`` describes a system
from its datasheet and ``spectrometer`` follows the signal through camera, resampling and
processing; ``noise``, ``detection``, ``rolloff``, ``attenuation``, ``backscatter``,
``polarization`` and ``phase`` are the optional system and sample effects, each applied to an
image. Names load on first use (SPEC 1, ``lazy_loader``).
"""

from .._deprecate import retired_names
from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, __file__)
__getattr__ = retired_names(__name__, __getattr__)
