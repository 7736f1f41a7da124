"""Random phase perturbations along depth from refractive-index fluctuations (off by default).

The refractive index along an A-line fluctuates, ``n(z) = n + dn(z)``, with ``dn`` a stationary
Gaussian process of variance ``s^2`` (``index_variance``, dimensionless) and Gaussian correlation
``E dn(z) dn(z + u) = s^2 exp(-u^2/l^2)`` (``l``: ``correlation_length`` in µm). Light reaching a
scatterer at depth ``z`` and returning picks up the extra phase

    phi(z) = 2 k0 int_0^z dn(z') dz',

a Gaussian process (zero mean) with structure ``Var[phi(b) - phi(a)] = 4 k0^2 D(|b - a|)`` and
``Var phi(z) = 4 k0^2 D(z)``, where

    D(u) = s^2 [u l sqrt(pi) erf(u/l) + l^2 (exp(-u^2/l^2) - 1)]

(``~ s^2 u^2`` for ``u << l``; ``~ s^2 l sqrt(pi) u``, a random walk, for ``u >> l``). Each
scatterer's amplitude is multiplied by ``exp(i phi(z_j))`` of its own depth (the phase belongs to
the path to the scatterer, not to a pixel). Two acquisitions with independent fluctuations keep,
for a scatterer at ``z``, the complex correlation ``E exp(i (phi_1 - phi_2)) = exp(-4 k0^2 D(z))``.

Sampling: ``phi`` is drawn exactly (multivariate normal, covariance from ``D``) on a grid of
step ``min(l/8, H/N)`` and linearly interpolated to the scatterer depths; each A-line (and each
combination of other dims) has an independent screen.

Shared scenes (scatterers at ``(z, x)``, or ``(z, x, y)`` in 3-D, seen by overlapping
A-lines): the fluctuation is a 2-D (3-D) field with separable Gaussian correlation
``s^2 exp(-u^2/l^2) exp(-v^2/l_x^2)`` (``v`` lateral, ``l_x``:
``lateral_correlation_length``, default ``l``), and the path to a scatterer runs straight down
at its own ``x`` (paraxial). Then ``phi(z, x)`` is Gaussian with covariance
``C_z(z1, z2) exp(-(x1 - x2)^2/l_x^2)``, ``C_z`` the single-line covariance above: the same
variance ``4 k0^2 D(z)`` at every ``x``, and scatterers ``dx`` apart at one depth share the
fraction ``exp(-dx^2/l_x^2)`` of it. One screen ``L_z W L_x^T`` (white ``W``) is drawn on a
``(z, x)`` grid of step ``l/8`` by ``l_x/8`` over the scene and interpolated bilinearly; in 3-D
the lateral factor is ``exp(-(dx^2 + dy^2)/l_x^2)`` (one square root per lateral axis, trilinear
interpolation), so the screen varies in ``y`` as in ``x``.
"""

from __future__ import annotations

import math

import numpy as np
import xarray as xr
from scipy import special
from scipy.interpolate import RegularGridInterpolator

from .._validate import as_finite_array, check_int, check_memory, check_real
from ..conventions import depth_range_of
from ..scene.shared import is_shared
from ._scene import check_scene, line_rng, scale_amplitudes

__all__ = ["phase_perturb", "phase_screens", "phase_structure", "shared_phase_screen"]

_STREAM = 103
_MAX_NODES = 2048


#: Bounds of the screen parameters (far beyond any tissue, keeping every square finite).
MAX_CORRELATION_LENGTH = 1e9  # µm
MAX_K0 = 1e7  # rad/µm


def _screen_parameters(index_variance: object, correlation_length: object, k0: object):
    """``(s^2, l, k0)`` checked: ``0 <= s^2 <= 1``, ``0 < l <= 1e9`` µm, ``0 <= k0 <= 1e7``."""
    s2 = check_real(index_variance, "index_variance", low=0, high=1)
    ell = check_real(correlation_length, "correlation_length", low=0, low_inclusive=False,
                     high=MAX_CORRELATION_LENGTH)  # fmt: skip
    k = check_real(k0, "k0", low=0, high=MAX_K0)
    return s2, ell, k


def phase_structure(
    u: object, index_variance: float, correlation_length: float, k0: float
) -> np.ndarray:
    """``Var[phi(z + u) - phi(z)] = 4 k0^2 D(|u|)`` in rad^2 (module docstring)."""
    s2, ell, k = _screen_parameters(index_variance, correlation_length, k0)
    uu = np.abs(as_finite_array(u, "u"))
    d = uu * ell * np.sqrt(np.pi) * special.erf(uu / ell) + ell**2 * np.expm1(-(uu**2) / ell**2)
    return 4 * k**2 * s2 * d


