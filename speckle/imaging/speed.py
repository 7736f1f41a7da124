"""Speed versus accuracy of the synthesis methods, and where each one fails, as datasets.

:func:`speed_accuracy` times every method at every value of its knob (``tol``) on the same
random scenes and measures its relative error ``||A - A_direct||_2 / ||A_direct||_2`` over the
B-scan. :func:`failure_map` measures how the error of each method (and of naive float32) grows
with the number of pixels ``N``, the scatterer density and ``k0/delta_k``, next to the error the
rules of :mod:`speckle.imaging.synthesis` predict.

Timings inside a pipeline are noisy (other jobs share the cores); ``benchmarks/bench_ascan.py``
is the reference for speed claims. Each time is the best of ``repeat`` runs, numba compilation
excluded.
"""

from __future__ import annotations

import functools
import time

import numpy as np
import xarray as xr

from ..scene.scatterers import line_generator
from ..sweep import sweep
from ..system.source import spectrum as make_spectrum
from .aline import ascan
from .carrier import naive_float32_phase_error_estimate
from .nufft import float32_error_estimate, kernel_width
from .psf import psf_ascan, tail_error
from .synthesis import choose_method

__all__ = ["FAILURE_CASES", "failure_map", "random_scene", "speed_accuracy"]


def random_scene(
    n_pixels: int,
    n_lines: int,
    density: float,
    *,
    pixel_size: float,
    seed: int,
    depth_factor: float = 2.0,
):
    """Random scene: depths uniform over ``[0, depth_factor * H)`` (wrap-around), complex
    Gaussian amplitudes (``E|a|^2 = 1``), ``round(density*N)`` scatterers per line.

    Returns ``(z, a, depth)`` with ``z`` in µm, shapes (lines, M). Line ``i`` draws from
    :func:`speckle.scene.scatterers.line_generator` ``(seed, i, N, M)``: reproducible per line.
    """
    depth = pixel_size * n_pixels
    m = max(1, round(density * n_pixels))
    z = np.empty((n_lines, m))
    a = np.empty((n_lines, m), dtype=complex)
    for i in range(n_lines):
        rng = line_generator(seed, i, n_pixels, m)
        z[i] = rng.uniform(0.0, depth_factor * depth, m)
        a[i] = (rng.normal(size=m) + 1j * rng.normal(size=m)) / np.sqrt(2)
    return z, a, depth


def _spectrum(n_pixels, depth, k0_dk, shape, fwhm_fraction):
    frac = fwhm_fraction if shape == "gaussian" else None
    return make_spectrum(n_pixels, depth, k0_dk=k0_dk, shape=shape, fwhm_fraction=frac)


def _best_time(func, repeat, **kwargs):
    """Best wall time of ``repeat`` calls ``func(**kwargs)`` and the last result."""
    best, out = np.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = func(**kwargs)
        best = min(best, time.perf_counter() - t0)
    return best, out


def _rel_err(a, ref):
    return float(np.linalg.norm(a - ref) / np.linalg.norm(ref))


