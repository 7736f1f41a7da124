"""Helpers shared by the flow studies (private): the homogeneous phantom, its scan options,
the analysed rows, the signal fraction of an SNR and the run attributes."""

from __future__ import annotations

import math

import numpy as np

from .._validate import check_int, check_real
from ..conventions import units_of
from ..imaging.scan import beam_reach
from ..imaging.truth import speckle_free_image
from ..scene.regions import background, cell_density, make_regions
from ..scene.shared import shared_scene
from ..system.source import spectrum

__all__ = [
    "analysed_rows",
    "check_geometry",
    "homogeneous_phantom",
    "run_attrs",
    "scan_options",
    "signal_fraction",
    "signal_intensity",
    "snr_value",
]


def check_geometry(geometry: object) -> dict:
    if not isinstance(geometry, dict):
        raise TypeError("geometry must be a dict (n_pixels, n_lines, pixel_size, ...)")
    g = dict(geometry)
    check_int(g.get("n_pixels"), "geometry.n_pixels", low=8)
    check_int(g.get("n_lines"), "geometry.n_lines", low=2)
    for key in ("pixel_size", "waist", "density", "k0_dk"):
        check_real(g.get(key), f"geometry.{key}", low=0, low_inclusive=False)
    m = check_int(g.get("margin", 4), "geometry.margin", low=0)
    if 2 * m >= int(g["n_pixels"]) - 1:
        raise ValueError("geometry.margin leaves fewer than 2 rows (need 2 margin < n_pixels - 1)")
    return g


def scan_options(geometry: dict) -> dict:
    method = geometry.get("method", "finufft")
    tol = geometry.get("tol", 1e-9) if method != "direct" else None
    return {"method": method, "tol": tol}


def run_attrs(g: dict, nf: int, window: tuple, nr: int, sd: int) -> dict:
    k0 = float(g["k0_dk"]) * math.pi / float(g["pixel_size"])  # k0 = k0_dk * N pi / H
    return {
        "n_pixels": int(g["n_pixels"]),
        "n_lines": int(g["n_lines"]),
        "pixel_size": float(g["pixel_size"]),
        "pitch": float(g.get("pitch", g["pixel_size"])),
        "waist": float(g["waist"]),
        "waist_units": units_of("length"),
        "k0": k0,
        "k0_units": units_of("wavenumber"),
        "density": float(g["density"]),
        "n_frames": nf,
        "window": list(int(w) for w in window),
        "repeats": nr,
        "seed": sd,
        "motion": "transverse flow along +x (uniform), frames translated by v t interval",
        "contrasts": "speckle_variance: var_t(I)/<I>^2 (1/N); decorrelation: ssada of one "
        "band, 1 - mean A_t A_t+1 / ((A_t^2 + A_t+1^2)/2); liv: var_t(10 log10 I) in dB^2 (1/N)",
    }


def homogeneous_phantom(geometry: dict, seed: int, max_shift: float) -> dict:
    """A homogeneous 2-D shared scene wide enough for every shift, its spectrum and lines.

    Equal amplitudes: the non-Gaussian (finite-density) part of the intensity covariance,
    ``E|a|^4/(E|a|^2)^2`` over the scatterers per resolution cell, is half the Rayleigh one.
    """
    n = int(geometry["n_pixels"])
    p = float(geometry["pixel_size"])
    pitch = float(geometry.get("pitch", p))
    w0 = float(geometry["waist"])
    src = spectrum(n, n * p, k0_dk=float(geometry["k0_dk"]))
    lines = np.arange(int(geometry["n_lines"])) * pitch
    reach = beam_reach(w0)
    rho = cell_density(float(geometry["density"]), p, pitch)
    scene = shared_scene(
        make_regions(background(density=rho, amplitude_model="equal")),
        z_range=(0.0, n * p),
        x_range=(lines[0] - max_shift - reach, lines[-1] + reach + pitch),
        seed=seed,
        tile=float(geometry.get("tile", 64.0)),
    )
    return {"scene": scene, "source": src, "lines": lines, "waist": w0}


def analysed_rows(geometry: dict) -> slice:
    """Depth rows analysed: away from the scene's top and bottom (the PSF is cut there)."""
    m = int(geometry.get("margin", 4))
    return slice(m, int(geometry["n_pixels"]) - m)


def signal_fraction(snr_db: float) -> float:
    """``s = SNR/(1 + SNR)``: the field correlation of two frames of one static pixel."""
    snr = snr_value(snr_db)
    return 1.0 if math.isinf(snr) else 1.0 / (1.0 + 10.0 ** (-snr / 10.0))


def signal_intensity(ph: dict, g: dict, kw: dict) -> float:
    """Expected signal intensity ``E|A|^2`` of the analysed rows (speckle-free image)."""
    truth = speckle_free_image(
        ph["scene"], ph["source"], waist=ph["waist"], lines=ph["lines"], **kw
    )
    return float(truth.values[analysed_rows(g)].mean())


def snr_value(snr_db: object) -> float:
    """SNR in dB: a real number in [-300, 300], or +inf (no noise)."""
    if isinstance(snr_db, int | float | np.floating) and np.isposinf(snr_db):
        return math.inf
    return check_real(snr_db, "snr_db", low=-300.0, high=300.0)
