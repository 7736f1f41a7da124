"""Retired path (issue 32) of the private :mod:`speckle.imaging._bscan`.

Use ``from speckle.imaging import bscan``. Importing this path warns once (``FutureWarning``)
and gives the old module's names; ``speckle.imaging.bscan`` stays the function. The path will be
removed in the next release.
"""

from .._deprecate import retired_module

__getattr__, __dir__, __all__ = retired_module(__name__, "speckle.imaging._bscan")