def speed_accuracy(
    sizes: list[dict],
    methods: list[str],
    tols: list[float],
    *,
    pixel_size: float,
    k0_dk: float,
    shape: str,
    fwhm_fraction: float | None,
    seed: int,
    repeat: int = 2,
) -> xr.Dataset:
    """Time and relative error of every method at every ``tol`` on 2-3 scene sizes.

    Parameters
    ----------
    sizes : list of dict
        Scenes, each ``{"n_pixels": N, "n_lines": B, "density": rho}``.
    methods : list of str
        Methods of :func:`speckle.ascan` (``"direct"`` is timed once per scene, at every tol).
    tols : list of float
        The knob: requested relative accuracy.
    pixel_size, k0_dk, shape, fwhm_fraction
        Source: pixel size ``H/N`` in µm, ``k0/delta_k``, spectrum shape and Gaussian FWHM as
        a fraction of ``delta_k``.
    seed : int
        Root seed of the scenes.
    repeat : int
        Each time is the best of ``repeat`` runs (run serially: parallel runs would share cores).

    Returns
    -------
    xarray.Dataset
        dims ``(scene, method, tol)``: ``time`` (s), ``error`` (relative, NaN where the method
        refused the tol), ``rate`` (scatterers/s), ``chosen`` (auto's choice, per scene and tol);
        scene coords ``n_pixels``, ``n_lines``, ``density``, ``n_scatterers``.
    """
    shape_ = (len(sizes), len(methods), len(tols))
    t_all = np.full(shape_, np.nan)
    e_all = np.full(shape_, np.nan)
    chosen = np.empty((len(sizes), len(tols)), dtype=object)
    n_scat = []
    for i, sz in enumerate(sizes):
        n, nl, rho = int(sz["n_pixels"]), int(sz["n_lines"]), float(sz["density"])
        z, a, depth = random_scene(n, nl, rho, pixel_size=pixel_size, seed=seed)
        spec = _spectrum(n, depth, k0_dk, shape, fwhm_fraction)
        k0 = float(spec.attrs["k0"])
        s = spec.values
        n_scat.append(z.size)
        run = functools.partial(ascan, z, a, n_pixels=n, depth=depth, k0=k0, spectrum=s)
        for name in methods:  # warm-up (numba compilation) on a tiny slice
            try:
                ascan(
                    z[:1, :4],
                    a[:1, :4],
                    n_pixels=n,
                    depth=depth,
                    k0=k0,
                    spectrum=s,
                    method=name,
                    tol=1e-3,
                )
            except ValueError:
                pass
        t_ref, ref = _best_time(run, repeat)
        for j, name in enumerate(methods):
            for k, tol in enumerate(tols):
                chosen[i, k] = choose_method(nl, z.shape[1], n, s, tol)
                if name == "direct":
                    t_all[i, j, k], e_all[i, j, k] = t_ref, 0.0
                    continue
                try:
                    t, out = _best_time(run, repeat, method=name, tol=tol)
                except ValueError:
                    continue  # the method refuses this tol on this scene
                t_all[i, j, k], e_all[i, j, k] = t, _rel_err(out, ref)
    scene = np.arange(len(sizes))
    ds = xr.Dataset(
        {
            "time": (
                ("scene", "method", "tol"),
                t_all,
                {"units": "s", "long_name": "wall time (best of repeat; noisy in a pipeline)"},
            ),
            "error": (
                ("scene", "method", "tol"),
                e_all,
                {"units": "1", "long_name": "relative error ||A - A_direct||_2/||A_direct||_2"},
            ),
            "chosen": (("scene", "tol"), chosen.astype(str), {"long_name": "method auto picks"}),
        },
        coords={
            "scene": scene,
            "method": list(methods),
            "tol": ("tol", list(map(float, tols)), {"long_name": "requested relative accuracy"}),
            "n_pixels": ("scene", [int(s["n_pixels"]) for s in sizes]),
            "n_lines": ("scene", [int(s["n_lines"]) for s in sizes]),
            "density": ("scene", [float(s["density"]) for s in sizes], {"units": "1/pixel"}),
            "n_scatterers": ("scene", n_scat),
        },
        attrs={
            "title": "speed versus accuracy of the A-scan synthesis methods",
            "k0_dk": k0_dk,
            "spectrum_shape": shape,
            "fwhm_fraction": np.nan if fwhm_fraction is None else fwhm_fraction,
            "pixel_size_um": pixel_size,
            "seed": seed,
            "repeat": repeat,
            "note": "timings from a pipeline run are noisy; benchmarks/bench_ascan.py is the "
            "reference for speed claims",
        },
    )
    ds["rate"] = (ds["n_scatterers"] / ds["time"]).assign_attrs(
        units="1/s", long_name="scatterers per second"
    )
    return ds


#: Failure-map cases: (label, method, knob). Gaussian cases use ``fwhm_fraction``.
FAILURE_CASES = (
    ("nufft tol=1e-2", "nufft", 1e-2),
    ("nufft tol=1e-6", "nufft", 1e-6),
    ("nufft32 tol=1e-5", "nufft32", 1e-5),
    ("float32 naive phase", "naive32", None),
    ("psf hw=8 gaussian", "psf-gaussian", 8),
    ("psf hw=8 rectangular", "psf-rectangular", 8),
)


