"""Public names of :mod:`speckle.studies` (``lazy_loader.attach_stub``, type checkers)."""

from . import dynamics as dynamics
from . import dynamics_series as dynamics_series
from . import failure as failure
from . import looks as looks
from . import phantom as phantom
from . import realism as realism
from . import speed as speed
from . import suppression as suppression
from . import twin as twin
from .dynamics import (
    FLOW_CONTRASTS,
    contrast_estimates,
    contrast_floors,
    decorrelation_calibration,
    expected_contrast,
    flow_failure,
    velocity_range,
)
from .dynamics_series import (
    g1_curves,
    phantom_series,
)
from .looks import (
    angular_looks,
    polarization_looks,
    spatial_looks,
    temporal_looks,
)
from .phantom import (
    EquivalentSystem,
    PhantomFit,
    equivalent_system,
    fit_phantom,
    phantom_closed_loop,
    phantom_closed_loop_case,
    phantom_failure_map,
    phantom_score_power,
    real_tissue_phantom,
    virtual_patient,
)
from .twin import (
    SystemFit,
    fit_system,
)

__all__ = [
    "FLOW_CONTRASTS",
    "EquivalentSystem",
    "PhantomFit",
    "SystemFit",
    "angular_looks",
    "contrast_estimates",
    "contrast_floors",
    "decorrelation_calibration",
    "equivalent_system",
    "expected_contrast",
    "fit_phantom",
    "fit_system",
    "flow_failure",
    "g1_curves",
    "phantom_closed_loop",
    "phantom_closed_loop_case",
    "phantom_failure_map",
    "phantom_score_power",
    "phantom_series",
    "polarization_looks",
    "real_tissue_phantom",
    "spatial_looks",
    "temporal_looks",
    "velocity_range",
    "virtual_patient",
]
