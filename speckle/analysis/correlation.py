"""Correlation between a reference and a deformed B-scan, displacement compensation and theory.

Compensation
------------
An A-scan of Eq. 4 is a trigonometric polynomial in depth, ``A(y) = sum_n F_n exp(-2i pi n
y/N)`` (``F_n`` exactly from the ``N`` pixels by an inverse DFT). *Exact compensation*
evaluates the deformed A-scan where each reference pixel's material point went, ``y = q +
u_z(z_q)/p`` (``p = H/N``), and removes the carrier ``exp(2i k0 u_z)`` of a moved scatterer
(a rigid shift then gives back the reference exactly).

Correlation
-----------
Pearson correlation of ``|A|^2``, ``|A|`` or the complex field (modulus), over the whole area
(:func:`pearson`) or in sliding ``(depth, x)`` windows (:func:`correlation_map`).

Theory (:func:`expected_correlation`)
-------------------------------------
Campbell's theorem for Poisson scatterers: the Siegert part ``|gamma|^2`` plus an incoherent
floor (docs/explanation/correlation.md); rectangular spectrum, exact compensation of strain
``s``: ``gamma(s) = max(0, 1 - s/2 - R s) / sqrt(1 - s)`` (``R = k0/delta_k``).
"""

from __future__ import annotations

import inspect

import numpy as np
import scipy.fft as sfft
import xarray as xr
from scipy import ndimage

from .._deprecate import keyword_only, moved
from .._validate import check_bool, check_choice, check_int, check_real
from .._wrap import ArraySpec, preprocess_and_wrap
from ..conventions import attrs, canonical_dims, coord, grid
from ..system.source import index_shift_phase, spectral_index
from ._common import DEPTH, LATERAL, grid_spacing, matched, parse_window, same_grid
from ._kernels import lagrange_resample
from .correlation_forms import amplitude_from_gamma

__all__ = [
    "KINDS",
    "compensate",
    "correlation_array",
    "correlation_map",
    "expected_correlation",
    "kernel",
    "oversample_depth",
    "pearson",
    "resample_depth",
    "sample_field",
]

#: Correlated quantities.
KINDS = ("intensity", "amplitude", "complex")
#: A labelled B-scan (field or a B-scan's ``field``), (..., depth, x), NaN allowed, labelled.
_SCAN = ArraySpec(
    dims=(DEPTH, LATERAL),
    extra_dims=True,
    labelled=True,
    variable="field",
    keep_labels=True,
    finite=False,
)
#: A source spectrum (:func:`speckle.spectrum`), passed labelled (its attrs give ``k0_dk``).
_SPECTRUM = ArraySpec(kind="real", dims=("wavenumber",), labelled=True, keep_labels=True)
#: Strains of the theory: real, finite, at least one.
_STRAIN = ArraySpec(kind="real")
#: Largest number of complex phase factors held in memory at once by :func:`sample_field`.
CHUNK_ELEMENTS = 1 << 22


