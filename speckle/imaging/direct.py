"""Retired path (issue 32) of the private :mod:`speckle.imaging._methods.direct`.

It holds the exact references (``method="direct"``). The imaging methods live in the private folder
``speckle/imaging/_methods/`` and are chosen by name (``speckle.ascan(..., method=)``,
``speckle.beam_scan(..., method=)``). Importing this path warns once
(``FutureWarning``) and gives the old module's names; it will be removed in the next release.
"""

from .._deprecate import retired_module
from ._rules import METHODS_INSTEAD

__getattr__, __dir__, __all__ = retired_module(
    __name__, "speckle.imaging._methods.direct", use=METHODS_INSTEAD
)
