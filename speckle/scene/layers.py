"""Retired path (issue 32) of the private :mod:`speckle.scene._layers`.

Use ``from speckle.scene import layer_stack``. Importing this path warns once (``FutureWarning``)
and gives the old module's names; ``speckle.scene.layers`` stays this module. The path will be
removed in the next release.
"""

from .._deprecate import retired_module

__getattr__, __dir__, __all__ = retired_module(__name__, "speckle.scene._layers")