@preprocess_and_wrap(
    checks={"field": ArraySpec(ndim=tuple(range(1, 33))), "positions": ArraySpec(kind="real")}
)
def sample_field(field: object, positions: object) -> np.ndarray:
    """Evaluate band-limited A-scans at real pixel positions (exact trigonometric interpolation).

    Parameters
    ----------
    field : array_like, shape (..., N)
        Complex A-scans at integer pixels ``q = 0 ... N-1`` (from :func:`speckle.ascan`).
    positions : array_like, shape (..., P)
        Pixel positions (real, in pixels) at which to evaluate each A-scan; broadcast against
        the leading dims of ``field``.

    Returns
    -------
    numpy.ndarray, shape (..., P)
        ``A(y) = sum_n F_n exp(-2i pi n y/N)``: equals ``field`` at integer ``y``, and Eq. 4
        evaluated at the pixel depth ``z_q = y H/N`` otherwise.

    Examples
    --------
    >>> import speckle
    >>> field = np.exp(2j * np.pi * np.arange(8) / 8)  # A(y) = exp(2i pi y/8), one component
    >>> speckle.sample_field(field, [0.5]).round(4)  # between pixels: exp(i pi/8)
    array([0.9239+0.3827j])
    """
    a = np.asarray(field, dtype=np.complex128)  # checked: numeric, finite, not empty
    y = np.asarray(positions, dtype=float)
    n = a.shape[-1]
    shift = n // 2
    spec = np.fft.ifft(a * index_shift_phase(n, -np.arange(n)), axis=-1)  # F_n, n=-(N//2)...
    batch = np.broadcast_shapes(a.shape[:-1], y.shape[:-1])
    spec = np.broadcast_to(spec, (*batch, n)).reshape(-1, n)
    yy = np.broadcast_to(y, (*batch, y.shape[-1])).reshape(-1, y.shape[-1])
    if yy.shape[0] > 1 and np.all(yy == yy[:1]):
        yy = yy[:1]  # same positions on every line (e.g. uniaxial strain): one phase table
    # reduce y mod N first: the polynomial has period N and small arguments stay accurate
    w = np.exp(-2j * np.pi * np.mod(yy, n) / n)
    out = _horner(spec, w) * w ** (-shift)
    return np.broadcast_to(out, (spec.shape[0], yy.shape[1])).reshape(*batch, y.shape[-1])


@keyword_only("axis")
@preprocess_and_wrap(checks={"field": ArraySpec(ndim=tuple(range(1, 33)))})
def oversample_depth(field: np.ndarray, factor: int, *, axis: int = 0) -> np.ndarray:
    """Complex A-scans (depth on ``axis``) at ``factor`` samples per pixel, exactly.

    ``A(y) = sum_n F_n exp(-2i pi n y/N)`` (``n = -(N//2) ... N-1-N//2``, as
    :func:`sample_field`) at ``y = q/factor``: the spectrum zero-padded to ``factor*N`` points.
    Equals ``field`` at whole pixels. Computed in complex64 for a complex64 ``field``, in
    complex128 otherwise.

    Examples
    --------
    >>> import speckle
    >>> field = np.exp(-2j * np.pi * np.arange(8) / 8)
    >>> fine = speckle.oversample_depth(field, 2)
    >>> fine.shape, np.allclose(fine[::2], field)
    ((16,), True)
    """
    a = np.asarray(field)
    a = a if a.dtype == np.complex64 else a.astype(np.complex128)
    f = check_int(factor, "factor", low=1)
    if f == 1:
        return a
    ax = axis % a.ndim
    n = a.shape[ax]
    # the transforms run along ``axis`` in the input's own layout (no moved, strided copies);
    # norm="forward" puts the 1/N on the forward transform: the zero-padded inverse needs no
    # rescaling pass
    spec = sfft.fft(a, axis=ax, norm="forward")  # spec[m] = F_{-m}: model index -n at m mod N
    shape = list(a.shape)
    shape[ax] = f * n
    pad = np.zeros(shape, dtype=a.dtype)
    neg = n // 2  # model indices -1 ... -(N//2) sit at m = 1 ... N//2
    pos = n - 1 - neg  # model indices 1 ... N-1-N//2 sit at m = N-1 ... N//2+1

    def at(sl: slice) -> tuple:
        return (slice(None),) * ax + (sl,)

    pad[at(slice(0, neg + 1))] = spec[at(slice(0, neg + 1))]
    if pos:
        pad[at(slice(f * n - pos, None))] = spec[at(slice(n - pos, None))]
    return sfft.ifft(pad, axis=ax, norm="forward", overwrite_x=True)


#: Oversampling of :func:`resample_depth` (samples per pixel).
RESAMPLE_OVERSAMPLE = 4


