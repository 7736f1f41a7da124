"""The elastography figures' experiment helpers (private; shared by the data builders of
:mod:`speckle.figures.elastography`): a section's spectrum and seeded scene, its FE inclusion, the
images of one scene under displacement fields, and one labelled strain estimate."""

from __future__ import annotations

from collections.abc import Callable, Mapping

import numpy as np
import xarray as xr

from ..analysis.strain import estimate_strain
from ..imaging._bscan import bscan
from ..scene.deformation import deformable_scene, displace
from ..scene.mechanics import compress_phantom, inclusion_labels
from ..studies.failure import method_options
from ..system.noise import add_complex_noise
from ._config import scene_kwargs, source_spectrum


def _source(cfg: Mapping, k0_dk: float | None = None, fwhm: float | None = None):
    """The section's Gaussian spectrum, ``k0_dk``/``fwhm_fraction`` optionally replaced."""
    override = {"k0_dk": k0_dk, "fwhm_fraction": fwhm}
    return source_spectrum(
        cfg, shape="gaussian", **{k: v for k, v in override.items() if v is not None}
    )


def _scene(cfg: Mapping, seed: int, n_alines: int, density: float, max_strain: float):
    """The seeded deformable scene of the section's grid (:func:`speckle.deformable_scene`)."""
    return deformable_scene(n_alines, density, **scene_kwargs(cfg), seed=seed, strain=max_strain)


def _inclusion_fe(cfg: Mapping, lines: int, strain: float) -> tuple[xr.DataArray, xr.Dataset]:
    """Label image and plane-strain FE solution of the section's circular inclusion on
    ``lines`` A-lines."""
    ic, n, p = cfg["inclusion"], int(cfg["n_pixels"]), float(cfg["pixel_size"])
    depth = np.arange(n) * p
    x = np.arange(lines) * p  # A-line positions of speckle.deformable_scene (pitch = pixel)
    labels = inclusion_labels(
        depth, x, (float(ic["depth_fraction"]) * n * p, x.mean()), float(ic["radius"])
    )
    return labels, compress_phantom(
        labels,
        {0: float(ic["youngs_modulus"][0]), 1: float(ic["youngs_modulus"][1])},
        float(ic["poisson_ratio"]),
        strain=strain,
        contact=ic["contact"],
    )


def _images(
    cfg: Mapping,
    seed: int,
    fields: list[Callable],
    *,
    k0_dk: float | None = None,
    fwhm: float | None = None,
    density: float | None = None,
    n_alines: int | None = None,
    max_strain: float = 0.05,
) -> tuple[list[np.ndarray], float]:
    """Complex images (depth, x) of one seeded scene under each displacement field."""
    src = _source(cfg, k0_dk, fwhm)
    scene = _scene(
        cfg,
        seed,
        int(cfg["n_alines"] if n_alines is None else n_alines),
        float(cfg["density"] if density is None else density),
        max_strain,
    )
    out = []
    for f in fields:
        img = bscan(displace(scene, f), src, method=cfg["method"], tol=cfg["tol"])
        out.append(img.field.transpose("depth", "x").values)
    return out, float(src.attrs["k0"])


def _uniform(s: float) -> Callable:
    return lambda z, x: -s * z


def _noisy(a: np.ndarray, snr_db: float | None, seed: int) -> np.ndarray:
    return a if snr_db is None else add_complex_noise(a, float(snr_db), seed=seed)


def _window(cfg: Mapping, depth: int | None = None) -> tuple[int, int]:
    w = cfg["window"]
    return (int(w[0] if depth is None else depth), int(w[1]))


def _estimate(a1, a2, k0, cfg, label, window=None):
    method, opts = method_options(label)
    return estimate_strain(
        a1,
        a2,
        k0=k0,
        pixel_size=float(cfg["pixel_size"]),
        method=method,
        window=window or _window(cfg),
        **opts,
    )
