"""The paper's Fig. 6: correlation maps, correlation versus strain and the non-monotonic question.

Each ``fig6*_data`` function takes plain config sections (``source``, ``fig6``, ``dask``,
``seed``) and returns the dataset the matching ``plot_fig6*`` function draws and returns as a
figure (the pipeline scripts write both). Strain sweeps run through
:func:`speckle.sweep.sweep` (Dask), one task per (spectrum or k0/delta_k, strain) point; every
task rebuilds the same seeded scene, so results do not depend on scheduler or workers.
"""

from __future__ import annotations

import functools
import json
from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib.figure import Figure

from ..analysis import correlation as corr
from ..analysis import correlation_forms as forms
from ..analysis.tracking import interpolate_displacement, track
from ..conventions import attrs
from ..imaging._bscan import bscan
from ..provenance import config_hash, provenance_attrs
from ..scene.deformation import deformable_scene, uniaxial_pixel_displacement, uniaxial_strain
from ..scene.scatterers import amplitude_kurtosis
from ..sweep import sweep
from ..system.source import spectrum as make_spectrum
from ._config import scene_kwargs, spectrum_kwargs
from .style import colorbar, legend_outside, new_figure

__all__ = [
    "fig6a_data",
    "fig6b_data",
    "fig6c_data",
    "make_source",
    "plot_fig6a",
    "plot_fig6b",
    "plot_fig6c",
    "plot_scan",
    "scan_combine",
    "scan_point_data",
    "strain_grid",
]


def strain_grid(spec: Mapping) -> np.ndarray:
    """Strain values from a config mapping ``{start, stop, num}`` (inclusive)."""
    return np.linspace(float(spec["start"]), float(spec["stop"]), int(spec["num"]))


def make_source(
    source: Mapping, k0_dk: float, spectrum: str | None = None, fig6: Mapping | None = None
) -> xr.DataArray:
    """Spectrum for ``k0_dk`` from the shared ``source`` section.

    ``spectrum`` overrides the shape: ``"rectangular"``, ``"gaussian"`` (FWHM
    ``fwhm_fraction*delta_k`` from ``fig6.panel_c`` or ``source``) or ``"two_peak"``
    (``fig6.panel_c.two_peak``).
    """
    shape = spectrum or source["shape"]
    panel = (fig6 or {}).get("panel_c", {})
    if shape == "rectangular":
        options = {"shape": shape}
    elif shape == "gaussian":
        frac = panel.get("gaussian_fwhm_fraction") or source.get("fwhm_fraction")
        options = {"shape": shape, "fwhm_fraction": float(frac)}
    elif shape == "two_peak":
        tp = panel["two_peak"]
        w = forms.two_peak_weights(
            int(source["n_pixels"]),
            separation=float(tp["separation_fraction"]),
            fwhm=float(tp["fwhm_fraction"]),
        )
        options = {"shape": "array", "weights": w}
    else:
        raise ValueError(f"unknown spectrum {shape!r}: rectangular, gaussian or two_peak")
    sp = make_spectrum(**spectrum_kwargs(source, k0_dk=k0_dk, **options))
    return sp.assign_attrs(shape="two_peak") if shape == "two_peak" else sp


def _scene(source: Mapping, fig6: Mapping, seed: int, n_alines: int, max_strain: float):
    return deformable_scene(
        n_alines,
        float(fig6["density"]),
        **scene_kwargs(source),
        seed=seed,
        strain=[0.0, max_strain],
        poisson_ratio=float(fig6["poisson_ratio"]),
        amplitude=fig6["amplitude"],
        count=fig6["count"],
    )


def _images(
    source: Mapping,
    fig6: Mapping,
    seed: int,
    n_alines: int,
    max_strain: float,
    strains: list[float],
    src: xr.DataArray,
) -> xr.Dataset:
    scene = _scene(source, fig6, seed, n_alines, max_strain)
    deformed = uniaxial_strain(
        scene, strains, poisson_ratio=float(fig6["poisson_ratio"]), wrap=bool(fig6["wrap"])
    )
    return bscan(deformed, src, method=fig6["method"], tol=fig6["tol"])