@preprocess_and_wrap(
    checks={
        "field": ArraySpec(kind="complex", ndim=2),
        "positions": ArraySpec(kind="real", ndim=2),
    }
)
def resample_depth(field: object, positions: object) -> np.ndarray:
    """Complex image ``(depth, x)`` evaluated at real depth positions, every A-line at once.

    The band-limited interpolant of :func:`sample_field` (periodic in depth with period
    ``N``), computed fast: the A-lines are oversampled exactly ``RESAMPLE_OVERSAMPLE`` = 4 times
    (:func:`oversample_depth`) and interpolated there by an 8-point Lagrange polynomial
    (:data:`~speckle.analysis._kernels.LAGRANGE_TAPS`). Its error is at most
    ``sum_n |F_n| e(2 pi n / 4N)``, with ``e(omega)`` the largest error of the polynomial for
    ``exp(i omega s)`` between two samples (every frequency's worst error added in phase):
    measured 3e-6 of the peak amplitude for a Gaussian spectrum of FWHM half the band, 2e-5
    for a rectangular one (tested against :func:`sample_field` and the bound). Cost
    ``O(N M log N)`` instead of ``O(N^2 M)``.

    Parameters
    ----------
    field : array_like, shape (N, M)
        Complex image (axis 0 = depth in pixels).
    positions : array_like, shape (N, M)
        Depth position (pixels) at which pixel ``(q, j)`` takes its value from A-line ``j``.

    Returns
    -------
    numpy.ndarray, shape (N, M)
        Pixel ``(q, j)``: A-line ``j`` evaluated at depth ``positions[q, j]``.

    Examples
    --------
    >>> import speckle
    >>> field = np.exp(-2j * np.pi * np.arange(8) / 8)[:, None]  # (depth, line)
    >>> np.allclose(speckle.resample_depth(field, np.arange(8.0)[:, None]), field)
    True
    """
    a, y = field, positions  # checked: complex 2-D image, finite real positions
    if y.shape != a.shape:
        raise ValueError(f"positions must have the field's shape {a.shape}, got {y.shape}")
    # single precision: 1e-7 relative, far below the interpolation error
    fine = inspect.unwrap(oversample_depth)(  # the numpy body: the field is checked
        np.ascontiguousarray(a.T, dtype=np.complex64), RESAMPLE_OVERSAMPLE, axis=-1
    )
    out = np.empty(a.shape[::-1], dtype=np.complex128)  # (aline, depth): each A-line contiguous
    positions = np.ascontiguousarray(np.asarray(y, dtype=float).T)  # (aline, depth), as ``fine``
    lagrange_resample(fine, positions, RESAMPLE_OVERSAMPLE, out)
    return out.T


def _horner(coef: np.ndarray, w: np.ndarray) -> np.ndarray:
    """``sum_m coef[..., m] w^m`` by Horner's rule (stable for ``|w| = 1``).

    ``coef`` has shape (B, N) and ``w`` shape (B or 1, P); returns shape (B, P).
    """
    acc = np.zeros((coef.shape[0], w.shape[1]), dtype=np.complex128)
    for m in range(coef.shape[1] - 1, -1, -1):
        acc *= w
        acc += coef[:, m, None]
    return acc


