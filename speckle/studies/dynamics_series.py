"""The pipeline's dynamics phantom and g1 curves: a phantom with static layers, Brownian cells
and a Poiseuille vessel imaged as an angiography protocol and a dOCT series, and |g1| against
lag for each motion model beside its theory. Lengths in µm, times in s, velocities in µm/s."""

from __future__ import annotations

import math

import numpy as np
import xarray as xr

from .._validate import check_int, check_real
from ..analysis.dynamics import (
    g1,
    liv,
    ocds,
    speckle_variance,
    ssada,
)
from ..analysis.dynamics_theory import (
    g1_brownian,
    g1_transverse_flow,
)
from ..conventions import attrs, coord, units_of
from ..imaging.aline import pixel_depths
from ..imaging.scan import beam_reach
from ..imaging.timeseries import bscan_series
from ..imaging.truth import speckle_free_image
from ..scene.motion import brownian_motion, flow_motion, poiseuille_velocity
from ..scene.regions import cell_density, circle, layer, make_regions, region_label
from ..scene.shared import shared_scene
from ..system.noise import add_noise
from ..system.source import spectrum
from ._flow import (
    analysed_rows,
    check_geometry,
    homogeneous_phantom,
    run_attrs,
    scan_options,
    signal_fraction,
    signal_intensity,
    snr_value,
)

__all__ = ["g1_curves", "phantom_series"]


# --- the pipeline's phantom and g1 curves ------------------------------------------------------


def _series(ph: dict, moved: xr.Dataset, kw: dict, snr_db: float, seed: int) -> xr.Dataset:
    """Snapshot B-scans of a moved scene with receiver noise (one stream per frame and line)."""
    out = bscan_series(moved, ph["source"], waist=ph["waist"], lines=ph["lines"], **kw).compute()
    if math.isinf(snr_db):
        return out
    return add_noise(out, snr_db, seed=seed, signal_intensity=ph["signal"])


def g1_curves(
    geometry: dict,
    *,
    diffusion: float,
    velocity: float,
    interval: float,
    n_frames: int,
    blocks: int,
    snr_db: float,
    seed: int,
) -> xr.Dataset:
    """Measured ``|g1|`` against lag of Brownian motion and transverse flow, with theory.

    Each model moves a homogeneous 2-D shared scene (:func:`speckle.scene.motion.brownian_motion`,
    :func:`~speckle.scene.motion.flow_motion` along ``+x``) over ``n_frames`` times
    ``interval`` s apart, images it as repeated B-scans
    (:func:`speckle.imaging.timeseries.bscan_series`) with receiver noise, and measures the
    pooled ``|g1|`` over the analysed rows (:func:`speckle.analysis.dynamics.g1`, standard
    error from ``blocks`` blocks of lines). Theory: ``s g1`` for lags > 0 (``s = SNR/(1 +
    SNR)``, noise uncorrelated between frames) with
    :func:`~speckle.analysis.dynamics_theory.g1_brownian` (the sampled band and the lateral
    steps through the beam) and :func:`~speckle.analysis.dynamics_theory.g1_transverse_flow`.

    Parameters
    ----------
    geometry : dict
        As in :func:`flow_failure`.
    diffusion : float
        ``D`` in µm^2/s (>= 0).
    velocity : float
        Transverse flow velocity in µm/s (>= 0).
    interval : float
        Time between frames in s (> 0).
    n_frames : int
        Frames (>= 2): lags ``0 ... n_frames - 1``.
    blocks : int
        Blocks of lines for the standard error (>= 2).
    snr_db : float
        Receiver SNR in dB (``inf``: no noise).
    seed : int
        Root seed (scene, motion and noise streams spawned from it).

    Returns
    -------
    xarray.Dataset
        Over ``(model, lag)``, ``model`` = ``brownian``, ``transverse_flow`` and ``lag`` in s:
        ``g1`` (measured ``|g1|``), ``g1_se``, ``g1_theory``; over ``model``: ``diffusion``
        (µm^2/s, NaN for flow) and ``velocity`` (µm/s, NaN for Brownian); attrs ``k0``
        (rad/µm, in the medium), ``refractive_index``, ``waist`` (µm), ``snr_db``.

    Examples
    --------
    >>> geo = dict(n_pixels=16, n_lines=8, pixel_size=4.0, k0_dk=10.0, waist=8.0,
    ...            density=4.0, margin=2)
    >>> ds = g1_curves(geo, diffusion=0.5, velocity=1000.0, interval=1e-3, n_frames=3,
    ...                blocks=2, snr_db=30.0, seed=0)
    >>> ds.g1.dims, ds.lag.attrs["units"]
    (('model', 'lag'), 's')
    """
    g = check_geometry(geometry)
    d = check_real(diffusion, "diffusion", low=0)
    v = check_real(velocity, "velocity", low=0)
    dt = check_real(interval, "interval", low=0, low_inclusive=False)
    nf = check_int(n_frames, "n_frames", low=2)
    nb = check_int(blocks, "blocks", low=2, high=int(g["n_lines"]))
    snr = snr_value(snr_db)
    sd = check_int(seed, "seed", low=0)
    kw = scan_options(g)
    rows = analysed_rows(g)
    times = np.arange(nf) * dt
    seeds = np.random.SeedSequence(sd).generate_state(4)
    ph = homogeneous_phantom(g, int(seeds[0]), v * dt * (nf - 1))
    ph["signal"] = signal_intensity(ph, g, kw)
    k0 = float(ph["source"].attrs["k0"])
    s = signal_fraction(snr)
    moved = {
        "brownian": brownian_motion(ph["scene"], times, diffusion=d, seed=int(seeds[1])),
        "transverse_flow": flow_motion(ph["scene"], times, velocity=[0.0, v]),
    }
    theory = {
        "brownian": g1_brownian(
            times, diffusion=d, k0=k0, spectrum=ph["source"], waist=g["waist"], lateral_axes=1
        ),
        "transverse_flow": g1_transverse_flow(times, velocity=v, waist=g["waist"]),
    }
    parts = []
    for name, sc in moved.items():
        series = _series(ph, sc, kw, snr, int(seeds[2]))
        meas = g1(series.field.isel(depth=rows), blocks=nb)
        th = np.where(np.arange(nf) == 0, 1.0, s * theory[name])
        parts.append(
            xr.Dataset(
                {
                    "g1": np.abs(meas.g1).assign_attrs(attrs("correlation", "measured |g1|")),
                    "g1_se": meas.g1_se,
                    "g1_theory": ("lag", th, attrs("correlation", "|g1| theory (with noise)")),
                }
            )
        )
    ds = xr.concat(parts, dim="model", coords="minimal", compat="override")
    ds = ds.assign_coords(model=("model", list(moved)))
    ds["diffusion"] = ("model", [d, np.nan], attrs("diffusion", "diffusion coefficient D"))
    ds["velocity"] = ("model", [np.nan, v], attrs("velocity", "transverse flow velocity"))
    meta = run_attrs(g, nf, (1, 1), 1, sd)
    for key in ("window", "repeats", "motion", "contrasts"):
        meta.pop(key)
    return ds.assign_attrs(
        meta
        | {
            "k0": k0,
            "refractive_index": 1.0,
            "interval": dt,
            "interval_units": units_of("time"),
            "snr_db": snr,
            "blocks": nb,
            "signal_fraction": s,
        }
    )


