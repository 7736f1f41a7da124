"""The phantom fit's closed loop (issue 34): one virtual patient scanned, fitted and compared.

:func:`phantom_closed_loop_case` draws a virtual patient (:func:`speckle.virtual_patient`),
scans it (:func:`speckle.synthoct_scan`), fits it (:func:`speckle.fit_phantom`) and compares,
layer by layer: the boundary (the largest distance between the fitted and the true profile
over the fitted lines, ``|x| <= x_max/2 - 3 r``, in pixels), and the pull ``(fit - truth)/SE``
of the top (mean depth), the attenuation ``mu``, ``rho E/100`` and, where the fit identifies
it, the density and the energy. A case succeeds when the layer count is right and every
boundary is within a pixel; otherwise ``failure`` names the first reason. With ``fit_seed`` the
case also holds the scans that the challenge's scoring compares: the fitted phantom drawn with
``fit_seed`` and scanned, and the floor, the true patient drawn again with ``fit_seed``.

Inclusions (``inclusions`` of the patient, one or several; the fit looks for them when
``fit_inclusions``, by default when the patient holds any): a true inclusion is *found* when a
fitted inclusion's centre lies inside the true ellipse (each fitted one matched at most once,
the true ones in order, the fitted centre nearest in the ellipse's own units); the case
reports the count fitted, the true ones found, the fitted inclusions not matched to a true one
(false alarms), and for the first true inclusion the centre error (the larger of the lateral
error in lines and the depth error in pixels), the pulls of :data:`INCLUSION_PULLED` and the
density's lower bound where the density is not identified. The case's ``success`` remains the
layers' (count and boundaries).

The window's top (:data:`WINDOW_SCALARS`): the fit's ``window_top`` and its SE against the true
one, ``20 log10 max |A|`` of the target's own complex field (the scanner puts its 51 dB
window's top at the image's maximum), in dB, and their pull.
"""

from __future__ import annotations

import numpy as np
import xarray as xr

from ...conventions import attrs, coord
from ...synthoct import _scan
from ...synthoct.scanner import synthoct_scan
from ._fit import fit_phantom
from .patients import scanner_config_of, virtual_patient

__all__ = [
    "INCLUSION_PULLED",
    "PULLED",
    "WINDOW_SCALARS",
    "fit_profiles",
    "phantom_closed_loop_case",
]

#: Parameters whose pulls the case reports (the fit's and the truth's variable names).
PULLED = ("top", "attenuation", "rho_e", "density", "energy")
#: The inclusion's pulled parameters: the fit's name -> the truth's (``rho_e``: density x
#: energy/100).
INCLUSION_PULLED = {
    "centre_x": "inclusion_x",
    "centre_z": "inclusion_z",
    "axis_x": "inclusion_width",
    "axis_z": "inclusion_height",
    "rho_e": "rho_e",
    "rho_e_shadow": "rho_e",
    "density": "inclusion_density",
}
#: The case's inclusion scalars (NaN without a true inclusion), in order.
INCLUSION_SCALARS = (
    "n_inclusions_true",
    "n_inclusions_fit",
    "inclusion_found",
    "inclusion_false_alarms",
    "inclusion_centre_error",
    *(f"{k}_{p}" for p in INCLUSION_PULLED for k in ("true_inclusion", "fit_inclusion")),
    *(f"fit_inclusion_{p}_se" for p in INCLUSION_PULLED),
    *(f"inclusion_{p}_pull" for p in INCLUSION_PULLED),
    "fit_inclusion_density_bound",
)
#: The case's window scalars (dB re ``|A| = 1``; the pull dimensionless), in order.
WINDOW_SCALARS = ("true_window_top", "fit_window_top", "fit_window_top_se", "window_top_pull")