@preprocess_and_wrap(checks={"deformed": _SCAN})
def compensate(
    deformed: xr.Dataset | xr.DataArray,
    displacement: xr.Dataset,
    *,
    carrier: bool = True,
) -> xr.DataArray:
    """Displacement-compensated deformed field, on the reference pixel grid.

    Parameters
    ----------
    deformed : xarray.Dataset or xarray.DataArray
        Deformed B-scan (from :func:`speckle.bscan`) with dims ``(..., depth, x)``: the
        pixel size and A-line pitch are read from its ``depth`` and ``x`` coordinates
        (uniform, µm; never from attributes), the carrier from attribute ``k0`` (rad/µm).
    displacement : xarray.Dataset
        ``uz`` (optionally ``ux``), µm, on the pixel grid of ``deformed`` (dims ``depth``, ``x``
        or the scene's ``aline``, and extra dims of ``deformed``), e.g. from
        :func:`speckle.scene.deformation.pixel_displacement` or :func:`speckle.track`.
    carrier : bool
        Remove the carrier ``exp(2i k0 u_z)`` of moved scatterers (complex correlation).

    Returns
    -------
    xarray.DataArray
        ``A'(q + u_z/p) exp(-2i k0 u_z)``; ``ux``: from the line nearest ``x + u_x`` (or NaN).

    Raises
    ------
    ValueError
        A missing or non-uniform ``depth``/``x`` coordinate, no ``k0`` with ``carrier=True``,
        a displacement on another grid.

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(64, 512.0, k0_dk=10.0)
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=64, depth_range=512.0, seed=1)
    >>> moved = speckle.bscan(speckle.translate(scene, 3.0, wrap=True), src)
    >>> uz = xr.DataArray(np.full(64, 3.0), dims="depth", coords={"depth": moved.depth})
    >>> back = speckle.compensate(moved, xr.Dataset({"uz": uz}))
    >>> ref = speckle.bscan(scene, src)
    >>> round(float(speckle.pearson(ref, back, kind="complex")), 3)
    1.0
    """
    field = deformed  # the B-scan's field, labelled (the decorator)
    carrier = check_bool(carrier, "carrier")
    from ..scene.deformation import check_field  # local: deformation imports nothing here

    if not isinstance(displacement, xr.Dataset):
        raise TypeError(
            "displacement must be an xarray.Dataset with 'uz' (µm), got "
            f"{type(displacement).__name__}"
        )
    displacement = canonical_dims(displacement, "displacement")  # (depth, aline): x, warning
    check_field(displacement, extra_dims=[d for d in field.dims if d != "depth"])
    pixel, pitch = grid_spacing(field)  # from the coordinates, refused if missing/non-uniform
    k0 = grid(field).k0  # the central wavenumber in the medium (attribute k0), or None
    if carrier and k0 is None:
        raise ValueError(
            "deformed needs attribute k0 (rad/µm) to remove the carrier phase, as a B-scan "
            "from speckle.bscan has (or pass carrier=False)"
        )
    for name in ("uz", "ux"):
        if name in displacement:
            same_grid(field, displacement[name], ("deformed", f"displacement {name}"))
    n = field.sizes["depth"]
    uz = displacement["uz"].broadcast_like(field.real).transpose(*field.dims)
    q = xr.DataArray(np.arange(n, dtype=float), dims="depth")
    pos = (q + uz / pixel).transpose(*field.dims)
    other = [d for d in field.dims if d != "depth"]
    f_np = field.transpose(*other, "depth").values
    p_np = pos.transpose(*other, "depth").values
    out = sample_field.__wrapped__(f_np, p_np)  # the numpy body: both checked
    if carrier:
        out = out * np.exp(-2j * k0 * uz.transpose(*other, "depth").values)
    result = xr.DataArray(out, dims=(*other, "depth"), coords=field.coords).transpose(*field.dims)
    if "ux" in displacement and np.any(displacement["ux"].values != 0):
        result = _lateral(result, displacement["ux"].broadcast_like(field.real), pitch)
    result.attrs = {**field.attrs, "compensation": "exact" if carrier else "exact, no carrier"}
    return result


def _lateral(field: xr.DataArray, ux: xr.DataArray, pitch: float) -> xr.DataArray:
    """Take each pixel from the A-line nearest to its laterally displaced material point
    (``pitch``: the A-line pitch in µm)."""
    aline = field.x.values
    f = field.transpose(..., "x").values
    u = ux.transpose(*field.transpose(..., "x").dims).values
    src = np.arange(len(aline)) + np.rint(u / pitch).astype(int)
    ok = (src >= 0) & (src < len(aline))
    taken = np.take_along_axis(f, np.clip(src, 0, len(aline) - 1), axis=-1)
    taken = np.where(ok, taken, np.nan + 0j)
    dims = field.transpose(..., "x").dims
    return xr.DataArray(taken, dims=dims, coords=field.coords).transpose(*field.dims)


def _quantity(field: xr.DataArray, kind: str) -> xr.DataArray:
    if kind == "intensity":
        return abs(field) ** 2
    if kind == "amplitude":
        return abs(field)
    return field