@functools.lru_cache(maxsize=16)
def _reference(
    source_items: tuple,
    fig6_key: str,
    seed: int,
    n_alines: int,
    max_strain: float,
    k0_dk: float,
    spectrum: str,
) -> xr.Dataset:
    """Reference image, computed once per process for every strain of a sweep."""
    source, fig6 = dict(source_items), json.loads(fig6_key)
    src = make_source(source, k0_dk, spectrum, fig6)
    return _images(source, fig6, seed, n_alines, max_strain, [0.0], src).isel(strain=0)


def strain_point(
    k0_dk: float,
    strain: float,
    *,
    spectrum: str,
    source: Mapping,
    fig6: Mapping,
    seed: int,
    n_alines: int,
    max_strain: float,
    carrier_window: int,
) -> xr.Dataset:
    """All correlation estimators between the reference and the image at one strain."""
    src = make_source(source, k0_dk, spectrum, fig6)
    ref = _reference(
        tuple(sorted(source.items())),
        json.dumps(fig6, sort_keys=True),
        seed,
        n_alines,
        max_strain,
        float(k0_dk),
        spectrum,
    )
    dfm = _images(source, fig6, seed, n_alines, max_strain, [float(strain)], src)
    disp = uniaxial_pixel_displacement(
        [float(strain)],
        dfm.depth.values,
        dfm.x.values,
        poisson_ratio=float(fig6["poisson_ratio"]),
    )
    dfm = dfm.isel(strain=0)
    disp = disp.isel(strain=0)
    exact = corr.compensate(dfm, disp)
    # the same positions with the carrier exp(2i k0 u_z) put back
    no_carrier = exact * np.exp(2j * float(dfm.attrs["k0"]) * disp["uz"])
    window = tuple(fig6["window"])
    out = {}
    for kind in corr.KINDS:
        out[f"{kind}_correlation"] = corr.pearson(ref, exact, kind=kind)
        out[f"{kind}_correlation_uncompensated"] = corr.pearson(ref, dfm, kind=kind)
        out[f"{kind}_correlation_windowed"] = corr.correlation_map(
            ref, exact, window=window, kind=kind
        ).mean()
    out["complex_correlation_windowed_no_carrier"] = corr.correlation_map(
        ref, no_carrier, window=(carrier_window, dfm.sizes["x"]), kind="complex"
    ).mean()
    return xr.Dataset({k: xr.DataArray(float(v)) for k, v in out.items()})


_LONG_NAMES = {
    "intensity_correlation": "Pearson correlation of |A|^2 over the scan area, exact compensation",
    "amplitude_correlation": "Pearson correlation of |A| over the scan area, exact compensation",
    "complex_correlation": "|complex Pearson correlation| of A over the scan area, exact "
    "compensation incl. carrier exp(2i k0 u)",
    "intensity_correlation_uncompensated": "Pearson correlation of |A|^2, no compensation",
    "amplitude_correlation_uncompensated": "Pearson correlation of |A|, no compensation",
    "complex_correlation_uncompensated": "|complex correlation| of A, no compensation",
    "intensity_correlation_windowed": "mean of sliding-window |A|^2 correlation, exact comp.",
    "amplitude_correlation_windowed": "mean of sliding-window |A| correlation, exact comp.",
    "complex_correlation_windowed": "mean of sliding-window |complex correlation|, exact comp.",
    "complex_correlation_windowed_no_carrier": "mean of sliding-window |complex correlation|, "
    "positions compensated, carrier phase not",
}


def _strain_sweep(
    grid_name: str,
    grid_values: list,
    strains: np.ndarray,
    *,
    spectrum_of,
    k0_of,
    source: Mapping,
    fig6: Mapping,
    dask: Mapping,
    seed: int,
    n_alines: int,
    carrier_window: int,
) -> xr.Dataset:
    max_strain = float(np.max(strains))

    def point(strain: float, **kw) -> xr.Dataset:
        key = kw[grid_name]
        return strain_point(
            k0_of(key),
            strain,
            spectrum=spectrum_of(key),
            source=source,
            fig6=fig6,
            seed=seed,
            n_alines=n_alines,
            max_strain=max_strain,
            carrier_window=carrier_window,
        )

    ds = sweep(
        point,
        {grid_name: grid_values, "strain": strains.tolist()},
        scheduler=dask["scheduler"],
        address=dask["address"],
        n_workers=dask["n_workers"],
        progress=True,
    )
    for name, long in _LONG_NAMES.items():
        ds[name].attrs.update(attrs("correlation", long))
    ds["strain"].attrs.update(attrs("strain", "compressive strain (u_z = -strain*z)"))
    return ds.merge(_theory(ds, grid_name, k0_of, spectrum_of, source, fig6))


