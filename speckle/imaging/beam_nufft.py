"""Retired path (issue 32) of the private :mod:`speckle.imaging._methods.beam_nufft`.

It holds the fast beam methods. The imaging methods live in the private folder
``speckle/imaging/_methods/`` and are chosen by name (``speckle.ascan(..., method=)``,
``speckle.beam_scan(..., method=)``). Its public names:
``from speckle.imaging import beam_estimates, choose_beam_method``. Importing this path warns
once (``FutureWarning``) and gives the old module's names; it will be removed in the next
release.
"""

from .._deprecate import retired_module

__getattr__, __dir__, __all__ = retired_module(__name__, "speckle.imaging._methods.beam_nufft")
