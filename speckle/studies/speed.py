"""Speed versus accuracy of the synthesis methods, and where each one fails, as datasets.

:func:`speed_accuracy` times every method at every value of its knob (``tol``) on the same
random scenes and measures its relative error ``||A - A_direct||_2 / ||A_direct||_2`` over the
B-scan; :func:`beam_speed_accuracy` does the same for the scanned-beam B-scan
(:func:`speckle.beam_scan`) on shared 2-D scenes. :func:`failure_map` measures how the error of
each method (and of naive float32) grows with the number of pixels ``N``, the scatterer density
and ``k0/delta_k``, next to the error the rules of :mod:`speckle.imaging.synthesis` predict.

Timings inside a pipeline are noisy (other jobs share the cores); ``benchmarks/bench_ascan.py``
and ``benchmarks/bench_beam.py`` are the references for speed claims. Each time is the best of
``repeat`` runs, numba compilation excluded.
"""

from __future__ import annotations

import functools
import time

import numpy as np
import xarray as xr

from ..conventions import attrs
from ..imaging._methods.beam_nufft import choose_beam_method
from ..imaging._methods.carrier import naive_float32_phase_error_estimate
from ..imaging._methods.nufft import float32_error_estimate, kernel_width
from ..imaging._methods.psf import psf_ascan, tail_error
from ..imaging.aline import ascan
from ..imaging.beam import Beam, BeamScene, beam_scan
from ..imaging.synthesis import choose_method
from ..scene.scatterers import line_generator
from ..sweep import sweep
from ..system.source import spectrum as make_spectrum

__all__ = [
    "FAILURE_CASES",
    "beam_speed_accuracy",
    "failure_map",
    "random_beam_scene",
    "random_scene",
    "speed_accuracy",
]


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


def _spectrum(n_pixels, depth_range, k0_dk, shape, fwhm_fraction):
    frac = fwhm_fraction if shape == "gaussian" else None
    return make_spectrum(n_pixels, depth_range, k0_dk=k0_dk, shape=shape, fwhm_fraction=frac)


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


def _warm_up(run_small, methods, tols) -> None:
    """Call every method at every tol once on a tiny scene: numba compiles every code path a
    timed run takes (e.g. the beam's row and general paths) before any timing."""
    for name in methods:
        for tol in tols:
            try:
                run_small(method=name, tol=tol)
            except ValueError:
                pass  # refused: nothing to compile for it


def _time_methods(run, methods, tols, repeat):
    """Best time (s) and relative error of ``run(method=, tol=)`` for every method and tol.

    The reference is ``run()`` (the exact ``"direct"`` method: time at every tol, error 0),
    run once: it costs more than everything else together. NaN where a method refuses a tol
    (ValueError). Returns two (method, tol) arrays.
    """
    t_ref, ref = _best_time(run, 1)
    t_all = np.full((len(methods), len(tols)), np.nan)
    e_all = np.full((len(methods), len(tols)), np.nan)
    for j, name in enumerate(methods):
        for k, tol in enumerate(tols):
            if name == "direct":
                t_all[j, k], e_all[j, k] = t_ref, 0.0
                continue
            try:
                t, out = _best_time(run, repeat, method=name, tol=tol)
            except ValueError:
                continue  # the method refuses this tol on this scene
            t_all[j, k], e_all[j, k] = t, _rel_err(out, ref)
    return t_all, e_all


def _time_sizes(sizes, methods, tols, repeat, case):
    """Times and errors ``(scene, method, tol)``, auto's choices and scatterer counts.

    ``case(size) -> (run, small, n_scatterers, choose)`` builds the scene of one entry of
    ``sizes``: ``run(method=, tol=)`` images it, ``small`` is ``run`` on a tiny part of it (the
    warm-up, :func:`_warm_up`) and ``choose(tol)`` is ``method="auto"``'s choice.
    """
    shape_ = (len(sizes), len(methods), len(tols))
    t_all = np.full(shape_, np.nan)
    e_all = np.full(shape_, np.nan)
    chosen = np.empty((len(sizes), len(tols)), dtype=object)
    n_scat = []
    for i, sz in enumerate(sizes):
        run, small, m, choose = case(sz)
        n_scat.append(m)
        _warm_up(small, methods, tols)
        t_all[i], e_all[i] = _time_methods(run, methods, tols, repeat)
        chosen[i] = [choose(tol) for tol in tols]
    return t_all, e_all, chosen, n_scat