def _theory(
    ds: xr.Dataset, grid_name: str, k0_of, spectrum_of, source: Mapping, fig6: Mapping
) -> xr.Dataset:
    kappa = amplitude_kurtosis(fig6["amplitude"])
    parts = []
    for key in ds[grid_name].values.tolist():
        src = make_source(source, k0_of(key), spectrum_of(key), fig6)
        th = corr.expected_correlation(
            ds.strain.values, spectrum=src, density=float(fig6["density"]), kurtosis=kappa
        )
        parts.append(th.expand_dims({grid_name: [key]}))
    th = xr.concat(parts, dim=grid_name)
    return xr.Dataset(
        {
            "intensity_correlation_theory": th["intensity"].assign_attrs(
                attrs(
                    "correlation",
                    "theory: Pearson |A|^2 after exact compensation (Poisson scatterers)",
                )
            ),
            "complex_correlation_theory": th["complex"].assign_attrs(
                attrs("correlation", "theory: |gamma| after exact compensation")
            ),
            "amplitude_correlation_theory": th["amplitude"].assign_attrs(
                attrs(
                    "correlation",
                    "theory: |A| correlation, Gaussian-speckle limit (no density floor)",
                )
            ),
            "incoherent_floor_theory": th["floor"].assign_attrs(
                attrs(
                    "correlation",
                    "theory: intensity correlation left at gamma = 0 (finite density)",
                )
            ),
        }
    )


def _run_attrs(source: Mapping, fig6: Mapping, seed: int, n_alines: int, shape: str) -> dict:
    return {
        "density": float(fig6["density"]),
        "density_units": attrs("density")["long_name"],
        "spectrum_shape": shape,
        "n_pixels": int(source["n_pixels"]),
        "pixel_size_um": float(source["pixel_size"]),
        "n_alines": n_alines,
        "amplitude_model": fig6["amplitude"],
        "count_model": fig6["count"],
        "poisson_ratio": float(fig6["poisson_ratio"]),
        "wrap": int(bool(fig6["wrap"])),
        "window_pixels": list(fig6["window"]),
        "method": fig6["method"],
        **provenance_attrs({"source": dict(source), "fig6": dict(fig6)}, seed),
    }


def fig6b_data(source: Mapping, fig6: Mapping, dask: Mapping, seed: int) -> xr.Dataset:
    """Area correlation versus strain for several k0/delta_k (``fig6.panel_b``)."""
    panel = fig6["panel_b"]
    strains = strain_grid(panel["strain"])
    shape = source["shape"]
    n_alines = int(fig6["n_alines"])
    ds = _strain_sweep(
        "k0_dk",
        [float(k) for k in panel["k0_dk"]],
        strains,
        spectrum_of=lambda _k: shape,
        k0_of=float,
        source=source,
        fig6=fig6,
        dask=dask,
        seed=seed,
        n_alines=n_alines,
        carrier_window=int(fig6["panel_c"]["carrier_window"]),
    )
    ds["k0_dk"].attrs.update(attrs("k0_dk"))
    run = _run_attrs(source, fig6, seed, n_alines, shape)
    ds.attrs.update(run)
    ds["intensity_correlation"].attrs.update(
        density=run["density"],
        spectrum_shape=shape,
        compensation="exact",
        amplitude_model=run["amplitude_model"],
    )
    return ds.transpose("k0_dk", "strain")


