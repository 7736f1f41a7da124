"""speckle: speckle in spectral-domain OCT and its evolution under deformation.

Implements the A-scan model of Zaitsev, Matveev, Matveyev, Gelikonov & Gelikonov, "A model for
simulating speckle-pattern evolution based on close to reality procedures used in
spectral-domain OCT" (Laser Phys. Lett., 2014). Lengths are in micrometres, wavenumbers in
rad/µm.
"""

from .analysis import correlation, measured, statistics, tracking
from .analysis.correlation import compensate, correlation_map, expected_correlation, pearson
from .analysis.statistics import contrast_theory, fit_exponential, fit_rayleigh, speckle_contrast
from .analysis.strain import accumulate_strain, estimate_displacement, estimate_strain
from .analysis.tracking import track
from .imaging import scan, synthesis
from .imaging.aline import METHODS, ascan, pixel_depths
from .imaging.beam import beam_scan
from .imaging.bscan import bscan, expected_intensity
from .imaging.scan import image, image_regions, scan_lines
from .imaging.synthesis import choose_method
from .io import open_dataset, to_netcdf
from .provenance import package_version
from .scene import deformation, regions, shared
from .scene.deformation import deformable_scene, displace, translate, uniaxial_strain
from .scene.layers import layers, region_values
from .scene.mechanics import (
    compress,
    displacement_at,
    inclusion_labels,
    inclusion_strain,
    layer_strains,
    layered_labels,
)
from .scene.regions import make_regions, rasterize, region_label
from .scene.scatterers import random_scatterers
from .scene.shared import shared_scene
from .system import detection
from .system.attenuation import attenuate, attenuate_regions, attenuation_map, optical_depth
from .system.backscatter import backscatter, backscatter_regions
from .system.datasheet import EXAMPLE_SYSTEMS, System, datasheet, example_system
from .system.detection import log_compress, log_expand
from .system.noise import add_complex_noise, add_noise
from .system.phase import phase_perturb
from .system.polarization import degree_of_polarization, depolarize
from .system.rolloff import rolloff
from .system.source import delta_k, k0_from_wavelength, spectrum
from .system.spectrometer import interferogram, process, system_ascan

__version__ = package_version()

__all__ = [
    "EXAMPLE_SYSTEMS",
    "METHODS",
    "System",
    "__version__",
    "accumulate_strain",
    "add_complex_noise",
    "add_noise",
    "ascan",
    "attenuate",
    "attenuate_regions",
    "attenuation_map",
    "backscatter",
    "backscatter_regions",
    "beam_scan",
    "bscan",
    "choose_method",
    "compensate",
    "compress",
    "contrast_theory",
    "correlation",
    "correlation_map",
    "datasheet",
    "deformable_scene",
    "deformation",
    "degree_of_polarization",
    "delta_k",
    "depolarize",
    "detection",
    "displace",
    "displacement_at",
    "estimate_displacement",
    "estimate_strain",
    "example_system",
    "expected_correlation",
    "expected_intensity",
    "fit_exponential",
    "fit_rayleigh",
    "image",
    "image_regions",
    "inclusion_labels",
    "inclusion_strain",
    "interferogram",
    "k0_from_wavelength",
    "layer_strains",
    "layered_labels",
    "layers",
    "log_compress",
    "log_expand",
    "make_regions",
    "measured",
    "open_dataset",
    "optical_depth",
    "pearson",
    "phase_perturb",
    "pixel_depths",
    "process",
    "random_scatterers",
    "rasterize",
    "region_label",
    "region_values",
    "regions",
    "rolloff",
    "scan",
    "scan_lines",
    "shared",
    "shared_scene",
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
