"""Scatterers: random point-scatterer fields as labelled xarray datasets.

A scatterer field is an ``xarray.Dataset`` with dims ``(aline, scatterer)`` holding

* ``z`` -- depth of each scatterer in µm (float64),
* ``amplitude`` -- complex scattering amplitude ``a_j`` (dimensionless),

and a coordinate ``aline`` with the lateral position of each A-line in µm. Ragged A-lines are
padded with zero-amplitude scatterers at ``z = 0``. Later steps (deformation) transform ``z``
and may add dims such as ``strain``; :func:`speckle.bscan` images any such field.

Randomness
----------
Each A-line draws from its own generator, seeded by ``SeedSequence(seed, spawn_key=(i,))`` where
``i`` is the A-line index. A line's scatterers therefore do not depend on how many lines are
drawn, on chunking or on the number of Dask workers, and the same ``seed`` gives the same field
for every ``k0`` (as in the paper's Fig. 5).
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from .._validate import check_choice, check_int, check_memory, check_real
from ..conventions import attrs, coord

__all__ = [
    "AMPLITUDE_MODELS",
    "COUNT_MODELS",
    "amplitude_kurtosis",
    "draw_amplitudes",
    "line_generator",
    "random_scatterers",
]

#: Amplitude models; each is normalised to E|a|^2 = 1.
AMPLITUDE_MODELS = ("equal", "rayleigh", "uniform")
#: How many scatterers an A-line gets: exactly round(rho*N*span/H), or Poisson with that mean.
COUNT_MODELS = ("fixed", "poisson")


def amplitude_kurtosis(model: str) -> float:
    """``E|a|^4 / (E|a|^2)^2`` of an amplitude model (1 equal, 2 Rayleigh, 9/5 uniform)."""
    check_choice(model, "amplitude", AMPLITUDE_MODELS)
    return {"equal": 1.0, "rayleigh": 2.0, "uniform": 9.0 / 5.0}[model]


def line_generator(seed: int, index: int, *stream: int) -> np.random.Generator:
    """Generator of A-line ``index`` (optionally of a sub-``stream``) for a given ``seed``."""
    return np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(index, *stream)))


def draw_amplitudes(rng: np.random.Generator, model: str, size: int) -> np.ndarray:
    """``size`` scatterer amplitudes of one amplitude model, each with E|a|^2 = 1.

    Parameters
    ----------
    rng : numpy.random.Generator
        Source of randomness (drawn from only for the random models).
    model : {"equal", "rayleigh", "uniform"}
        ``"equal"``: all 1; ``"rayleigh"``: Rayleigh with sigma^2 = 1/2; ``"uniform"``: uniform
        on [0, sqrt(3)]. Checked by the callers (``AMPLITUDE_MODELS``).
    size : int
        Number of amplitudes.

    Returns
    -------
    numpy.ndarray
        Real amplitudes, shape ``(size,)``.
    """
    if model == "equal":
        return np.ones(size)
    if model == "rayleigh":  # |a| Rayleigh with E|a|^2 = 1 (sigma^2 = 1/2)
        return rng.rayleigh(scale=np.sqrt(0.5), size=size)
    return rng.uniform(0.0, np.sqrt(3.0), size=size)  # E a^2 = 1


def random_scatterers(
    n_alines: int,
    density: float,
    *,
    n_pixels: int,
    depth_range: float,
    seed: int,
    amplitude: str = "equal",
    count: str = "fixed",
    z_range: tuple[float, float] | None = None,
    aline_pitch: float | None = None,
    first_aline: int = 0,
) -> xr.Dataset:
    """Uniformly distributed point scatterers, independent from A-line to A-line.

    Parameters
    ----------
    n_alines : int
        Number of A-lines (>= 1).
    density : float
        Mean number of scatterers per pixel ``N_sc/N`` (>= 0), i.e. per ``H/N`` µm
        of depth.
    n_pixels : int
        Pixels per A-scan ``N`` (>= 2), defines the pixel size ``depth_range/n_pixels``.
    depth_range : float
        Unambiguous depth ``H`` in µm (> 0).
    seed : int
        Non-negative integer seed (see module docstring).
    amplitude : {"equal", "rayleigh", "uniform"}
        Amplitude model, normalised to ``E|a|^2 = 1``. Amplitudes are real and positive; the
        random phase of each contribution comes from its depth.
    count : {"fixed", "poisson"}
        ``"fixed"``: every A-line holds ``round(density*N*span/H)`` scatterers (the paper).
        ``"poisson"``: a Poisson number with that mean.
    z_range : (float, float), optional
        Depth interval ``[z_min, z_max)`` in µm populated with scatterers; default ``[0, H)``.
        Scatterers outside ``[0, H)`` wrap around in the image (see :func:`speckle.ascan`).
    aline_pitch : float, optional
        Lateral distance between A-lines in µm (> 0); default one pixel, ``H/N``.
    first_aline : int
        Index of the first A-line (>= 0); lines ``first_aline ... first_aline+n_alines-1`` are
        drawn, so a sub-range of a larger scene is reproduced exactly.

    Returns
    -------
    xarray.Dataset
        Variables ``z`` (µm) and ``amplitude`` with dims ``(aline, scatterer)``; coordinate
        ``aline`` (µm). Attributes record every parameter.

    Raises
    ------
    TypeError, ValueError
        On invalid input, and (``ValueError``) when the field would need more than
        :data:`speckle._validate.MAX_BYTES` (32 B per scatterer), before drawing anything.

    Examples
    --------
    >>> import speckle
    >>> scene = speckle.random_scatterers(8, 4.0, n_pixels=64, depth_range=512.0, seed=1)
    >>> sorted(scene.data_vars), int(scene.sizes["aline"])
    (['amplitude', 'count', 'z'], 8)
    """
    nl = check_int(n_alines, "n_alines", low=1)
    rho = check_real(density, "density", low=0)
    n = check_int(n_pixels, "n_pixels", low=2)
    h = check_real(depth_range, "depth_range", low=0, low_inclusive=False)
    sd = check_int(seed, "seed", low=0)
    check_choice(amplitude, "amplitude", AMPLITUDE_MODELS)
    check_choice(count, "count", COUNT_MODELS)
    i0 = check_int(first_aline, "first_aline", low=0)
    if z_range is None:
        z0, z1 = 0.0, h
    else:
        if isinstance(z_range, str) or not hasattr(z_range, "__len__") or len(z_range) != 2:
            raise TypeError(f"z_range must be a pair (z_min, z_max) in µm, got {z_range!r}")
        z0 = check_real(z_range[0], "z_range[0]")
        z1 = check_real(z_range[1], "z_range[1]", low=z0, low_inclusive=False)
    pitch = (
        h / n
        if aline_pitch is None
        else check_real(aline_pitch, "aline_pitch", low=0, low_inclusive=False)
    )
    mean_count = rho * n * (z1 - z0) / h
    # z (8 B), amplitude drawn (8 B) and stored complex (16 B) per scatterer slot; Poisson
    # counts are padded to the largest line (~ mean + 5 sqrt(mean))
    width_est = mean_count + (5.0 * np.sqrt(mean_count) if count == "poisson" else 0.5)
    check_memory(
        32.0 * nl * width_est,
        "n_alines, density or z_range",
        f"{nl} A-lines x {width_est:.3g} scatterers (density {rho:g} x n_pixels {n} x "
        f"(z_max - z_min)/depth {(z1 - z0) / h:.3g})",
    )
    rngs = [line_generator(sd, i0 + i) for i in range(nl)]
    if count == "fixed":
        counts = np.full(nl, round(mean_count), dtype=int)
    else:
        counts = np.array([rng.poisson(mean_count) for rng in rngs], dtype=int)
    width = int(counts.max(initial=0))
    z = np.zeros((nl, width))
    amp = np.zeros((nl, width))
    for i, (rng, c) in enumerate(zip(rngs, counts, strict=True)):
        z[i, :c] = rng.uniform(z0, z1, size=c)
        amp[i, :c] = draw_amplitudes(rng, amplitude, c)
    x = (i0 + np.arange(nl)) * pitch
    return xr.Dataset(
        {
            "z": (("aline", "scatterer"), z, attrs("z")),
            "amplitude": (
                ("aline", "scatterer"),
                amp.astype(np.complex128),
                attrs("amplitude", "scattering amplitude a_j"),
            ),
            "count": ("aline", counts, attrs("count", "scatterers in A-line")),
        },
        coords={"aline": coord("aline", x, "lateral position")},
        attrs={
            "density": rho,
            "density_units": attrs("density")["long_name"],
            "n_pixels": n,
            "depth_range": h,
            "seed": sd,
            "amplitude_model": amplitude,
            "count_model": count,
            "z_min": z0,
            "z_max": z1,
            "aline_pitch": pitch,
        },
    )