def fig6c_data(source: Mapping, fig6: Mapping, dask: Mapping, seed: int) -> xr.Dataset:
    """k0/delta_k = ``panel_c.k0_dk`` over 0-10 % strain for several spectrum shapes."""
    panel = fig6["panel_c"]
    strains = strain_grid(panel["strain"])
    k0_dk = float(panel["k0_dk"])
    n_alines = int(fig6["n_alines"])
    names = list(panel["spectra"])
    ds = _strain_sweep(
        "spectrum",
        names,
        strains,
        spectrum_of=str,
        k0_of=lambda _s: k0_dk,
        source=source,
        fig6=fig6,
        dask=dask,
        seed=seed,
        n_alines=n_alines,
        carrier_window=int(panel["carrier_window"]),
    )
    w = int(panel["carrier_window"])
    factor = forms.carrier_window_factor(ds.strain.values, k0_dk, w)
    ds["complex_correlation_no_carrier_theory"] = (
        ds["complex_correlation_theory"] * xr.DataArray(factor, dims="strain")
    ).assign_attrs(
        attrs("correlation", f"theory: |gamma| x carrier Dirichlet factor, window {w} px")
    )
    spectra = [make_source(source, k0_dk, name, fig6) for name in names]
    ds["spectrum_weight"] = xr.DataArray(
        np.stack([s.values / s.values.max() for s in spectra]),
        dims=("spectrum", "n"),
        coords={"n": spectra[0].n.values},
        attrs=attrs("weight", "normalised spectral weight S(k_n)"),
    )
    ds.attrs.update(_run_attrs(source, fig6, seed, n_alines, "see spectrum dim"))
    ds.attrs.update(
        k0_dk=k0_dk,
        carrier_window_pixels=w,
        s_ret_paper=1.0 / (2 * k0_dk),
        s_ret_paper_note="2 k0 Lc s_ret = 2 pi with Lc = 2 pi/delta_k",
    )
    return ds


def fig6a_data(source: Mapping, fig6: Mapping, seed: int) -> xr.Dataset:
    """Correlation maps at one strain before and after exact and estimated compensation."""
    panel = fig6["panel_a"]
    strain = float(panel["strain"])
    n_alines = int(panel["n_alines"])
    src = make_source(source, float(panel["k0_dk"]), None, fig6)
    images = _images(source, fig6, seed, n_alines, strain, [0.0, strain], src)
    ref, dfm = images.isel(strain=0), images.isel(strain=1)
    disp = uniaxial_pixel_displacement(
        [strain], ref.depth.values, ref.x.values, poisson_ratio=float(fig6["poisson_ratio"])
    ).isel(strain=0)
    tp = panel["tracking"]
    tracked = track(
        ref,
        dfm,
        window=tuple(tp["window"]),
        step=tuple(tp["step"]),
        upsample=int(tp["upsample"]),
        oversample=int(tp["oversample"]),
        max_error=float(tp["max_error"]),
        truth=disp,
    )
    est = interpolate_displacement(tracked, ref.depth.values, ref.x.values)
    kind = panel["kind"]
    window = tuple(fig6["window"])
    maps = {
        "none": corr.correlation_map(ref, dfm, window=window, kind=kind),
        "exact": corr.correlation_map(ref, corr.compensate(dfm, disp), window=window, kind=kind),
        "tracked": corr.correlation_map(ref, corr.compensate(dfm, est), window=window, kind=kind),
    }
    cmap = xr.concat(list(maps.values()), dim="compensation").assign_coords(compensation=list(maps))
    ds = xr.Dataset(
        {
            "correlation": cmap.drop_vars("strain", errors="ignore").assign_attrs(
                attrs("correlation", f"{kind} correlation in a {window} pixel sliding window")
            ),
            "reference_amplitude": ref["amplitude"]
            .drop_vars("strain")
            .assign_attrs(attrs("amplitude", "reference amplitude |A|")),
            "deformed_amplitude": dfm["amplitude"]
            .drop_vars("strain")
            .assign_attrs(attrs("amplitude", "deformed amplitude |A|")),
            "exact_uz": disp["uz"]
            .drop_vars("strain")
            .assign_attrs(attrs("displacement", "exact axial displacement")),
        }
    )
    trk = tracked.rename({"depth": "window_depth", "x": "window_x"})
    for name in trk.data_vars:
        ds[f"tracked_{name}"] = trk[name]
    ds.attrs.update(_run_attrs(source, fig6, seed, n_alines, src.attrs["shape"]))
    ds.attrs.update(
        strain=strain,
        k0_dk=float(panel["k0_dk"]),
        kind=kind,
        tracking_rms_error_pixels=float(np.sqrt((tracked.uz_residual**2).mean())),
        tracking_failed_fraction=float(tracked.failed.mean()),
    )
    for name in maps:
        ds.attrs[f"mean_correlation_{name}"] = float(cmap.sel(compensation=name).mean())
    return ds


