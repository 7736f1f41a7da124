"""Public names of :mod:`speckle.analysis` (``lazy_loader.attach_stub``, type checkers)."""

from . import autocorrelation as autocorrelation
from . import beam as beam
from . import compounding as compounding
from . import correlation as correlation
from . import correlation_forms as correlation_forms
from . import dynamics as dynamics
from . import dynamics_theory as dynamics_theory
from . import failure as failure
from . import filters as filters
from . import image_files as image_files
from . import image_quality as image_quality
from . import measured as measured
from . import phase as phase
from . import realism as realism
from . import sparse as sparse
from . import statistics as statistics
from . import strain as strain
from . import tracking as tracking
from . import twin as twin
from .compounding import (
    apodization_correlation,
    brownian_frames,
    brownian_g1,
    compound,
    compounded_contrast,
    frequency_looks,
    noisy_looks,
    split_spectrum_contrast,
    subband_apodizations,
    subband_fwhm,
)
from .correlation import (
    compensate,
    correlation_array,
    correlation_map,
    expected_correlation,
    oversample_depth,
    pearson,
    resample_depth,
    sample_field,
)
from .correlation_forms import (
    amplitude_from_gamma,
    expected_gamma,
)
from .dynamics import (
    doppler_phase,
    doppler_phase_array,
    g1,
    g1_array,
    g2,
    g2_array,
    liv,
    liv_array,
    ocds,
    ocds_array,
    speckle_variance,
    speckle_variance_array,
    ssada,
    ssada_array,
)
from .dynamics_theory import (
    doppler_shift,
    g1_axial_flow,
    g1_ballistic,
    g1_brownian,
    g1_transverse_flow,
    liv_expected,
    log_intensity_correlation,
    ocds_expected,
    siegert_g2,
    speckle_variance_expected,
    ssada_expected,
    ssada_ratio,
)
from .filters import (
    FILTERS,
    despeckle,
    filter_available,
    frost,
    kuan,
    lee,
)
from .image_quality import (
    bandlimited,
    cnr,
    edge_width,
    enl,
    peak_fwhm,
    psnr_db,
    ssim_db,
)
from .measured import (
    compare_measured,
    load_measured,
)
from .sparse import (
    depth_intensity_psf,
    log_intensity_moments,
    sparse_inverse_density,
)
from .statistics import (
    contrast_theory,
    fit_exponential,
    fit_rayleigh,
    speckle_contrast,
)
from .strain import (
    accumulate_strain,
    estimate_displacement,
    estimate_strain,
)
from .tracking import (
    TRACK_METHODS,
    interpolate_displacement,
    interpolate_windows,
    track,
    track_array,
    track_axial,
)

__all__ = [
    "FILTERS",
    "TRACK_METHODS",
    "accumulate_strain",
    "amplitude_from_gamma",
    "apodization_correlation",
    "bandlimited",
    "brownian_frames",
    "brownian_g1",
    "cnr",
    "compare_measured",
    "compensate",
    "compound",
    "compounded_contrast",
    "contrast_theory",
    "correlation_array",
    "correlation_map",
    "depth_intensity_psf",
    "despeckle",
    "doppler_phase",
    "doppler_phase_array",
    "doppler_shift",
    "edge_width",
    "enl",
    "estimate_displacement",
    "estimate_strain",
    "expected_correlation",
    "expected_gamma",
    "filter_available",
    "fit_exponential",
    "fit_rayleigh",
    "frequency_looks",
    "frost",
    "g1",
    "g1_array",
    "g1_axial_flow",
    "g1_ballistic",
    "g1_brownian",
    "g1_transverse_flow",
    "g2",
    "g2_array",
    "interpolate_displacement",
    "interpolate_windows",
    "kuan",
    "lee",
    "liv",
    "liv_array",
    "liv_expected",
    "load_measured",
    "log_intensity_correlation",
    "log_intensity_moments",
    "noisy_looks",
    "ocds",
    "ocds_array",
    "ocds_expected",
    "oversample_depth",
    "peak_fwhm",
    "pearson",
    "psnr_db",
    "resample_depth",
    "sample_field",
    "siegert_g2",
    "sparse_inverse_density",
    "speckle_contrast",
    "speckle_variance",
    "speckle_variance_array",
    "speckle_variance_expected",
    "split_spectrum_contrast",
    "ssada",
    "ssada_array",
    "ssada_expected",
    "ssada_ratio",
    "ssim_db",
    "subband_apodizations",
    "subband_fwhm",
    "track",
    "track_array",
    "track_axial",
]