def phantom_series(
    geometry: dict,
    phantom: dict,
    *,
    snr_db: float,
    seed: int,
) -> xr.Dataset:
    """A phantom imaged as an angiography protocol and as a dynamic-OCT series, with contrasts.

    Static layer 1 (``z < interface``) holding a disc of Brownian "cells", static layer 2 below
    holding a vessel (a band of half-width ``radius`` about ``depth``) with Poiseuille flow
    along ``+x``. The angiography protocol images ``angiography.frames`` snapshot B-scans
    ``angiography.interval`` s apart and computes speckle variance (over the mean intensity
    squared of each pixel's series pooled in the window), SSADA and LIV; the dOCT series images
    ``doct.frames`` B-scans ``doct.interval`` s apart and computes LIV and OCDS (delays
    ``doct.delays``). Receiver noise at ``snr_db`` over the mean signal intensity.

    Parameters
    ----------
    geometry : dict
        As in :func:`flow_failure` (``n_lines`` lines of pitch ``pixel_size``).
    phantom : dict
        ``interface`` (µm), ``backscatter`` (two layers), ``cells`` (``centre`` (z, x) µm,
        ``radius`` µm, ``diffusion`` µm^2/s, ``fraction`` moving), ``vessel`` (``depth``,
        ``radius`` µm, ``peak_velocity`` µm/s), ``angiography`` and ``doct`` (``frames``,
        ``interval`` s; dOCT ``delays`` (s, s)), ``window`` (pixels, lines), ``n_bands``
        (SSADA sub-bands).
    snr_db : float
        Receiver SNR in dB.
    seed : int
        Root seed.

    Returns
    -------
    xarray.Dataset
        The contrast images over ``(depth, x)``: ``labels``, ``structure`` (dB re the mean
        signal), ``speckle_variance``, ``ssada``, ``liv`` (angiography), ``liv_doct``,
        ``ocds`` (dOCT), and over ``region`` each contrast's mean (``<name>_region``).

    Examples
    --------
    >>> geo = dict(n_pixels=16, n_lines=8, pixel_size=4.0, k0_dk=10.0, waist=8.0,
    ...            density=4.0, method="direct")
    >>> ph = dict(interface=24.0, backscatter=[1.0, 2.0],
    ...           cells=dict(centre=[12.0, 16.0], radius=6.0, diffusion=0.5),
    ...           vessel=dict(depth=44.0, radius=8.0, peak_velocity=2000.0),
    ...           angiography=dict(frames=3, interval=2e-3),
    ...           doct=dict(frames=4, interval=4e-3, delays=[4e-3, 8e-3]),
    ...           window=[3, 3], n_bands=2)
    >>> phantom_series(geo, ph, snr_db=30.0, seed=1).ssada.dims
    ('depth', 'x')
    """
    g = check_geometry(geometry)
    sd = check_int(seed, "seed", low=0)
    snr = snr_value(snr_db)
    kw = scan_options(g)
    n, p = int(g["n_pixels"]), float(g["pixel_size"])
    pitch = float(g.get("pitch", p))
    w0 = float(g["waist"])
    src = spectrum(n, n * p, k0_dk=float(g["k0_dk"]))
    lines = np.arange(int(g["n_lines"])) * pitch
    rho = cell_density(float(g["density"]), p, pitch)
    cells, vessel = phantom["cells"], phantom["vessel"]
    b1, b2 = (float(b) for b in phantom["backscatter"])
    regions = make_regions(
        layer(0.0, float(phantom["interface"]), density=rho, backscatter=b1),
        layer(float(phantom["interface"]), n * p, density=rho, backscatter=b2),
        circle(*cells["centre"], cells["radius"], density=rho, backscatter=b1),
        layer(
            float(vessel["depth"]) - float(vessel["radius"]),
            float(vessel["depth"]) + float(vessel["radius"]),
            density=rho,
            backscatter=b2,
        ),
    )
    seeds = np.random.SeedSequence(sd).generate_state(6)
    reach = beam_reach(w0)
    scene = shared_scene(
        regions,
        z_range=(0.0, n * p),
        x_range=(lines[0] - reach, lines[-1] + reach + pitch),
        seed=int(seeds[0]),
        tile=float(g.get("tile", 64.0)),
    )
    ph = {"scene": scene, "source": src, "lines": lines, "waist": w0}
    truth = speckle_free_image(scene, src, waist=w0, lines=lines, **kw)
    ph["signal"] = float(truth.values.mean())
    vel = poiseuille_velocity(
        scene,
        peak_velocity=float(vessel["peak_velocity"]),
        radius=float(vessel["radius"]),
        centre=(float(vessel["depth"]), 0.0),
        direction=(0.0, 1.0),
    )

    def move(times: np.ndarray, key: int) -> xr.Dataset:
        moved = brownian_motion(
            scene,
            times,
            diffusion=float(cells["diffusion"]),
            seed=int(seeds[key]),
            regions=[2],
            fraction=float(cells.get("fraction", 1.0)),
        )
        return flow_motion(moved, times, velocity=vel, regions=[3])

    an, dc = phantom["angiography"], phantom["doct"]
    window = tuple(int(w) for w in phantom["window"])
    t_an = np.arange(int(an["frames"])) * float(an["interval"])
    t_dc = np.arange(int(dc["frames"])) * float(dc["interval"])
    angio = _series(ph, move(t_an, 1), kw, snr, int(seeds[3]))
    doct = _series(ph, move(t_dc, 2), kw, snr, int(seeds[4]))
    mean_i = angio.intensity.mean("time")
    sv = speckle_variance(angio, window=window) / (
        mean_i.rolling(depth=window[0], x=window[1], center=True, min_periods=1).mean() ** 2
    )
    labels = _labels(regions, src, lines)
    out = xr.Dataset(
        {
            "labels": labels,
            "structure": (10 * np.log10(mean_i / ph["signal"])).assign_attrs(
                attrs("dimensionless", "mean intensity, dB re the mean signal")
            ),
            "speckle_variance": sv.assign_attrs(
                attrs("dimensionless", "speckle variance over the local mean intensity squared")
            ),
            "ssada": ssada(angio, n_bands=int(phantom.get("n_bands", 4)), window=window),
            "liv": liv(angio, window=window),
            "liv_doct": liv(doct, window=window),
            "ocds": ocds(doct, delays=tuple(float(t) for t in dc["delays"]), window=window),
        }
    )
    out.attrs.update(
        run_attrs(g, int(an["frames"]), window, 1, sd)
        | {
            "angiography_interval": float(an["interval"]),
            "doct_frames": int(dc["frames"]),
            "doct_interval": float(dc["interval"]),
            "interval_units": units_of("time"),
            "snr_db": snr,
            "region_names": "layer 1, layer 2, cells (Brownian), vessel (Poiseuille flow)",
        }
    )
    for key in ("motion", "contrasts", "repeats"):
        out.attrs.pop(key)
    names = ("speckle_variance", "ssada", "liv", "liv_doct", "ocds")
    region = coord("region", np.arange(4))
    for name in names:
        means = [float(out[name].where(labels == r).mean()) for r in range(4)]
        out[f"{name}_region"] = ("region", means, {**out[name].attrs})
    out = out.assign_coords(region=region)
    return out


def _labels(regions: xr.Dataset, src: xr.DataArray, lines: np.ndarray) -> xr.DataArray:
    """Region label of every pixel centre (depth, x)."""
    depth = pixel_depths(int(src.attrs["n_pixels"]), float(src.attrs["depth_range"]))
    zz, xx = np.meshgrid(depth, lines, indexing="ij")
    lab = np.asarray(region_label(regions, zz, xx))
    return xr.DataArray(
        lab.astype(np.int32),
        dims=("depth", "x"),
        coords={"depth": coord("depth", depth), "x": coord("x", lines)},
        attrs=attrs("label", "region label (0, 1 layers, 2 cells, 3 vessel)"),
    )
