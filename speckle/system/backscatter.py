"""Retired path (issue 32) of the private :mod:`speckle.system._backscatter`.

Use ``from speckle.system import backscatter``. Importing this path warns once (``FutureWarning``)
and gives the old module's names; ``speckle.system.backscatter`` stays the function. The path will
be removed in the next release.
"""

from .._deprecate import retired_module

__getattr__, __dir__, __all__ = retired_module(__name__, "speckle.system._backscatter")