def inclusion_scores(inclusions: xr.Dataset, truth: xr.Dataset, cfg) -> dict:
    """The case's inclusion scalars (:data:`INCLUSION_SCALARS`) from the fitted inclusions and
    the patient's truth: ``{name: (value, attrs)}``."""
    n_true, n_fit = truth.sizes["inclusion"], inclusions.sizes["inclusion"]
    out = {
        "n_inclusions_true": (n_true, attrs("count", "true inclusions")),
        "n_inclusions_fit": (n_fit, attrs("count", "fitted inclusions")),
    }
    matches, used = [], set()
    for j in range(n_true):
        xc, zc = float(truth.inclusion_x[j]), float(truth.inclusion_z[j])
        w, h = float(truth.inclusion_width[j]), float(truth.inclusion_height[j])
        inside = ((inclusions.centre_x.values - xc) / w) ** 2 + (
            (inclusions.centre_z.values - zc) / h
        ) ** 2
        inside[list(used)] = np.inf
        matches.append(int(np.argmin(inside)) if n_fit and float(np.min(inside)) < 1 else -1)
        used.add(matches[-1])
    n_found = sum(m >= 0 for m in matches)
    match = matches[0] if n_true else -1
    found = match >= 0
    out["inclusion_found"] = (
        n_found if n_true else -1,
        attrs("label", "true inclusions found (1 or 0 for one), none in the patient (-1)"),
    )
    out["inclusion_false_alarms"] = (
        n_fit - n_found,
        attrs("count", "fitted inclusions not matched to a true one"),
    )
    error = np.nan
    if found:
        xc, zc = float(truth.inclusion_x[0]), float(truth.inclusion_z[0])
        dx = abs(float(inclusions.centre_x[match]) - xc) / cfg.line_pitch
        dz = abs(float(inclusions.centre_z[match]) - zc) / cfg.pixel_size
        error = max(dx, dz)
    out["inclusion_centre_error"] = (
        error, attrs("pixels", "larger of the first inclusion's lateral (lines) and depth "
                     "(pixels) errors")
    )  # fmt: skip
    for p, t_name in INCLUSION_PULLED.items():
        q = inclusions[p].attrs
        long = p.replace("_", " ")
        t = f = s = np.nan
        if n_true:
            if t_name == "rho_e":
                t = float(truth.inclusion_density[0] * truth.inclusion_energy[0] / 100)
            else:
                t = float(truth[t_name][0])
        if found:
            f, s = float(inclusions[p][match]), float(inclusions[f"{p}_se"][match])
        out[f"true_inclusion_{p}"] = (t, {**q, "long_name": f"true inclusion {long}"})
        out[f"fit_inclusion_{p}"] = (f, {**q, "long_name": f"fitted inclusion {long}"})
        out[f"fit_inclusion_{p}_se"] = (
            s, {**q, "long_name": f"standard error of fitted inclusion {long}"}
        )  # fmt: skip
        pull = (f - t) / s if found and s > 0 else np.nan
        out[f"inclusion_{p}_pull"] = (
            pull, attrs("dimensionless", f"(fit - truth)/SE of the inclusion's {long}")
        )  # fmt: skip
    bound = float(inclusions.density_bound[match]) if found else np.nan
    out["fit_inclusion_density_bound"] = (
        bound, {**inclusions.density_bound.attrs, "long_name": "fitted inclusion's density bound"}
    )  # fmt: skip
    return {k: out[k] for k in INCLUSION_SCALARS}


def fit_profiles(layers: xr.Dataset, x: np.ndarray, x_max: float) -> np.ndarray:
    """Fitted boundary profiles ``(layer, x)`` in µm: ``top + tilt x + curvature (x^2 -
    X^2/12)`` (flat where the fit has no shape variables)."""
    x = np.asarray(x, float)
    top = layers.top.values[:, None]
    tilt = layers["top_tilt"].values[:, None] if "top_tilt" in layers else 0.0
    curv = layers["top_curvature"].values[:, None] if "top_curvature" in layers else 0.0
    return top + tilt * x + curv * (x**2 - x_max**2 / 12)


