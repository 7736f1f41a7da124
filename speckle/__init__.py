"""speckle: speckle in spectral-domain OCT and its evolution under deformation.

Implements the A-scan model of Zaitsev, Matveev, Matveyev, Gelikonov & Gelikonov, "A model for
simulating speckle-pattern evolution based on close to reality procedures used in
spectral-domain OCT" (Laser Phys. Lett., 2014). Lengths are in micrometres, wavenumbers in
rad/µm.
"""

from . import correlation, deformation, detection, measured, statistics, synthesis, tracking
from .aline import METHODS, ascan, pixel_depths
from .bscan import bscan, expected_intensity
from .correlation import compensate, correlation_map, expected_correlation, pearson
from .deformation import deformable_scene, displace, translate, uniaxial_strain
from .io import open_dataset, to_netcdf
from .provenance import package_version
from .scatterers import random_scatterers
from .source import delta_k, k0_from_wavelength, spectrum
from .statistics import contrast_theory, fit_exponential, fit_rayleigh, speckle_contrast
from .synthesis import choose_method
from .system.datasheet import EXAMPLE_SYSTEMS, System, datasheet, example_system
from .system.spectrometer import interferogram, process, system_ascan
from .tracking import track

__version__ = package_version()

__all__ = [
    "EXAMPLE_SYSTEMS",
    "METHODS",
    "System",
    "__version__",
    "ascan",
    "bscan",
    "choose_method",
    "compensate",
    "contrast_theory",
    "correlation",
    "correlation_map",
    "datasheet",
    "deformable_scene",
    "deformation",
    "delta_k",
    "detection",
    "displace",
    "example_system",
    "expected_correlation",
    "expected_intensity",
    "fit_exponential",
    "fit_rayleigh",
    "interferogram",
    "k0_from_wavelength",
    "measured",
    "open_dataset",
    "pearson",
    "pixel_depths",
    "process",
    "random_scatterers",
    "speckle_contrast",
    "spectrum",
    "statistics",
    "synthesis",
    "system_ascan",
    "to_netcdf",
    "track",
    "tracking",
    "translate",
    "uniaxial_strain",
]