def scan_point_data(
    source: Mapping,
    fig6: Mapping,
    scan: Mapping,
    seed: int,
    *,
    density: float,
    k0_dk: float,
    spectrum: str,
    dask: Mapping | None = None,
) -> xr.Dataset:
    """One point of the decorrelation scan: every estimator versus strain for one scene.

    The scene is Fig. 6's (``fig6``: amplitude and count models, window, method, ...) at
    ``density`` scatterers per pixel, ``k0_dk`` and ``spectrum`` (``"rectangular"``,
    ``"gaussian"``, ``"two_peak"``), imaged over ``scan.strain`` with ``scan.n_alines``
    A-lines, with the theory beside it. The result has dims (``density``, ``k0_dk``,
    ``spectrum``, ``strain``) of sizes (1, 1, 1, S), so :func:`scan_combine` stacks points.
    In the pipeline each point is one Snakemake job (``Paramspace`` over a table), so a scan
    spreads over cluster nodes with an executor plugin.
    """
    point = {**fig6, "density": float(density)}
    n_alines = int(scan["n_alines"])
    ds = _strain_sweep(
        "k0_dk",
        [float(k0_dk)],
        strain_grid(scan["strain"]),
        spectrum_of=lambda _k: spectrum,
        k0_of=float,
        source=source,
        fig6=point,
        dask=dask or {"scheduler": "synchronous", "address": None, "n_workers": 1},
        seed=seed,
        n_alines=n_alines,
        carrier_window=int(fig6["panel_c"]["carrier_window"]),
    )
    ds = ds.expand_dims(density=[float(density)], spectrum=[str(spectrum)])
    ds["density"].attrs.update(attrs("density"))
    ds["k0_dk"].attrs.update(attrs("k0_dk"))
    ds.attrs.update(_run_attrs(source, point, seed, n_alines, str(spectrum)))
    return ds.transpose("density", "k0_dk", "spectrum", "strain")


SCAN_DIMS = ("density", "k0_dk", "spectrum")


def _same(a, b) -> bool:
    return a is not None and np.array_equal(np.asarray(a), np.asarray(b))


def scan_combine(points: list[xr.Dataset]) -> xr.Dataset:
    """Stack scan points into one dataset (``density, k0_dk, spectrum, strain``).

    Combinations missing from the scan table are NaN. Variable and coordinate attributes
    (``units``, ``long_name``) are kept; dataset attributes shared by every point are kept, those
    that differ (density, spectrum shape) are dropped. ``config_sha256`` is the hash of the
    sorted per-point hashes (listed in ``point_config_sha256``), so it changes with any point's
    configuration.

    Raises
    ------
    ValueError
        If ``points`` is empty or two points have the same (density, k0_dk, spectrum).
    """
    if not points:
        raise ValueError("points must hold at least one scan point")
    keys = [tuple(p[d].values.item() for d in SCAN_DIMS) for p in points]
    dup = sorted({k for k in keys if keys.count(k) > 1}, key=str)
    if dup:
        raise ValueError(
            f"scan points must be distinct; (density, k0_dk, spectrum) {dup} appear more than "
            "once (remove the duplicate rows of the scan table)"
        )
    # variable attrs (units, long_name) agree between points: keep them; dataset attrs below
    ds = xr.combine_by_coords(points, join="outer", combine_attrs="drop_conflicts")
    first = points[0].attrs
    ds.attrs = {k: v for k, v in first.items() if all(_same(p.attrs.get(k), v) for p in points[1:])}
    hashes = sorted(str(p.attrs["config_sha256"]) for p in points if "config_sha256" in p.attrs)
    ds.attrs.pop("config_sha256", None)
    if hashes:
        ds.attrs["config_sha256"] = config_hash({"points": hashes})
        ds.attrs["point_config_sha256"] = json.dumps(hashes)
    ds.attrs["scan_points"] = len(points)
    return ds.transpose("density", "k0_dk", "spectrum", "strain")


# --------------------------------------------------------------------------------------------
# Figures
# --------------------------------------------------------------------------------------------


