"""Forming images: the paper's Eq. 4 (``aline``), its fast methods, the beam, B-scans.

Also the speckle-free image (``truth``): the expected intensity over scatterer phases through
the same spectrum and beam. Names in ``__all__`` are imported on first use.
"""

import importlib

#: Public name -> module of this subpackage that defines it (imported on first access).
_LAZY = {
    "intensity_spectrum": "truth",
    "speckle_free_image": "truth",
    "speckle_free_lines": "truth",
}

__all__ = sorted(_LAZY)


def __getattr__(name: str):
    if name in _LAZY:
        return getattr(importlib.import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
