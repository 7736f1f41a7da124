"""Public names of :mod:`speckle.studies.phantom` (``lazy_loader.attach_stub``, type checkers)."""

from . import limits as limits
from . import loop as loop
from . import patients as patients
from ._fit import (
    PhantomFit,
    fit_phantom,
)
from ._slab import (
    slab_constants,
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

__all__ = [
    "PhantomFit",
    "fit_phantom",
    "phantom_closed_loop_case",
    "phantom_failure_map",
    "slab_constants",
    "virtual_patient",
]