def _failure_point(n_pixels, density, k0_dk, *, n_lines, pixel_size, fwhm_fraction, seed):
    """Measured and predicted relative error of every failure case on one random scene."""
    n = int(n_pixels)
    z, a, depth = random_scene(n, n_lines, float(density), pixel_size=pixel_size, seed=seed)
    rect = _spectrum(n, depth, float(k0_dk), "rectangular", None)
    gauss = _spectrum(n, depth, float(k0_dk), "gaussian", fwhm_fraction).values
    k0 = float(rect.attrs["k0"])
    common = dict(n_pixels=n, depth=depth, k0=k0)
    ref_rect = ascan(z, a, **common)
    ref_gauss = ascan(z, a, spectrum=gauss, **common)
    measured, predicted = [], []
    m = z.shape[1]
    for _label, kind, knob in FAILURE_CASES:
        if kind in ("nufft", "nufft32"):
            out = ascan(z, a, method=kind, tol=knob, **common)
            measured.append(_rel_err(out, ref_rect))
            pred = (
                knob
                if kind == "nufft"
                else (0.5 * knob + float32_error_estimate(m, n, kernel_width(0.5 * knob)))
            )
            predicted.append(pred)
        elif kind == "naive32":
            exact = np.exp(2j * k0 * z)
            naive = np.exp(1j * (np.float32(2 * k0) * z.astype(np.float32))).astype(complex)
            out = ascan(z, a * naive / exact, **common)  # the A-scan with a float32 phase
            measured.append(_rel_err(out, ref_rect))
            predicted.append(naive_float32_phase_error_estimate(z, k0))
        else:
            s, ref = (gauss, ref_gauss) if kind == "psf-gaussian" else (np.ones(n), ref_rect)
            out = psf_ascan(z, a, n, depth, k0, s, hw=knob, rows=4096)
            measured.append(_rel_err(out, ref))
            predicted.append(tail_error(s, knob))
    labels = [c[0] for c in FAILURE_CASES]
    return xr.Dataset(
        {"error": ("case", measured), "predicted": ("case", predicted)},
        coords={"case": labels},
    )


def failure_map(
    n_pixels: list[int],
    densities: list[float],
    k0_dks: list[float],
    *,
    base: dict,
    n_lines: int,
    pixel_size: float,
    fwhm_fraction: float,
    seed: int,
    dask: dict | None = None,
) -> xr.Dataset:
    """Relative error of each failure case versus ``N``, density and ``k0/delta_k``.

    One axis varies at a time, the others stay at ``base`` (``{"n_pixels", "density",
    "k0_dk"}``). Each point is a random scene of ``n_lines`` lines with depths over ``[0, 2H)``;
    errors are measured against the direct sum and shown next to the predicted error.
    Sweeps run with :func:`speckle.sweep.sweep` (``dask``: the config's dask section).

    Returns
    -------
    xarray.Dataset
        ``error_vs_<axis>`` and ``predicted_vs_<axis>`` for axis in ``n_pixels``, ``density``,
        ``k0_dk``, each with dims ``(<axis>, case)``.
    """
    fixed = dict(n_lines=n_lines, pixel_size=pixel_size, fwhm_fraction=fwhm_fraction, seed=seed)
    dask = dict(dask or {})
    opts = {k: dask[k] for k in ("scheduler", "address", "n_workers") if k in dask}
    out = xr.Dataset()
    for axis, values in (("n_pixels", n_pixels), ("density", densities), ("k0_dk", k0_dks)):
        point = {k: v for k, v in base.items() if k != axis}
        ds = sweep(_failure_point, {axis: list(values)}, fixed={**point, **fixed}, **opts)
        out[f"error_vs_{axis}"] = ds["error"].assign_attrs(
            units="1", long_name=f"measured relative error vs {axis}"
        )
        out[f"predicted_vs_{axis}"] = ds["predicted"].assign_attrs(
            units="1", long_name=f"predicted relative error vs {axis}"
        )
    out["density"].attrs["units"] = "1/pixel"
    out["k0_dk"].attrs["long_name"] = "k0/delta_k (= Lc/lambda0)"
    out.attrs.update(
        title="failure map of the A-scan synthesis methods",
        base_n_pixels=base["n_pixels"],
        base_density=base["density"],
        base_k0_dk=base["k0_dk"],
        n_lines=n_lines,
        pixel_size_um=pixel_size,
        fwhm_fraction=fwhm_fraction,
        seed=seed,
        error_definition="||A - A_direct||_2/||A_direct||_2 over the B-scan",
    )
    return out