@preprocess_and_wrap(checks={"reference": _SCAN, "deformed": _SCAN})
def pearson(
    reference: xr.Dataset | xr.DataArray,
    deformed: xr.Dataset | xr.DataArray,
    *,
    kind: str = "intensity",
    dims: tuple[str, ...] = ("depth", "x"),
) -> xr.DataArray:
    """Pearson correlation over ``dims`` (the whole scan area by default).

    Parameters
    ----------
    reference, deformed : xarray.Dataset or xarray.DataArray
        Complex fields (B-scan datasets or field DataArrays) on the same pixel grid (shared
        dims of equal size and coordinates, else ``ValueError``); NaN pixels are left out.
    kind : {"intensity", "amplitude", "complex"}
        Correlated quantity; ``"complex"`` returns the modulus of the complex coefficient.
    dims : tuple of str
        Dims averaged over; the others (e.g. ``strain``) are kept.

    Examples
    --------
    >>> import speckle
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> img = speckle.bscan(scene, speckle.spectrum(32, 256.0, k0_dk=10.0))
    >>> float(speckle.pearson(img, img))
    1.0
    """
    check_choice(kind, "kind", KINDS)
    x = _quantity(reference, kind)
    y = _quantity(deformed, kind)
    x, y = matched(x, y)
    names = (dims,) if isinstance(dims, str) else dims
    if not isinstance(names, (tuple, list)) or not names:
        raise TypeError(f"dims must be a dim name or a tuple of them, got {dims!r}")
    unknown = [d for d in names if d not in x.dims]
    if unknown:
        raise ValueError(f"dims {unknown} are not dims of the images; they have {x.dims}")
    ok = np.isfinite(abs(x)) & np.isfinite(abs(y))
    x, y = x.where(ok), y.where(ok)
    dx = x - x.mean(dims)
    dy = y - y.mean(dims)
    cov = (dx * np.conj(dy)).mean(dims)
    r = abs(cov) / np.sqrt((abs(dx) ** 2).mean(dims) * (abs(dy) ** 2).mean(dims))
    if kind != "complex":
        r = cov.real / np.sqrt((dx**2).mean(dims) * (dy**2).mean(dims))
    return r.assign_attrs(attrs("correlation", f"{kind} correlation coefficient", kind=kind))


def _numeric(v: object, name: str) -> np.ndarray:
    """``v`` as a numeric (real or complex) array; NaN allowed (it blanks its windows)."""
    a = np.asarray(v)
    if a.dtype.kind not in "fciu":
        raise TypeError(f"{name} must be a numeric array, got dtype {a.dtype}")
    return a


