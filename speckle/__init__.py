"""speckle: speckle in spectral-domain OCT and its evolution under deformation.

Implements the A-scan model of Zaitsev, Matveev, Matveyev, Gelikonov & Gelikonov, "A model for
simulating speckle-pattern evolution based on close to reality procedures used in
spectral-domain OCT" (Laser Phys. Lett., 2014). Lengths are in micrometres, wavenumbers in
rad/µm.
"""

from .aline import METHODS, ascan, pixel_depths
from .bscan import bscan, expected_intensity
from .io import open_dataset, to_netcdf
from .provenance import package_version
from .scatterers import random_scatterers
from .source import delta_k, k0_from_wavelength, spectrum

__version__ = package_version()

__all__ = [
    "METHODS",
    "__version__",
    "ascan",
    "bscan",
    "delta_k",
    "expected_intensity",
    "k0_from_wavelength",
    "open_dataset",
    "pixel_depths",
    "random_scatterers",
    "spectrum",
    "to_netcdf",
]