def plot_fig6a(ds: xr.Dataset) -> Figure:
    """Reference image and correlation maps before/after exact and tracked compensation, at the
    physical aspect ratio (mm on both axes)."""
    span_z = float(ds.depth[-1] - ds.depth[0]) or 1.0
    span_x = float(ds.x[-1] - ds.x[0]) or 1.0
    height = min(max(1.5 * span_z / span_x, 2.5), 6.0) + 1.0  # panels at 1 µm = 1 µm
    fig, axes = new_figure(1, 4, width=11, height=height, sharey=True)
    axes = axes[0]
    extent = [
        float(ds.x[0]) / 1e3,
        float(ds.x[-1]) / 1e3,
        float(ds.depth[-1]) / 1e3,
        float(ds.depth[0]) / 1e3,
    ]
    amp = ds.reference_amplitude.transpose("depth", "x")
    ref = axes[0].imshow(
        20 * np.log10(amp / amp.max() + 1e-6),
        cmap="gray",
        vmin=-40,
        vmax=0,
        extent=extent,
        aspect="equal",
    )
    axes[0].set_title("reference image")
    colorbar(fig, ref, axes[0], "|A| (dB re its maximum)", shrink=0.9)
    titles = {
        "none": "before compensation",
        "exact": "after exact compensation",
        "tracked": "after tracked compensation",
    }
    im = None
    for ax, comp in zip(axes[1:], ds.compensation.values, strict=True):
        m = ds.correlation.sel(compensation=comp).transpose("depth", "x")
        im = ax.imshow(m, vmin=0, vmax=1, cmap="viridis", extent=extent, aspect="equal")
        ax.set_title(f"{titles[str(comp)]}\nmean {float(m.mean()):.3f}")
    failed = ds.tracked_failed.values
    if failed.any():
        zz, xx = np.meshgrid(ds.window_depth.values, ds.window_x.values, indexing="ij")
        axes[3].plot(xx[failed] / 1e3, zz[failed] / 1e3, "rx", ms=4, label="tracking failed")
        legend_outside(axes[3])
    for ax in axes:
        ax.set_xlabel("lateral position (mm)")
    axes[0].set_ylabel("depth (mm)")
    fig.colorbar(im, ax=axes[1:], shrink=0.9, label=f"{ds.attrs['kind']} correlation")
    fig.suptitle(
        f"Fig. 6a: {100 * ds.attrs['strain']:g} % uniaxial strain, k0/Δk = {ds.attrs['k0_dk']:g},"
        f" density {ds.attrs['density']:g}/pixel, window {ds.attrs['window_pixels']} px; "
        f"tracking rms error {ds.attrs['tracking_rms_error_pixels']:.3f} px"
    )
    return fig


def _curves(ax, ds: xr.Dataset, dim: str, var: str, theory: str | None, label_of) -> None:
    for i, key in enumerate(ds[dim].values):
        colour = f"C{i}"
        sel = ds.sel({dim: key})
        ax.plot(100 * ds.strain, sel[var], "o", color=colour, ms=4, label=label_of(key))
        if theory is not None:
            ax.plot(100 * ds.strain, sel[theory], "-", color=colour, lw=1)


def _strain_axes(axes, ylabel: str) -> None:
    """Common look of the correlation-versus-strain panels."""
    for ax in axes:
        ax.set_xlabel("strain (%)")
        ax.set_ylabel(ylabel)
        ax.set_ylim(0, 1.02)
        ax.grid(alpha=0.3)
        legend_outside(ax)


def plot_fig6b(ds: xr.Dataset) -> Figure:
    """Intensity correlation versus strain for each k0/delta_k: simulation and theory."""
    fig, axes = new_figure(1, 2, width=11, height=4.2)
    axes = axes[0]
    _curves(
        axes[0],
        ds,
        "k0_dk",
        "intensity_correlation",
        "intensity_correlation_theory",
        lambda k: f"k0/Δk = {k:g}",
    )
    axes[0].set_title("after exact compensation (dots: simulation, lines: theory)")
    _curves(
        axes[1],
        ds,
        "k0_dk",
        "intensity_correlation_uncompensated",
        None,
        lambda k: f"k0/Δk = {k:g}",
    )
    axes[1].set_title("without compensation")
    _strain_axes(axes, "area Pearson correlation of |A|²")
    fig.suptitle(
        f"Fig. 6b: density {ds.attrs['density']:g}/pixel, "
        f"{ds.attrs['spectrum_shape']} spectrum, N = {ds.attrs['n_pixels']}, "
        f"{ds.attrs['n_alines']} A-lines"
    )
    return fig