@preprocess_and_wrap(
    checks={"x": ArraySpec(finite=False), "y": ArraySpec(finite=False, same_as="x")}
)
def correlation_array(
    x: np.ndarray,
    y: np.ndarray,
    window: tuple[int, int],
    *,
    axes: tuple[int, int] = (0, 1),
    modulus: bool = False,
) -> np.ndarray:
    """Sliding-window Pearson correlation of two arrays (numpy core of :func:`correlation_map`).

    Parameters
    ----------
    x, y : numpy.ndarray
        Real or complex arrays of the same shape (NaN pixels allowed).
    window : (int, int)
        Window (pixels) along ``axes`` (depth, x).
    axes : (int, int)
        Axes of depth and aline.
    modulus : bool
        Complex data: modulus of the complex coefficient (else its real part).

    Returns
    -------
    numpy.ndarray
        Coefficient at each window centre (pixel ``c`` holds the window starting at
        ``c - w//2``); NaN where the window does not fit or holds a NaN pixel of either array.

    Examples
    --------
    >>> import speckle
    >>> x = np.random.default_rng(0).normal(size=(32, 16))
    >>> c = speckle.correlation_array(x, x, (8, 4))
    >>> float(np.nanmax(c)), c.shape
    (1.0, (32, 16))
    """
    x, y = (_numeric(v, n) for v, n in ((x, "x"), (y, "y")))
    if x.shape != y.shape:
        raise ValueError(f"x and y must have the same shape, got {x.shape} and {y.shape}")
    if isinstance(window, str | bytes) or np.ndim(window) != 1 or len(window) != 2:
        raise TypeError(f"window must be a pair (depth, x) of pixel counts, got {window!r}")
    wz, wx = (check_int(w, f"window[{i}]", low=1) for i, w in enumerate(window))
    modulus = check_bool(modulus, "modulus")
    if x.ndim < 2 or min(x.shape[axes[0]], x.shape[axes[1]]) < 1:
        raise ValueError(f"x and y must hold a 2-D image along axes {axes}, got shape {x.shape}")
    size = [1] * x.ndim
    size[axes[0]], size[axes[1]] = wz, wx
    xv, yv = x, y
    bad = ~(np.isfinite(xv) & np.isfinite(yv))
    if bad.any():  # zero them so that they do not spread through the running sums
        xv, yv = np.where(bad, 0, xv), np.where(bad, 0, yv)

    def local_mean(v: np.ndarray) -> np.ndarray:
        if np.iscomplexobj(v):
            return local_mean(v.real) + 1j * local_mean(v.imag)
        return ndimage.uniform_filter(v, size=size, mode="nearest")

    mx, my = local_mean(xv), local_mean(yv)
    cov = local_mean(xv * np.conj(yv)) - mx * np.conj(my)
    vx = local_mean(np.abs(xv) ** 2) - np.abs(mx) ** 2
    vy = local_mean(np.abs(yv) ** 2) - np.abs(my) ** 2
    with np.errstate(invalid="ignore", divide="ignore"):
        r = (np.abs(cov) if modulus else cov.real) / np.sqrt(vx * vy)
    valid = np.zeros(x.shape, bool)
    sl = [slice(None)] * x.ndim
    sl[axes[0]] = slice(wz // 2, x.shape[axes[0]] - (wz - 1) // 2)
    sl[axes[1]] = slice(wx // 2, x.shape[axes[1]] - (wx - 1) // 2)
    valid[tuple(sl)] = True
    if bad.any():  # windows holding a NaN pixel: their count of NaN pixels is >= 1
        valid &= ndimage.uniform_filter(bad.astype(float), size=size, mode="constant") < (
            0.5 / (wz * wx)
        )
    return np.where(valid, r, np.nan)


@preprocess_and_wrap(checks={"reference": _SCAN, "deformed": _SCAN})
def correlation_map(
    reference: xr.Dataset | xr.DataArray,
    deformed: xr.Dataset | xr.DataArray,
    *,
    window: int | tuple[int, int] = 16,
    kind: str = "intensity",
) -> xr.DataArray:
    """Pearson correlation in a window sliding pixel by pixel over ``(depth, x)``.

    Parameters
    ----------
    reference, deformed : xarray.Dataset or xarray.DataArray
        Complex fields with dims ``(..., depth, x)`` on the same pixel grid (shared dims of
        equal size and coordinates, else ``ValueError``).
    window : int or (int, int)
        Window size in pixels (depth, x); an int means square.
    kind : {"intensity", "amplitude", "complex"}
        Correlated quantity (``"complex"``: modulus of the complex coefficient).

    Returns
    -------
    xarray.DataArray
        Coefficient at each window centre (pixel ``c`` holds the window starting at
        ``c - w//2``); NaN where the window does not fit in the image or holds a NaN pixel
        (of either image), and only there.

    Examples
    --------
    >>> import speckle
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> img = speckle.bscan(scene, speckle.spectrum(32, 256.0, k0_dk=10.0))
    >>> c = speckle.correlation_map(img, img, window=8)
    >>> c.dims, float(c.max())
    (('depth', 'x'), 1.0)
    """
    check_choice(kind, "kind", KINDS)
    wz, wx = parse_window(window)
    x = _quantity(reference, kind)
    y = _quantity(deformed, kind)
    x, y = matched(x, y)
    y = y.transpose(*x.dims)
    if x.sizes["depth"] < wz or x.sizes["x"] < wx:
        raise ValueError(
            f"window {(wz, wx)} is larger than the image {(x.sizes['depth'], x.sizes['x'])}"
        )
    axes = (x.dims.index("depth"), x.dims.index("x"))
    r = correlation_array.__wrapped__(  # the numpy body: the images are checked
        x.values, y.values, (wz, wx), axes=axes, modulus=kind == "complex"
    )
    return xr.DataArray(
        r,
        dims=x.dims,
        coords=x.coords,
        attrs={
            **attrs("correlation", f"{kind} correlation in a sliding window"),
            "kind": kind,
            "window_depth_pixels": wz,
            "window_x_pixels": wx,
        },
    )


# --------------------------------------------------------------------------------------------
# Theory
# --------------------------------------------------------------------------------------------


@preprocess_and_wrap(
    checks={"x": ArraySpec(kind="real", nonempty=False), "spectrum": ArraySpec(kind="real", ndim=1)}
)
def kernel(x: object, spectrum: object) -> np.ndarray:
    """Point-spread kernel ``P(x) = sum_n S_n exp(2i pi n x/N)`` at pixel offsets ``x``.

    A scatterer ``x`` pixels below pixel ``q`` contributes ``a exp(2i k0 z) P(x)`` to ``A(q)``.
    """
    s, xx = spectrum, x  # checked: real, finite (spectrum 1-D)
    n = s.size
    idx = spectral_index(n).astype(float)
    w = np.exp(2j * np.pi * np.mod(xx.ravel(), n) / n)[None, :]
    out = _horner(s[None, :].astype(np.complex128), w)[0] * w[0] ** float(idx[0])
    return out.reshape(xx.shape)


def _integrals(
    spectrum: np.ndarray, phase: float, scale: float, offset: float, oversample: int
) -> dict[str, np.ndarray]:
    """Integrals over scatterer offset x for every reference pixel q (pooled later).

    Deformed kernel ``h(x) = exp(-2i pi phase x) P(scale*x + offset)``; reference scatterers at
    ``x in [-q, N-q)``.
    """
    n = spectrum.size
    dx = 1.0 / oversample
    x = np.arange(-n, n, dx) + 0.5 * dx  # midpoint rule on band-limited integrands
    core = kernel.__wrapped__  # the numpy body: the spectrum is checked
    p = core(x, spectrum)
    h = np.exp(-2j * np.pi * phase * x) * core(scale * x + offset, spectrum)
    grid = {
        "C": p * np.conj(h),
        "D": np.abs(p) ** 2 * np.abs(h) ** 2,
    }
    q = np.arange(n)
    out = {}
    for name, g in grid.items():
        cum = np.concatenate([[0], np.cumsum(g) * dx])
        lo = np.rint((-q + n) * oversample).astype(int)
        hi = np.rint((n - q + n) * oversample).astype(int)
        out[name] = cum[hi] - cum[lo]
    out["A"] = n * float(np.sum(spectrum**2))  # int over one period of |P|^2 (Parseval)
    out["A4"] = float(np.sum(np.abs(p[(x >= 0) & (x < n)]) ** 4) * dx)
    return out


@preprocess_and_wrap(checks={"strain": _STRAIN, "spectrum": _SPECTRUM})
def expected_correlation(
    strain: object = 0.0,
    *,
    spectrum: xr.DataArray,
    density: float,
    kurtosis: float = 1.0,
    compensation: str = "exact",
    shift: float = 0.0,
    oversample: int = 8,
) -> xr.Dataset:
    """Theoretical area correlation of intensity, amplitude and complex field versus strain.

    Parameters
    ----------
    strain : float or sequence of float
        Compressive uniaxial strain(s) in (-1, 1).
    spectrum : xarray.DataArray
        Source spectrum from :func:`speckle.system.source.spectrum` (its ``k0_dk`` = ``R`` is used).
    density : float
        Scatterers per pixel (> 0); sets the incoherent floor.
    kurtosis : float
        ``E|a|^4/(E|a|^2)^2`` of the amplitudes (1 for equal amplitudes).
    compensation : {"exact", "none"}
        ``"exact"``: deformed field evaluated at the displaced pixel positions (see
        :func:`compensate`). ``"none"``: only for a rigid axial ``shift`` (strain must be 0).
    shift : float
        Rigid axial shift in pixels for ``compensation="none"``.
    oversample : int
        Integration points per pixel (midpoint rule).

    Returns
    -------
    xarray.Dataset
        ``intensity`` (Pearson of ``|A|^2`` with the finite-density floor), ``complex``
        (``|gamma|``), ``amplitude`` (``(pi/4)(2F1(-1/2,-1/2;1;|gamma|^2) - 1)/(1 - pi/4)``)
        and ``floor`` (intensity correlation at ``gamma = 0``), over dim ``strain``; Poisson
        counts (a fixed count differs by ``O(1/(density*N))``).

    Examples
    --------
    >>> import speckle
    >>> src = speckle.spectrum(64, 512.0, k0_dk=10.0)
    >>> r = speckle.expected_correlation([0.0, 0.01], spectrum=src, density=4.0)
    >>> sorted(r.data_vars)
    ['amplitude', 'complex', 'floor', 'intensity']
    """
    s = np.atleast_1d(strain).astype(float)  # checked: real, finite, not empty
    if np.any((s <= -1) | (s >= 1)):
        raise ValueError(f"strain must lie in (-1, 1), got {s.tolist()}")
    rho = check_real(density, "density", low=0, low_inclusive=False)
    kappa = check_real(kurtosis, "kurtosis", low=1.0)
    check_choice(compensation, "compensation", ("exact", "none"))
    sh = check_real(shift, "shift")
    ov = check_int(oversample, "oversample", low=2)
    if compensation == "none" and np.any(s != 0):
        raise ValueError("compensation='none' is derived for a rigid shift only; use strain=0")
    w = np.asarray(spectrum, float)
    r_ratio = _k0_dk(spectrum)
    res = {k: [] for k in ("intensity", "complex", "amplitude", "floor")}
    for si in s:
        if compensation == "exact":
            it = _integrals(w, r_ratio * si, 1.0 - si, 0.0, ov)
            scale = 1.0 - si
        else:
            it = _integrals(w, 0.0, 1.0, sh, ov)
            scale = 1.0
        a, a4 = it["A"], it["A4"]
        a_def, a4_def = a / scale, a4 / scale  # deformed scatterers span N/scale pixels
        c_mean = np.mean(it["C"])
        c2 = np.mean(np.abs(it["C"]) ** 2)
        d = np.mean(it["D"])
        var = np.sqrt(
            (rho**2 * a**2 + rho * kappa * a4) * (rho**2 * a_def**2 + rho * kappa * a4_def)
        )
        res["intensity"].append((rho**2 * c2 + rho * kappa * d) / var)
        res["floor"].append(rho * kappa * d / var)
        g = abs(c_mean) / np.sqrt(a * a_def)
        res["complex"].append(g)
        res["amplitude"].append(amplitude_from_gamma.__wrapped__(g))
    coords = {"strain": coord("strain", s, "compressive strain")}
    meta = {
        "density": rho,
        "kurtosis": kappa,
        "k0_dk": r_ratio,
        "spectrum_shape": spectrum.attrs.get("shape", "array"),
        "compensation": compensation,
        "shift_pixels": sh,
    }
    return xr.Dataset(
        {
            k: ("strain", np.array(v), attrs("correlation", f"theoretical {k} correlation"))
            for k, v in res.items()
        },
        coords=coords,
        attrs=meta,
    )


def _k0_dk(spectrum: xr.DataArray) -> float:
    """``R = k0/delta_k`` of a source spectrum (ValueError naming ``spectrum`` without it)."""
    if "k0_dk" not in spectrum.attrs:
        raise ValueError(
            "spectrum needs attribute k0_dk (a spectrum from speckle.spectrum); it has "
            f"{sorted(spectrum.attrs)}"
        )
    return float(spectrum.attrs["k0_dk"])


#: Closed forms that moved to :mod:`speckle.analysis.correlation_forms` (they warn for a release).
__getattr__ = moved(
    __name__,
    "speckle.analysis.correlation_forms",
    ["carrier_window_factor", "continuum_gamma", "two_peak_weights"],
)