def _chart_dataset(time_, error, chosen, methods, tols, coords, meta) -> xr.Dataset:
    """The chart's dataset: dims ``(scene, method, tol)``, ``coords`` per scene as
    ``{name: (values, attrs)}`` (``n_scatterers`` among them), ``rate`` from ``time``;
    ``meta``: the dataset's attributes."""
    ds = xr.Dataset(
        {
            "time": (
                ("scene", "method", "tol"),
                time_,
                attrs("time", "wall time (best of repeat, direct: one run; noisy in a pipeline)"),
            ),
            "error": (
                ("scene", "method", "tol"),
                error,
                attrs("dimensionless", "relative error ||A - A_direct||_2/||A_direct||_2"),
            ),
            "chosen": (("scene", "tol"), chosen.astype(str), {"long_name": "method auto picks"}),
        },
        coords={
            "scene": np.arange(time_.shape[0]),
            "method": list(methods),
            "tol": ("tol", list(map(float, tols)), {"long_name": "requested relative accuracy"}),
            **{k: ("scene", v, a) for k, (v, a) in coords.items()},
        },
        attrs=meta,
    )
    ds["rate"] = (ds["n_scatterers"] / ds["time"]).assign_attrs(attrs("rate"))
    return ds


def _source_attrs(k0_dk, shape, fwhm_fraction, pixel_size, seed, repeat) -> dict:
    return {
        "k0_dk": k0_dk,
        "spectrum_shape": shape,
        "fwhm_fraction": np.nan if fwhm_fraction is None else fwhm_fraction,
        "pixel_size_um": pixel_size,
        "seed": seed,
        "repeat": repeat,
    }


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

    def case(sz):
        n, nl, rho = int(sz["n_pixels"]), int(sz["n_lines"]), float(sz["density"])
        z, a, depth = random_scene(n, nl, rho, pixel_size=pixel_size, seed=seed)
        spec = _spectrum(n, depth, k0_dk, shape, fwhm_fraction)
        k0 = float(spec.attrs["k0"])
        s = spec.values
        common = dict(n_pixels=n, depth_range=depth, k0=k0, spectrum=s)
        small = functools.partial(ascan, z[:1, :4], a[:1, :4], **common)
        run = functools.partial(ascan, z, a, **common)
        return run, small, z.size, lambda tol: choose_method(nl, z.shape[1], n, s, tol)

    t_all, e_all, chosen, n_scat = _time_sizes(sizes, methods, tols, repeat, case)
    coords = {
        "n_pixels": ([int(s["n_pixels"]) for s in sizes], attrs("count", "pixels N")),
        "n_lines": ([int(s["n_lines"]) for s in sizes], attrs("count", "lines")),
        "density": ([float(s["density"]) for s in sizes], attrs("line_density")),
        "n_scatterers": (n_scat, attrs("count", "scatterers")),
    }
    meta = {
        "title": "speed versus accuracy of the A-scan synthesis methods",
        **_source_attrs(k0_dk, shape, fwhm_fraction, pixel_size, seed, repeat),
        "note": "timings from a pipeline run are noisy; benchmarks/bench_ascan.py is the "
        "reference for speed claims",
    }
    return _chart_dataset(t_all, e_all, chosen, methods, tols, coords, meta)


def random_beam_scene(
    n_pixels: int, n_lines: int, density: float, *, pitch: float, pixel_size: float, seed: int
):
    """Shared 2-D scene of a scanned-beam B-scan with lines every ``pitch`` µm from ``x = 0``.

    ``round(density * N * L)`` scatterers, ``x`` uniform over the scanned span
    ``[-pitch/2, (L - 1/2) pitch)`` and ``z`` over one unambiguous depth ``[0, H)``,
    ``H = N * pixel_size``, complex Gaussian amplitudes (``E|a|^2 = 1``). The generator is
    seeded by ``SeedSequence(seed, spawn_key=(N, L, M))``: the same size gives the same scene.

    Returns
    -------
    (z, x, a, lines, depth)
        Depths and lateral positions (µm), amplitudes, shapes (M,); line positions (L,) in µm;
        ``H`` in µm.
    """
    depth = pixel_size * n_pixels
    m = max(1, round(density * n_pixels * n_lines))
    rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(n_pixels, n_lines, m)))
    x = rng.uniform(-0.5 * pitch, (n_lines - 0.5) * pitch, m)
    z = rng.uniform(0.0, depth, m)
    a = (rng.normal(size=m) + 1j * rng.normal(size=m)) / np.sqrt(2)
    return z, x, a, np.arange(n_lines) * pitch, depth