def _grid(z_max: float, step: float) -> np.ndarray:
    n = int(np.ceil(z_max / step)) + 1
    if n > _MAX_NODES:
        raise ValueError(
            f"phase screen needs {n} nodes (> {_MAX_NODES}) for depths up to {z_max:g} µm: "
            "use a longer correlation_length or fewer pixels"
        )
    return np.linspace(0.0, max(z_max, step), max(n, 2))


def _span_grid(lo: float, hi: float, step: float) -> np.ndarray:
    """Nodes from ``lo`` to exactly ``hi`` (``lo + linspace`` can end a float step short of
    ``hi``, which the interpolator then refuses as outside the grid)."""
    g = lo + _grid(hi - lo, step)
    g[-1] = max(g[-1], hi)
    return g


def _factor(grid: np.ndarray, s2: float, ell: float, k0: float) -> np.ndarray:
    """``L`` with ``L L^T = Cov(phi(grid))`` (eigen-decomposition, tiny negatives clipped)."""
    dz = phase_structure(grid, s2, ell, k0)
    cov = 0.5 * (
        dz[:, None] + dz[None, :] - phase_structure(grid[:, None] - grid[None, :], s2, ell, k0)
    )
    return _sqrt_cov(cov)


def _sqrt_cov(cov: np.ndarray) -> np.ndarray:
    val, vec = np.linalg.eigh(cov)
    return vec * np.sqrt(np.clip(val, 0.0, None))


def _draw(z: np.ndarray, s2: float, ell: float, k0: float, seed: int, step: float) -> np.ndarray:
    """One independent screen per row of ``z`` (depths in µm, >= 0), evaluated at ``z``."""
    if np.any(z < 0):
        raise ValueError("scatterer depths must be >= 0 µm (the path starts at z = 0)")
    grid = _grid(float(z.max(initial=0.0)), min(step, ell / 8))
    lmat = _factor(grid, s2, ell, k0)
    phi = np.empty(z.shape)
    for i in range(z.shape[0]):
        screen = lmat @ line_rng(seed, i, _STREAM).standard_normal(grid.size)
        phi[i] = np.interp(z[i], grid, screen)
    return phi


def phase_screens(
    depths: object,
    *,
    n_screens: int,
    index_variance: float,
    correlation_length: float,
    k0: float,
    seed: int,
) -> np.ndarray:
    """Independent phase screens ``phi(z)`` in rad at ``depths`` (µm, >= 0).

    Screen ``i`` is the one :func:`phase_perturb` gives A-line ``i`` with the same seed (for
    the same grid step). Returns shape ``(n_screens, depths.size)``.
    """
    z = as_finite_array(depths, "depths").ravel()
    ns = check_int(n_screens, "n_screens", low=1)
    s2, ell, k = _screen_parameters(index_variance, correlation_length, k0)
    sd = check_int(seed, "seed", low=0)
    return _draw(np.broadcast_to(z, (ns, z.size)), s2, ell, k, sd, ell / 8)


def shared_phase_screen(
    z: object,
    x: object,
    *,
    index_variance: float,
    correlation_length: float,
    k0: float,
    seed: int,
    lateral_correlation_length: float | None = None,
    step: float | None = None,
    y: object | None = None,
) -> np.ndarray:
    """Phase ``phi(z_j, x_j[, y_j])`` in rad of one 2-D (3-D with ``y``) screen at scatterer
    positions (µm; module docstring). ``step``: the depth grid step (default ``l/8``). Same
    arguments, same screen. In 3-D the lateral covariance ``exp(-(dx^2 + dy^2)/l_x^2)`` is the
    product of one factor per lateral axis: the screen ``W`` (white, ``(z, x, y)`` grid) is
    multiplied by the covariance square root along each axis and interpolated trilinearly.

    Raises
    ------
    ValueError
        On mismatched sizes, negative depths, a grid beyond the node or memory limit.
    """
    zz = as_finite_array(z, "z").ravel()
    xx = as_finite_array(x, "x").ravel()
    yy = None if y is None else as_finite_array(y, "y").ravel()
    if zz.shape != xx.shape or (yy is not None and yy.shape != zz.shape):
        sizes = f"{zz.size} and {xx.size}" + ("" if yy is None else f" and {yy.size}")
        raise ValueError(f"z, x (and y) must have the same size, got {sizes}")
    if np.any(zz < 0):
        raise ValueError("scatterer depths must be >= 0 µm (the path starts at z = 0)")
    s2, ell, k = _screen_parameters(index_variance, correlation_length, k0)
    lx = (
        ell
        if lateral_correlation_length is None
        else check_real(
            lateral_correlation_length,
            "lateral_correlation_length",
            low=0,
            low_inclusive=False,
            high=MAX_CORRELATION_LENGTH,
        )
    )
    sd = check_int(seed, "seed", low=0)
    if zz.size == 0:
        return np.zeros(0)
    gz = _grid(float(zz.max()), min(ell / 8, ell / 8 if step is None else step))
    lateral = [xx] if yy is None else [xx, yy]
    grids = [_span_grid(float(v.min()), float(v.max()), lx / 8) for v in lateral]
    shape = (gz.size, *(g.size for g in grids))
    check_memory(3 * 8.0 * math.prod(shape), "lateral_correlation_length", "the phase screen")
    lz = _factor(gz, s2, ell, k)
    factors = [_sqrt_cov(np.exp(-((g[:, None] - g[None, :]) ** 2) / lx**2)) for g in grids]
    rng = np.random.default_rng(np.random.SeedSequence(sd, spawn_key=(_STREAM,)))
    if yy is None:
        screen = lz @ rng.standard_normal(shape) @ factors[0].T
    else:
        screen = np.einsum("ia,abc->ibc", lz, rng.standard_normal(shape))
        screen = np.einsum("jb,ibc->ijc", factors[0], screen)
        screen = np.einsum("kc,ijc->ijk", factors[1], screen)
    return RegularGridInterpolator((gz, *grids), screen)(np.column_stack([zz, *lateral]))


