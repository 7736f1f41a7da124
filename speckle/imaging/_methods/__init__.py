"""The imaging methods (private): how Eq. 4 and the beam sum are evaluated.

One module per way of computing an A-scan or a scanned-beam image, and their kernels:
``direct`` (the exact float64 references), ``nufft`` (our folded type-1 NUFFT and FINUFFT),
``psf`` (truncated PSF tables), ``beam_nufft`` and ``beam_row`` (the fast beam scans, general
and row/raster paths), ``carrier`` (the carrier phase and wrapped positions every fast method
shares), ``_kernels`` and ``_beam_kernels`` (numba). Users choose a method by name:
``speckle.ascan(..., method=)`` and ``speckle.beam_scan(..., method=)``, from the tables of
:mod:`speckle.imaging.methods`; ``speckle.imaging.synthesis`` predicts their errors and costs.
The modules' old public paths (``speckle.imaging.<module>``) are shims that warn for a
release (``speckle._deprecate.retired_module``).
"""