def beam_speed_accuracy(
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
    """Time and relative error of every :func:`speckle.beam_scan` method at every ``tol``.

    Each scene is :func:`random_beam_scene` with lines every ``pitch = pixel_size`` µm, imaged
    by a beam without focus of waist ``w0 = waist_pitch * pitch``. The reference is
    ``method="direct"`` on all lines (exact, float64); errors are relative l2 over the whole
    B-scan, as the ``tol`` of :func:`speckle.beam_scan` is defined.

    Parameters
    ----------
    sizes : list of dict
        Scenes, each ``{"n_pixels": N, "n_lines": L, "density": rho, "waist_pitch": w0/p}``
        (``rho`` scatterers per pixel per line).
    methods : list of str
        Methods of :func:`speckle.beam_scan` (``"direct"`` runs once per scene).
    tols : list of float
        The knob: requested relative accuracy.
    pixel_size, k0_dk, shape, fwhm_fraction
        Source as in :func:`speed_accuracy` (pixel size and line pitch in µm).
    seed : int
        Root seed of the scenes.
    repeat : int
        Each time is the best of ``repeat`` runs.

    Returns
    -------
    xarray.Dataset
        As :func:`speed_accuracy` (``chosen``: the beam's auto choice), scene coords
        ``n_pixels``, ``n_lines``, ``density``, ``waist_pitch``, ``n_scatterers``.
    """
    pitch = pixel_size

    def case(sz):
        n, nl, rho = int(sz["n_pixels"]), int(sz["n_lines"]), float(sz["density"])
        w0 = float(sz["waist_pitch"]) * pitch
        z, x, a, lines, depth = random_beam_scene(
            n, nl, rho, pitch=pitch, pixel_size=pixel_size, seed=seed
        )
        spec = _spectrum(n, depth, k0_dk, shape, fwhm_fraction)
        k0 = float(spec.attrs["k0"])
        s = spec.values
        common = dict(lines=lines, waist=w0, n_pixels=n, depth_range=depth, k0=k0, spectrum=s)
        part = slice(0, 64)
        small = functools.partial(beam_scan, z[part], x[part], a[part], **common)
        run = functools.partial(beam_scan, z, x, a, **common)
        scene = BeamScene(z, x, None, a, lines, n, depth, k0, s)
        return run, small, z.size, lambda tol: choose_beam_method(scene, Beam(w0, None, None), tol)

    t_all, e_all, chosen, n_scat = _time_sizes(sizes, methods, tols, repeat, case)
    coords = {
        "n_pixels": ([int(s["n_pixels"]) for s in sizes], attrs("count", "pixels N")),
        "n_lines": ([int(s["n_lines"]) for s in sizes], attrs("count", "lines")),
        "density": ([float(s["density"]) for s in sizes], attrs("beam_density")),
        "waist_pitch": (
            [float(s["waist_pitch"]) for s in sizes],
            attrs("waist_pitch", "beam waist w0 / line pitch"),
        ),
        "n_scatterers": (n_scat, attrs("count", "scatterers")),
    }
    meta = {
        "title": "speed versus accuracy of the scanned-beam B-scan methods",
        **_source_attrs(k0_dk, shape, fwhm_fraction, pixel_size, seed, repeat),
        "pitch_um": pitch,
        "scene": "shared 2-D scene: x uniform over the scanned span, z uniform over [0, H), "
        "complex Gaussian amplitudes; beam without focus",
        "reference": "method='direct' on all lines (exact float64); errors over the whole B-scan",
        "note": "timings from a pipeline run are noisy; benchmarks/bench_beam.py is the "
        "reference for speed claims",
    }
    return _chart_dataset(t_all, e_all, chosen, methods, tols, coords, meta)


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
    common = dict(n_pixels=n, depth_range=depth, k0=k0)
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
            attrs("dimensionless", f"measured relative error vs {axis}")
        )
        out[f"predicted_vs_{axis}"] = ds["predicted"].assign_attrs(
            attrs("dimensionless", f"predicted relative error vs {axis}")
        )
    out["density"].attrs.update(attrs("line_density"))
    out["k0_dk"].attrs.update(attrs("k0_dk"))
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
