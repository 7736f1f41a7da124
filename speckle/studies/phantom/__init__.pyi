"""Public names of :mod:`speckle.studies.phantom` (``lazy_loader.attach_stub``, type checkers)."""

from . import batch as batch
from . import limits as limits
from . import loop as loop
from . import patients as patients
from . import real as real
from ._fit import (
    PhantomFit,
    fit_phantom,
)
from ._slab import (
    slab_constants,
)
from .batch import (
    phantom_closed_loop,
    phantom_score_power,
)
from .limits import (
    phantom_failure_map,
)
from .loop import (
    phantom_closed_loop_case,
)
from .patients import (
    virtual_patient,
)
from .real import (
    EquivalentSystem,
    equivalent_system,
    real_tissue_phantom,
)

__all__ = [
    "EquivalentSystem",
    "PhantomFit",
    "equivalent_system",
    "fit_phantom",
    "phantom_closed_loop",
    "phantom_closed_loop_case",
    "phantom_failure_map",
    "phantom_score_power",
    "real_tissue_phantom",
    "slab_constants",
    "virtual_patient",
]
