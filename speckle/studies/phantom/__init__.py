"""The SynthOCT inverse problem (issue 34): fit a digital phantom to a scan.

``_fit`` holds the flat-layer fit (:func:`fit_phantom`, :class:`PhantomFit`; its module
docstring derives the model). Names load on first use (SPEC 1, ``lazy_loader``).
"""

from ..._lazy import attach

__getattr__, __dir__, __all__ = attach(
    __name__,
    {
        "_fit": ["PhantomFit", "fit_phantom"],
        "_slab": ["slab_constants"],
        "batch": ["phantom_closed_loop"],
        "limits": ["phantom_failure_map"],
        "loop": ["phantom_closed_loop_case"],
        "patients": ["virtual_patient"],
    },
)
