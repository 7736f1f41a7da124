"""Public names of :mod:`speckle.studies.twin` (``lazy_loader.attach_stub``, type checkers)."""

from . import fit as fit
from . import system_fit as system_fit
from ._theory import (
    SPECTRUM_SHAPES,
    rectangular_weights,
)
from .fit import (
    fit_system,
)
from .system_fit import (
    SystemFit,
)

__all__ = [
    "SPECTRUM_SHAPES",
    "SystemFit",
    "fit_system",
    "rectangular_weights",
]