def phase_perturb(
    scene: xr.Dataset,
    *,
    index_variance: float,
    correlation_length: float,
    k0: float,
    seed: int,
    lateral_correlation_length: float | None = None,
) -> xr.Dataset:
    """Multiply each scatterer amplitude by ``exp(i phi(z_j))`` of an independent screen per line
    (independent-line scenes) or of one 2-D screen ``phi(z_j, x_j)`` (shared scenes).

    Parameters
    ----------
    scene : xarray.Dataset
        Scatterer field (``z`` in µm, >= 0, ``amplitude``) with an ``aline`` dim, or a shared
        scene (:func:`speckle.shared_scene`: ``z``, ``x`` over ``scatterer``).
    index_variance : float
        Variance ``s^2`` of the refractive-index fluctuation (>= 0).
    correlation_length : float
        Correlation length ``l`` in µm (> 0).
    k0 : float
        Central wavenumber in the medium, rad/µm (>= 0), e.g. ``source.attrs["k0"]``.
    seed : int
        Seed of the screens; screen ``i`` belongs to the ``i``-th A-line (other dims share it).
    lateral_correlation_length : float, optional
        Shared scenes: lateral correlation length ``l_x`` in µm (> 0; default ``l``).

    Returns
    -------
    xarray.Dataset
        The perturbed scene; attributes record the parameters.

    Examples
    --------
    >>> import numpy as np
    >>> import speckle
    >>> src = speckle.spectrum(32, 256.0, k0_dk=10.0)
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=32, depth_range=256.0, seed=1)
    >>> k0 = float(src.attrs["k0"])
    >>> out = speckle.phase_perturb(
    ...     scene, index_variance=1e-6, correlation_length=20.0, k0=k0, seed=2
    ... )
    >>> bool(np.allclose(abs(out.amplitude), abs(scene.amplitude)))  # phases only
    True
    """
    check_scene(scene)
    if is_shared(scene):
        phi = shared_phase_screen(
            scene.z.values,
            scene.x.values,
            y=scene.y.values if "y" in scene.data_vars else None,
            index_variance=index_variance,
            correlation_length=correlation_length,
            k0=k0,
            seed=seed,
            lateral_correlation_length=lateral_correlation_length,
        )
        return scale_amplitudes(
            scene,
            scene.z.copy(data=np.exp(1j * phi)),
            phase_index_variance=float(index_variance),
            phase_correlation_length=float(correlation_length),
            phase_lateral_correlation_length=float(
                correlation_length
                if lateral_correlation_length is None
                else lateral_correlation_length
            ),
            phase_k0=float(k0),
            phase_seed=int(seed),
        )
    if lateral_correlation_length is not None:
        raise ValueError(
            "lateral_correlation_length applies to shared scenes only (independent A-lines "
            "have independent screens)"
        )
    if "aline" not in scene.z.dims:
        raise ValueError("scene must have an 'aline' dim (or be a shared scene)")
    s2, ell, k = _screen_parameters(index_variance, correlation_length, k0)
    sd = check_int(seed, "seed", low=0)
    step = ell / 8
    h = depth_range_of(scene, "scene", required=False)
    if h is not None and "n_pixels" in scene.attrs:
        step = min(step, h / int(scene.attrs["n_pixels"]))
    z = scene.z.transpose("aline", ...)
    zv = z.values.reshape(z.shape[0], -1)
    phi = _draw(zv, s2, ell, k, sd, step).reshape(z.shape)
    factor = z.copy(data=np.exp(1j * phi))
    return scale_amplitudes(
        scene,
        factor,
        phase_index_variance=s2,
        phase_correlation_length=ell,
        phase_k0=k,
        phase_seed=sd,
    )
