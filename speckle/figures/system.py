"""The SD-OCT system targets (``results/system/``): PSF, roll-off and an artefact B-scan.

* :func:`psf_dataset` / :func:`plot_psf`: point reflectors at several depths through a
  wavelength-linear camera with a dispersion mismatch, processed without k-linearisation,
  with it, and with it plus numerical dispersion compensation (``|A|`` in dB).
* :func:`rolloff_dataset` / :func:`plot_rolloff`: the roll-off of a point reflector measured
  through the chain (``measured_db``) against the closed form (``analytic_db``), along ``depth``.
* :func:`artefact_bscan` / :func:`plot_artefact_bscan`: a layered scene with the zero delay
  inside the sample, imaged by a real camera (DC, autocorrelation, mirror image) and processed
  (background subtraction, k-linearisation, dispersion compensation, apodization).

Lengths in µm (in the sample), wavenumbers in rad/µm, levels in dB (``20 log10 |A|``).
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..conventions import attrs, coord
from ..system import spectrometer as sp
from ..system._datasheet import System
from ._config import system_from_config
from .style import colorbar, legend_outside, new_figure

__all__ = [
    "artefact_bscan",
    "dispersion_from_config",
    "plot_artefact_bscan",
    "plot_psf",
    "plot_rolloff",
    "psf_dataset",
    "rolloff_dataset",
    "system_from_config",
]

DB_FLOOR = 1e-12  # amplitude floor before the log (relative)


def dispersion_from_config(cfg: Mapping | None) -> dict[int, float]:
    """``{second: c2, third: c3}`` (µm^2, µm^3) -> ``{2: c2, 3: c3}``."""
    cfg = cfg or {}
    return {p: float(cfg[k]) for p, k in ((2, "second"), (3, "third")) if cfg.get(k)}


def _db(a: np.ndarray, ref: float) -> np.ndarray:
    return 20 * np.log10(np.maximum(np.abs(a) / ref, DB_FLOOR))


def _depth_coord(system: System) -> xr.DataArray:
    return xr.DataArray(
        np.arange(system.n_pixels) * system.pixel_size,
        dims="depth",
        attrs=attrs("depth", "depth in the sample (pixel q at qH/N)"),
    )


def _peak_ref(system: System) -> float:
    """``|A|`` of a unit reflector at zero delay through the ideal chain: ``sum_n S(k_n)``."""
    return float(sp.source_weights(system, sp.grid_wavenumbers(system)).sum())


PSF_VARIANTS = {
    "raw": dict(resample="none", compensate=False),
    "linearised": dict(resample="cubic", compensate=False),
    "compensated": dict(resample="cubic", compensate=True),
}


def psf_dataset(
    system: System, depths: Sequence[float], dispersion: Mapping[int, float]
) -> xr.Dataset:
    """PSFs of unit reflectors at ``depths`` (fractions of ``z_max``) for each processing.

    The camera is wavelength-linear with the system's pixel width and line, real detection, no
    DC; ``raw`` skips k-linearisation and compensation, ``linearised`` resamples with a cubic
    spline, ``compensated`` also removes ``dispersion``. Variables: ``psf_db`` (variant,
    reflector, depth) in dB re. the ideal peak; ``width`` (variant, reflector), the equivalent
    width ``p sum_q |A(q)|^2 / max |A|^2`` over ``[0, z_max)`` in µm (exact whatever the
    sampling, by Parseval; a Gaussian amplitude PSF of FWHM ``dz`` has ``0.7528 dz``).
    """
    frac = np.asarray(depths, dtype=float)
    if np.any((frac <= 0) | (frac >= 1)):
        raise ValueError("depths must be fractions of the imaging depth in (0, 1)")
    z = np.round(frac * system.n_pixels / 2)[:, None] * system.pixel_size
    ref = _peak_ref(system)
    out, widths = [], []
    for opts in PSF_VARIANTS.values():
        img = sp.system_ascan(
            system, z, np.ones_like(z), dispersion=dispersion, resample=opts["resample"],
            compensate=dispersion if opts["compensate"] else None,
        )  # fmt: skip
        power = np.abs(img[:, : system.n_pixels // 2]) ** 2
        out.append(_db(img, ref))
        widths.append(power.sum(axis=-1) / power.max(axis=-1) * system.pixel_size)
    ds = xr.Dataset(
        {
            "psf_db": (("variant", "reflector", "depth"), np.array(out), attrs("level")),
            "width": (("variant", "reflector"), np.array(widths),
                      attrs("length", "equivalent width sum |A|^2 / max |A|^2")),
        },
        coords={
            "variant": list(PSF_VARIANTS),
            "reflector": coord("reflector", z[:, 0]),
            "depth": _depth_coord(system),
        },
        attrs={"axial_resolution": system.axial_resolution, "imaging_depth": system.imaging_depth,
               **{f"dispersion_order_{p}": c for p, c in dispersion.items()}},
    )  # fmt: skip
    return ds


def rolloff_dataset(system: System, n_depths: int, resample: str = "cubic") -> xr.Dataset:
    """Roll-off of a unit reflector at ``n_depths`` pixel-centre depths in ``(0, z_max)``.

    ``measured_db``: ``20 log10(|A(q)|/sum S)`` through the chain (wavelength-linear camera,
    pixel width, spectrometer line, real detection, ``resample``); ``measured_exact_db``: the
    same with exact k-linearisation; ``camera_db``: :meth:`System.rolloff_db` (pixel width and
    spectrometer line at the central pixel); ``analytic_db``: ``camera_db`` plus the
    k-linearisation's own attenuation ``20 log10 |F(z)|``
    (:func:`speckle.system.spectrometer.resampling_response`, 0 dB for ``"exact"``), the
    closed form of the processing used.
    """
    # from 8 px: nearer the zero delay the mirror image's PSF overlaps the reflector's
    q = np.unique(np.linspace(8, system.n_pixels // 2 - 1, n_depths).round().astype(int))
    z = (q * system.pixel_size)[:, None]
    ref = _peak_ref(system)
    measured = {}
    for name, method in (("measured_db", resample), ("measured_exact_db", "exact")):
        img = sp.system_ascan(system, z, np.ones_like(z), resample=method)
        measured[name] = _db(img[np.arange(q.size), q], ref)
    level = attrs("level")
    camera = system.rolloff_db(z[:, 0])
    resampling = 20 * np.log10(np.abs(sp.resampling_response(system, z[:, 0], resample)))
    return xr.Dataset(
        {
            "measured_db": ("depth", measured["measured_db"], {**level, "resample": resample}),
            "measured_exact_db": ("depth", measured["measured_exact_db"], level),
            "camera_db": ("depth", camera, {**level, "long_name": "pixel width and line"}),
            "analytic_db": ("depth", camera + resampling, {**level, "resample": resample,
                            "long_name": "pixel width, line and k-linearisation"}),
        },
        coords={"depth": coord("depth", z[:, 0], "reflector depth")},
        attrs={"imaging_depth": system.imaging_depth, "rolloff_6db": system.rolloff_6db_depth},
    )  # fmt: skip


def layered_scene(
    n_alines: int,
    *,
    surface: float,
    interfaces: Sequence[Mapping],
    density: float,
    pixel_size: float,
    seed: int,
    tilt: float = 0.0,
    scatterer_amplitude: float = 0.1,
) -> tuple[np.ndarray, np.ndarray]:
    """Depths and amplitudes (lines, M) of a layered sample.

    Interfaces ``{depth: µm below the surface, amplitude}`` plus random-phase scatterers of
    amplitude ``scatterer_amplitude`` (``density`` per pixel) between the surface and the
    deepest interface. The surface of line ``i`` sits at ``surface + i*tilt`` µm from the zero
    delay (negative: zero delay inside the sample). Line ``i`` draws from
    ``SeedSequence(seed, spawn_key=(i,))``.
    """
    bottom = max(float(f["depth"]) for f in interfaces)
    m = round(density * bottom / pixel_size)
    zs, amps = [], []
    for i in range(n_alines):
        rng = np.random.default_rng(np.random.SeedSequence(seed, spawn_key=(i,)))
        zi = (
            surface
            + i * tilt
            + np.concatenate([[float(f["depth"]) for f in interfaces], rng.uniform(0, bottom, m)])
        )
        ai = np.concatenate(
            [[float(f["amplitude"]) for f in interfaces],
             scatterer_amplitude * np.exp(2j * np.pi * rng.uniform(size=m))]
        )  # fmt: skip
        zs.append(zi)
        amps.append(ai)
    return np.array(zs), np.array(amps)


def artefact_bscan(
    system: System,
    *,
    n_alines: int,
    surface: float,
    interfaces: Sequence[Mapping],
    density: float,
    dispersion: Mapping[int, float],
    reference_power: float,
    apodization: str,
    seed: int,
    tilt: float = 0.0,
    scatterer_amplitude: float = 0.1,
) -> xr.Dataset:
    """A layered B-scan, raw and processed (``raw_db``, ``processed_db``: depth, x).

    Raw: real camera signal with DC and autocorrelation, transformed as is (no background
    subtraction, no k-linearisation, no compensation, no apodization). Processed: subtraction of the
    reference-arm spectrum ``P_r S`` (recorded with the sample arm blocked: removes the DC, not
    the autocorrelation), cubic k-linearisation, dispersion compensation, ``apodization``. The depth
    axis runs over ``[-H/2, H/2)`` (the FFT's negative depths hold the mirror image), in dB re. the
    processed image's maximum.
    """
    z, a = layered_scene(
        n_alines, surface=surface, interfaces=interfaces, density=density,
        pixel_size=system.pixel_size, seed=seed, tilt=tilt,
        scatterer_amplitude=scatterer_amplitude,
    )  # fmt: skip
    sig, k = sp.camera_signal(
        system, z, a, dc=True, autocorrelation=True, reference_power=reference_power,
        dispersion=dispersion,
    )  # fmt: skip
    grid = sp.grid_wavenumbers(system)
    raw = sp.process_interferogram(sig, grid=grid, k0=system.k0)
    proc = sp.process_interferogram(
        sig, grid=grid, k0=system.k0, wavenumber=k, resample="cubic",
        background=reference_power * sp.source_weights(system, k),
        dispersion=dispersion, apodization=apodization,
    )  # fmt: skip
    n = system.n_pixels
    shift = n // 2
    ref = np.abs(proc).max()
    depth = (np.arange(n) - shift) * system.pixel_size
    return xr.Dataset(
        {
            "raw_db": (("x", "depth"), np.roll(_db(raw, ref), shift, axis=-1), attrs("level")),
            "processed_db": (("x", "depth"), np.roll(_db(proc, ref), shift, axis=-1),
                             attrs("level")),
        },
        coords={
            "depth": coord("depth", depth, "depth from the zero delay"),
            "x": ("x", np.arange(n_alines)),
        },
        attrs={"surface": surface, "tilt": tilt, "apodization": apodization,
               "reference_power": reference_power, "imaging_depth": system.imaging_depth},
    ).transpose("depth", "x")  # fmt: skip


# --- figures ----------------------------------------------------------------------------------
def plot_psf(ds: xr.Dataset) -> Figure:
    """One panel per processing variant: the PSFs of all reflectors (dB)."""
    fig, axes = new_figure(1, ds.sizes["variant"], width=7.5, height=2.6, sharey=True)
    zmax = ds.attrs["imaging_depth"]
    for ax, v in zip(axes[0], ds.variant.values, strict=True):
        for r in ds.reflector.values:
            sel = ds.psf_db.sel(variant=v, reflector=r)
            ax.plot(ds.depth, sel, lw=0.7)
        widths = ", ".join(f"{w:.0f}" for w in ds.width.sel(variant=v).values)
        ax.set_title(f"{v}\nwidths {widths} µm")
        ax.set_xlim(0, zmax)
        ax.set_ylim(-60, 3)
        ax.set_xlabel("depth (µm)")
    axes[0, 0].set_ylabel("|A| (dB re. ideal peak)")
    return fig


def plot_rolloff(ds: xr.Dataset) -> Figure:
    """Measured roll-off (markers) against the closed form (line)."""
    fig, axes = new_figure(1, 1, width=6.5, height=3.2)
    ax = axes[0, 0]
    ax.plot(ds.depth, ds.camera_db, "k:", lw=1, label="analytic, camera only (exact)")
    ax.plot(ds.depth, ds.analytic_db, "k-", lw=1,
            label=f"analytic, {ds.analytic_db.attrs['resample']} resampling")  # fmt: skip
    ax.plot(ds.depth, ds.measured_exact_db, "o", ms=3, mfc="none", label="chain, exact resampling")
    ax.plot(ds.depth, ds.measured_db, "x", ms=3,
            label=f"chain, {ds.measured_db.attrs['resample']} resampling")  # fmt: skip
    ax.set_xlabel("reflector depth (µm, in the sample)")
    ax.set_ylabel("peak intensity (dB)")
    legend_outside(ax)
    return fig


def plot_artefact_bscan(ds: xr.Dataset, dynamic_range: float = 60.0) -> Figure:
    """Raw (DC, autocorrelation, mirror, no linearisation) beside the processed B-scan."""
    fig, axes = new_figure(1, 2, width=7.0, height=3.6, sharey=True)
    extent = [-0.5, ds.sizes["x"] - 0.5, float(ds.depth[-1]), float(ds.depth[0])]
    for ax, name, title in zip(
        axes[0], ("raw_db", "processed_db"), ("raw (FFT of the camera signal)", "processed"),
        strict=True,
    ):  # fmt: skip
        im = ax.imshow(ds[name].values, aspect="auto", cmap="gray", extent=extent,
                       vmin=-dynamic_range, vmax=0)  # fmt: skip
        ax.axhline(0, color="tab:red", lw=0.5, ls=":")
        ax.set_title(title)
        ax.set_xlabel("A-line index")
    axes[0, 0].set_ylabel("depth from zero delay (µm)")
    colorbar(fig, im, axes[0].tolist(), "intensity (dB re the processed peak)")
    return fig
