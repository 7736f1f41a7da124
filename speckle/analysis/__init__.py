"""What is measured on images: statistics, correlation, tracking, strain, measured images.

``statistics`` fits the speckle histograms and contrast; ``correlation`` maps the correlation of
two images with and without displacement compensation; ``tracking`` and ``strain`` estimate
displacement and strain (OCT elastography); ``autocorrelation``, ``beam`` and ``phase`` measure
the resolution cell and noise; ``measured`` compares a measured image with the model;
``compounding`` (averaging looks and its theory), ``filters`` (digital despeckling) and
``image_quality`` (metrics against a known truth) measure speckle suppression (a user's own
image is read by :func:`speckle.io.load_image`); ``dynamics`` computes the contrasts of speckle
in time (g1, g2, Doppler, speckle variance, SSADA, LIV, OCDS) and ``dynamics_theory`` their
expected values.
``analysis`` imports no imaging: the experiments that image scenes to study these estimators
(the twin, realism, failure maps, the compounding looks) are in :mod:`speckle.studies`.
Names load on first use (SPEC 1, ``lazy_loader``).
"""

from .._deprecate import moved, retired_names
from .._lazy import attach

_lazy_getattr, __dir__, __all__ = attach(__name__, __file__)
#: Retired names (:data:`speckle.conventions.RETIRED`) warn and resolve to the new ones.
_retired = retired_names(__name__, _lazy_getattr)
#: Names that moved to :mod:`speckle.studies` (issue 32): they warn for a release.
_moved = moved(
    __name__,
    "speckle.studies",
    [
        "SystemFit",
        "angular_looks",
        "fit_system",
        "polarization_looks",
        "spatial_looks",
        "temporal_looks",
    ],
)


#: The loader of measured images moved to :mod:`speckle.io` (issue 32): it warns for a release.
_moved_io = moved(__name__, "speckle.io", ["IMAGE_KINDS", "load_image"])


def __getattr__(name: str):
    """Lazy public names; the twin's and the loader's old names warn (``FutureWarning``)."""
    try:
        return _retired(name)
    except AttributeError:
        pass
    try:
        return _moved(name)
    except AttributeError:
        return _moved_io(name)
