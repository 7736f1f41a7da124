"""Correlational speckle tracking: sub-pixel displacement estimates between two B-scans.

Each window of the reference image is registered to the same window of the deformed image with
:func:`skimage.registration.phase_cross_correlation` (upsampled DFT registration, Guizar-Sicairos
et al. 2008) -- what a user does with measured images. The estimates, interpolated to every
pixel, feed :func:`speckle.analysis.correlation.compensate` ("estimated compensation").
"""

from __future__ import annotations

import numpy as np
import xarray as xr
from scipy.interpolate import RegularGridInterpolator
from skimage.registration import phase_cross_correlation

from .._validate import as_finite_array, check_choice, check_int, check_real
from ..conventions import spacing
from .correlation import _field_of, _matched, _window, sample_field

__all__ = ["interpolate_displacement", "track"]


def track(
    reference: xr.Dataset | xr.DataArray,
    deformed: xr.Dataset | xr.DataArray,
    *,
    window: int | tuple[int, int] = (32, 16),
    step: int | tuple[int, int] = (16, 8),
    upsample: int = 20,
    oversample: int = 2,
    quantity: str = "amplitude",
    max_error: float = 0.5,
    truth: xr.Dataset | None = None,
) -> xr.Dataset:
    """Axial (and lateral) displacement of every window by sub-pixel phase correlation.

    Parameters
    ----------
    reference, deformed : xarray.Dataset or xarray.DataArray
        Complex fields with dims exactly ``(depth, aline)``, finite, on the same pixel grid
        (``ValueError`` otherwise).
    window : int or (int, int)
        Window size in pixels (depth, aline).
    step : int or (int, int)
        Distance between window centres in pixels.
    upsample : int
        Upsampling factor of the registration (precision ``1/(upsample*oversample)`` pixel).
    oversample : int
        Depth samples per pixel of the registered images (>= 1). The complex A-scans are
        interpolated exactly (:func:`speckle.analysis.correlation.sample_field`) before taking the
        amplitude: ``|A|`` has twice the field's bandwidth, so at one sample per pixel
        (rectangular spectrum) it is aliased and the estimates lock to whole pixels.
    quantity : {"amplitude", "intensity"}
        Image registered (the carrier phase is unknown in measured data, so not the field).
    max_error : float
        A window counts as failed when its estimate is more than ``max_error`` pixels from
        ``truth`` (if given); without ``truth`` the registration error metric is reported only.
    truth : xarray.Dataset, optional
        Known displacement (``uz`` in µm on the pixel grid) to score the estimates.

    Returns
    -------
    xarray.Dataset
        On window centres (dims ``depth``, ``aline`` with µm coordinates): ``uz`` and ``ux``
        (µm), ``uz_pixels``, ``registration_error`` (skimage's normalised RMS error) and,
        with ``truth``, ``uz_residual`` (pixels) and ``failed`` (bool).
    """
    check_choice(quantity, "quantity", ("amplitude", "intensity"))
    wz, wx = _window(window)
    sz, sx = _window(step, "step", low=1)
    up = check_int(upsample, "upsample", low=1)
    ov = check_int(oversample, "oversample", low=1)
    tol = check_real(max_error, "max_error", low=0, low_inclusive=False)
    ref = _field_of(reference)
    dfm = _field_of(deformed)
    for name, f in (("reference", ref), ("deformed", dfm)):
        if set(f.dims) != {"depth", "aline"}:
            raise ValueError(f"{name} must have dims exactly (depth, aline), got {f.dims}")
        as_finite_array(f.values, name, dtype=np.complex128)  # NaN/inf: cannot register
        for key in ("n_pixels", "depth_range"):
            if key not in f.attrs:
                raise ValueError(
                    f"{name} needs attribute {key!r} (a B-scan from speckle.bscan keeps it)"
                )
    _matched(ref, dfm)
    fine = np.arange(0, ref.sizes["depth"], 1 / ov)
    a = np.abs(sample_field(ref.transpose("aline", "depth").values, fine)).T
    b = np.abs(sample_field(dfm.transpose("aline", "depth").values, fine)).T
    if quantity == "intensity":
        a, b = a**2, b**2
    nz, nx = a.shape[0] // ov, a.shape[1]
    if wz > nz or wx > nx:
        raise ValueError(f"window {(wz, wx)} is larger than the image {(nz, nx)}")
    starts_z = np.arange(0, nz - wz + 1, sz)
    starts_x = np.arange(0, nx - wx + 1, sx)
    shifts = np.zeros((len(starts_z), len(starts_x), 2))
    errors = np.zeros((len(starts_z), len(starts_x)))
    for i, z0 in enumerate(starts_z):
        for j, x0 in enumerate(starts_x):
            pa = a[z0 * ov : (z0 + wz) * ov, x0 : x0 + wx]
            pb = b[z0 * ov : (z0 + wz) * ov, x0 : x0 + wx]
            # plain (not phase-normalised) cross-correlation: whitening amplifies the weak
            # high-frequency content of smooth spectra and biases the sub-pixel peak
            shift, err, _ = phase_cross_correlation(
                pa - pa.mean(), pb - pb.mean(), upsample_factor=up, normalization=None
            )
            # skimage returns the shift registering b onto a: minus the displacement
            shifts[i, j] = -np.asarray(shift) / (ov, 1)
            errors[i, j] = err
    n = int(ref.attrs["n_pixels"])
    pixel = float(ref.attrs["depth_range"]) / n
    depth = ref.depth.values
    aline = ref.aline.values
    pitch = spacing(ref, "aline", default=pixel)
    cz = depth[starts_z] + (wz - 1) / 2 * pixel
    cx = aline[starts_x] + (wx - 1) / 2 * pitch
    dims = ("depth", "aline")
    out = xr.Dataset(
        {
            "uz": (
                dims,
                shifts[..., 0] * pixel,
                {"units": "um", "long_name": "tracked axial displacement"},
            ),
            "ux": (
                dims,
                shifts[..., 1] * pitch,
                {"units": "um", "long_name": "tracked lateral displacement"},
            ),
            "uz_pixels": (dims, shifts[..., 0], {"units": "pixel"}),
            "registration_error": (
                dims,
                errors,
                {"units": "1", "long_name": "phase-correlation RMS error"},
            ),
        },
        coords={
            "depth": ("depth", cz, {"units": "um", "long_name": "window centre depth"}),
            "aline": ("aline", cx, {"units": "um", "long_name": "window centre"}),
        },
        attrs={
            "window_depth_pixels": wz,
            "window_aline_pixels": wx,
            "step_depth_pixels": sz,
            "step_aline_pixels": sx,
            "upsample": up,
            "oversample": ov,
            "quantity": quantity,
            "method": "skimage.registration.phase_cross_correlation",
        },
    )
    if truth is not None:
        exact = (
            truth["uz"].interp(depth=out.depth, aline=out.aline, kwargs={"fill_value": None})
            / pixel
        )
        resid = out["uz_pixels"] - exact
        out["uz_residual"] = resid.assign_attrs(
            units="pixel", long_name="tracked minus exact displacement"
        )
        out["failed"] = (abs(resid) > tol).assign_attrs(
            long_name=f"tracking failed (|error| > {tol:g} pixel)"
        )
        out.attrs["max_error_pixels"] = tol
    return out


def interpolate_displacement(
    tracked: xr.Dataset, depth: np.ndarray, aline: np.ndarray, *, axial_only: bool = True
) -> xr.Dataset:
    """Tracked window displacements interpolated (and extrapolated) linearly to every pixel.

    ``axial_only`` drops the lateral estimate (A-lines are independent in the model, so the
    lateral registration carries no sub-line information).
    """
    pts = np.stack(np.meshgrid(depth, aline, indexing="ij"), axis=-1)
    out = {}
    names = ("uz",) if axial_only else ("uz", "ux")
    for name in names:
        grid = (tracked.depth.values, tracked.aline.values)
        vals = tracked[name].transpose("depth", "aline").values
        if len(grid[1]) == 1:  # one window column: interpolate in depth only
            grid = (grid[0], np.array([grid[1][0] - 1.0, grid[1][0] + 1.0]))
            vals = np.repeat(vals, 2, axis=1)
        f = RegularGridInterpolator(grid, vals, bounds_error=False, fill_value=None)
        out[name] = (("depth", "aline"), f(pts), {"units": "um"})
    return xr.Dataset(
        out,
        coords={
            "depth": ("depth", np.asarray(depth, float)),
            "aline": ("aline", np.asarray(aline, float)),
        },
    )
