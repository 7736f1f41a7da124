"""speckle: speckle in spectral-domain OCT and its evolution under deformation.

Implements the A-scan model of Zaitsev, Matveev, Matveyev, Gelikonov & Gelikonov, "A model for
simulating speckle-pattern evolution based on close to reality procedures used in
spectral-domain OCT" (Laser Phys. Lett., 2014). Lengths are in micrometres, wavenumbers in
rad/µm.

The package follows the flow of a simulation: ``scene`` (what is imaged) and ``system`` (the
OCT system) feed ``imaging`` (Eq. 4 and its fast methods, the beam, scans), whose images
``analysis`` measures (statistics, correlation, tracking, strain); ``studies`` runs experiments
on those methods, ``synthoct`` is an open drop-in for the SynthOCT challenge's scanner,
``figures`` draws and ``pipeline`` connects a config file to all of it.
``io`` reads and writes NetCDF atomically; ``sweep`` runs parameter sweeps on Dask.

The top level gathers the functions and classes of the subpackages' ``__all__`` (each
subpackage lists its own), and loads each on first use (scientific Python's SPEC 1, through
``lazy_loader``): ``import speckle`` imports neither numba nor dask nor scikit-fem.
"""

from . import analysis, imaging, scene, studies, synthoct, system
from ._deprecate import retired_names
from ._lazy import gather

#: Subpackages whose public names the top level gathers, in the order of the flow.
_GROUPS = {
    "scene": scene,
    "system": system,
    "imaging": imaging,
    "analysis": analysis,
    "studies": studies,
    "synthoct": synthoct,
}
#: Top-level infrastructure modules and the names they contribute (``speckle.sweep`` is the
#: module of the Dask sweeps; its function is ``speckle.sweep.sweep``).
_INFRASTRUCTURE = {
    "io": ["IMAGE_KINDS", "load_image", "open_dataset", "stream_to_netcdf", "to_netcdf"]
}

_lazy_getattr, _lazy_dir, _names = gather(
    __name__, {**{name: mod.__all__ for name, mod in _GROUPS.items()}, **_INFRASTRUCTURE}
)
#: Retired names (``speckle.METHODS``, ``speckle.image``, ...) warn and resolve to the new ones.
_retired_getattr = retired_names(__name__, _lazy_getattr)
#: Functions, classes and constants only (subpackages and modules are reached as attributes).
__all__ = ["__version__", *_names]


def __getattr__(name: str):
    """Load a public name on first use (lazy_loader's, plus ``__version__``)."""
    if name == "__version__":
        from .provenance import package_version

        return package_version()
    return _retired_getattr(name)


def __dir__() -> list[str]:
    return sorted({*__all__, *_lazy_dir()})


del analysis, gather, imaging, retired_names, scene, studies, synthoct, system