def phantom_closed_loop_case(
    seed: int,
    *,
    config: object = "challenge",
    fit_seed: int | None = None,
    max_layers: int = 5,
    fit_inclusions: bool | None = None,
    **patient: object,
) -> xr.Dataset:
    """One closed-loop case: a virtual patient scanned, fitted back and compared with its truth.

    Parameters
    ----------
    seed : int
        The patient's seed (:func:`speckle.virtual_patient`).
    config : str or ScannerConfig
        ``"challenge"``, ``"2025"`` or a configuration.
    fit_seed : int, optional
        Seed of the fitted phantom's draw and of the true patient's second draw: with it the
        case holds ``fitted_scan`` and ``floor_scan`` (two more scanner calls).
    max_layers : int
        Most layers the fit tries (1..10).
    fit_inclusions : bool, optional
        Whether the fit looks for inclusions (:func:`speckle.fit_phantom`'s ``inclusions``);
        default: when the patient holds any (``inclusions``).
    **patient
        Options of :func:`speckle.virtual_patient` (``layers``, ``shapes``, ``inclusions``,
        ...).

    Returns
    -------
    xarray.Dataset
        Dim ``layer`` (the true layers): ``true_<p>``, ``fit_<p>``, ``fit_<p>_se`` and
        ``<p>_pull`` for ``p`` in :data:`PULLED` (the fitted layer matched by order when the
        count is right, else the one of nearest top), ``boundary_error`` (pixels), ``true_shape``
        and ``fit_shape``; the inclusion scalars (module docstring: ``n_inclusions_true``,
        ``n_inclusions_fit``, ``inclusion_found``, ``inclusion_false_alarms``,
        ``inclusion_centre_error`` in pixels, ``true_inclusion_<p>``, ``fit_inclusion_<p>``,
        ``fit_inclusion_<p>_se``, ``inclusion_<p>_pull`` for ``p`` in
        :data:`INCLUSION_PULLED`); the window's top (:data:`WINDOW_SCALARS`, dB: the true
        one from the target's complex field); scalars ``n_true``, ``n_fit``, ``layers_right``,
        ``boundaries_right``,
        ``success`` and ``failure`` (empty on success); ``target_scan`` ``(depth, x)`` and, with
        ``fit_seed``, ``fitted_scan`` and ``floor_scan``. Attributes: ``seed``, ``fit_seed``
        (-1 without), the fit's ``criterion``.

    Raises
    ------
    TypeError, ValueError
        A bad seed, config or option (as :func:`speckle.virtual_patient` and
        :func:`speckle.fit_phantom` refuse them), before any scan.

    Examples
    --------
    >>> import speckle
    >>> cfg = speckle.ScannerConfig(n_pixels=128, n_lines=128, x_max=768.0, n_scatterers=37_500)
    >>> case = speckle.phantom_closed_loop_case(0, config=cfg, layers=(2, 2), shapes=("flat",))
    >>> bool(case.layers_right), bool(case.success)
    (True, True)
    """
    if fit_seed is not None and (
        isinstance(fit_seed, bool) or not isinstance(fit_seed, int | np.integer) or fit_seed < 0
    ):
        raise ValueError(f"fit_seed must be None or a non-negative integer, got {fit_seed!r}")
    if isinstance(max_layers, bool) or not isinstance(max_layers, int) or not 1 <= max_layers <= 10:
        raise ValueError(f"max_layers must be an integer in 1..10, got {max_layers!r}")
    if fit_inclusions is None:
        fit_inclusions = bool(patient.get("inclusions", False))
    if not isinstance(fit_inclusions, bool):
        raise TypeError(f"fit_inclusions must be None or a bool, got {fit_inclusions!r}")
    cfg = scanner_config_of(config)
    table, truth = virtual_patient(seed, config=cfg, **patient)
    field = synthoct_scan(table, cfg, field=True, nthreads=1)
    scan = _scan.to_levels(field.values)  # the scan: the field's 8-bit window
    fit = fit_phantom(scan, cfg, max_layers=max_layers, inclusions=fit_inclusions)
    layers = fit.layers
    n_true, n_fit = truth.sizes["layer"], layers.sizes["layer"]
    if n_fit == n_true:
        match = np.arange(n_true)
    else:
        match = np.array(
            [int(np.argmin(np.abs(layers.top.values - t))) for t in truth.top_mean.values]
        )
    central = np.abs(cfg.line_positions) <= cfg.x_max / 2 - 3 * cfg.beam_radius
    xs = cfg.line_positions[central]
    fitted = fit_profiles(layers, xs, cfg.x_max)[match]
    error = np.max(np.abs(fitted - truth.top.values[:, central]), axis=1) / cfg.pixel_size
    true_of = {"top": truth.top_mean.values}
    data = {}
    for p in PULLED:
        t = true_of.get(p, truth[p].values if p in truth else None)
        f = layers[p].values[match]
        s = layers[f"{p}_se"].values[match]
        long = p.replace("_", " ")
        q = layers[p].attrs
        data[f"true_{p}"] = ("layer", t, {**q, "long_name": f"true {long}"})
        data[f"fit_{p}"] = ("layer", f, {**q, "long_name": f"fitted {long}"})
        data[f"fit_{p}_se"] = ("layer", s, {**q, "long_name": f"standard error of fitted {long}"})
        with np.errstate(invalid="ignore", divide="ignore"):
            pull = np.where(s > 0, (f - t) / s, np.nan)
        data[f"{p}_pull"] = ("layer", pull, attrs("dimensionless", f"(fit - truth)/SE of {long}"))
    data["top_pull"][1][0] = np.nan  # the surface is not fitted (0 by construction)
    layers_right = n_fit == n_true
    boundaries_right = bool(np.all(error < 1.0))
    failure = ""
    if not layers_right:
        failure = f"layer count: {n_fit} fitted, {n_true} true"
    elif not boundaries_right:
        k = int(np.argmax(error))
        failure = f"boundary {k}: {error[k]:.2f} px off"
    fit_shape = layers["shape"].values[match] if "shape" in layers else ["flat"] * n_true
    data.update(
        boundary_error=("layer", error, attrs("pixels", "largest |fit - true| of the boundary")),
        true_shape=("layer", truth.shape.values, attrs("label", "true boundary shape")),
        fit_shape=("layer", np.asarray(fit_shape, dtype=object),
                   attrs("label", "fitted boundary shape")),
        n_true=((), n_true, attrs("count", "true layers")),
        n_fit=((), n_fit, attrs("count", "fitted layers")),
        layers_right=((), layers_right, attrs("label", "layer count right")),
        boundaries_right=((), boundaries_right, attrs("label", "every boundary within a pixel")),
        success=((), layers_right and boundaries_right, attrs("label", "case succeeded")),
        failure=((), failure, attrs("label", "why the case failed (empty on success)")),
        target_scan=(("depth", "x"), scan, attrs("label", "target scan")),
    )  # fmt: skip
    for name, (value, attr) in inclusion_scores(fit.inclusions, truth, cfg).items():
        data[name] = ((), value, attr)
    window = (20 * np.log10(np.abs(field.values).max()), layers.attrs["window_top"],
              layers.attrs["window_top_se"])  # fmt: skip
    pull = (window[1] - window[0]) / window[2] if window[2] > 0 else np.nan
    for name, value, long in zip(WINDOW_SCALARS, (*window, pull),
                                 ("true window top (20 log10 max |A|)", "fitted window top",
                                  "standard error of fitted window top",
                                  "(fit - truth)/SE of window top"), strict=True):  # fmt: skip
        data[name] = ((), float(value), attrs("dimensionless" if "pull" in name else "level", long))
    if fit_seed is not None:
        floor_table, _ = virtual_patient(seed, config=cfg, draw_seed=int(fit_seed), **patient)
        data["fitted_scan"] = (("depth", "x"), fit.render(int(fit_seed), nthreads=1).values,
                               attrs("label", "fitted phantom's scan (fit_seed)"))  # fmt: skip
        data["floor_scan"] = (("depth", "x"), synthoct_scan(floor_table, cfg, nthreads=1).values,
                              attrs("label", "true patient's scan (fit_seed)"))  # fmt: skip
    return xr.Dataset(
        data,
        coords={
            "layer": coord("layer", np.arange(n_true)),
            "depth": field["depth"],
            "x": field["x"],
        },
        attrs={
            "seed": int(seed),
            "fit_seed": -1 if fit_seed is None else int(fit_seed),
            "criterion": layers.attrs["criterion"],
        },
    )