def plot_fig6c(ds: xr.Dataset) -> Figure:
    """Spectra, intensity correlation to 10 % strain, and carrier-window complex correlation."""
    fig, axes = new_figure(1, 3, width=15, height=4.3)
    axes = axes[0]
    n = ds.n.values / ds.attrs["n_pixels"]
    for i, name in enumerate(ds.spectrum.values):
        axes[0].plot(n, ds.spectrum_weight.sel(spectrum=name), color=f"C{i}", label=str(name))
    axes[0].set_xlabel("(k - k0)/Δk")
    axes[0].set_ylabel("S(k)")
    axes[0].set_title("spectra")
    _curves(axes[1], ds, "spectrum", "intensity_correlation", "intensity_correlation_theory", str)
    axes[1].plot(
        100 * ds.strain,
        ds.incoherent_floor_theory.sel(spectrum="rectangular"),
        ":",
        color="k",
        lw=1,
        label="incoherent floor (rect.)",
    )
    axes[1].axvline(100 * ds.attrs["s_ret_paper"], color="grey", ls="--", lw=0.8)
    axes[1].set_title("|A|² area correlation, exact compensation")
    rect = ds.sel(spectrum="rectangular")
    w = ds.attrs["carrier_window_pixels"]
    axes[2].plot(
        100 * ds.strain,
        rect.complex_correlation,
        "o",
        color="C0",
        ms=4,
        label="|γ| area, carrier removed",
    )
    axes[2].plot(100 * ds.strain, rect.complex_correlation_theory, "-", color="C0", lw=1)
    axes[2].plot(
        100 * ds.strain,
        rect.complex_correlation_windowed_no_carrier,
        "s",
        color="C3",
        ms=4,
        label=f"|γ| in {w}-px windows, carrier kept",
    )
    axes[2].plot(100 * ds.strain, rect.complex_correlation_no_carrier_theory, "-", color="C3", lw=1)
    axes[2].set_title("complex correlation, rectangular spectrum")
    _strain_axes(axes[1:], "correlation")
    fig.suptitle(
        f"Fig. 6c: k0/Δk = {ds.attrs['k0_dk']:g}, density {ds.attrs['density']:g}/"
        "pixel (dots: simulation, lines: theory; grey dashed: the paper's "
        "s_ret = 1/(2 k0/Δk))"
    )
    return fig


def plot_scan(ds: xr.Dataset) -> Figure:
    """Intensity correlation versus strain: one panel per (spectrum, k0/delta_k), one colour per
    density; dots simulation, lines theory, dotted the incoherent floor."""
    pairs = [
        (sp, k)
        for sp in ds.spectrum.values
        for k in ds.k0_dk.values
        if ds.intensity_correlation.sel(spectrum=sp, k0_dk=k).notnull().any()
    ]
    fig, axes = new_figure(1, len(pairs), width=4.2 * len(pairs), height=3.8)
    for ax, (sp, k) in zip(axes[0], pairs, strict=True):
        sel = ds.sel(spectrum=sp, k0_dk=k).dropna(
            "density", how="all", subset=["intensity_correlation"]
        )
        _curves(
            ax,
            sel,
            "density",
            "intensity_correlation",
            "intensity_correlation_theory",
            lambda d: f"density {d:g}/px",
        )
        for i, d in enumerate(sel.density.values):
            ax.plot(
                100 * sel.strain,
                sel.incoherent_floor_theory.sel(density=d),
                ":",
                color=f"C{i}",
                lw=1,
            )
        ax.set_title(f"{sp} spectrum, k0/Δk = {k:g}")
    _strain_axes(axes[0], "area Pearson correlation of |A|², exact compensation")
    fig.suptitle(
        f"Decorrelation scan ({ds.attrs.get('scan_points', len(pairs))} Paramspace jobs): "
        "dots simulation, lines theory, dotted the low-density floor"
    )
    return fig
