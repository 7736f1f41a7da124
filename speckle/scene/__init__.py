"""What is imaged: point scatterers (per A-line or shared), regions, deformation and mechanics.

``scatterers`` draws random scatterers for independent A-lines; ``shared`` builds one 2-D/3-D
scene that overlapping A-lines see; ``regions`` and ``layers`` describe the sample's structure
and per-region properties; ``deformation`` moves scatterers (uniform strain, translation, any
displacement field); ``mechanics`` computes such fields with finite elements (scikit-fem);
``motion`` moves scatterers in time (Brownian, ballistic, flow, bulk motion).
Names load on first use (SPEC 1, ``lazy_loader``).
"""

from .._deprecate import retired_names
from .._lazy import attach

__getattr__, __dir__, __all__ = attach(__name__, __file__)
__getattr__ = retired_names(__name__, __getattr__)
