"""Pipeline targets of the scanned beam over shared scenes (``results/beam/``).

* :func:`bscans_data` / :func:`plot_bscans`: B-scans of one shared scene for several
  waist/pitch ratios beside the paper's independent A-lines, with the measured lateral and
  axial correlation against theory (:mod:`speckle.analysis.beam`).
* :func:`strain_data` / :func:`plot_strain`: Fig. 6's correlation versus strain under the
  beam, with and without lateral Poisson expansion, beside the independent-line result.
* :func:`volume_data` / :func:`plot_volume`: a 3-D volume computed lazily by tiles (the
  pipeline streams it to a chunked NetCDF file), and its orthogonal slices.

Each ``*_data`` function computes a dataset, each ``plot_*`` function draws one and returns the
figure; the pipeline scripts write both (atomically).

Config section ``beam`` (lengths in µm; densities in scatterers per pixel x pitch [x pitch]
cell, converted with :func:`speckle.scene.regions.cell_density`).
"""

from __future__ import annotations

from collections.abc import Mapping

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

import speckle

from ..analysis import correlation as corr
from ..analysis.beam import axial_correlation, lateral_correlation, poisson_lateral_factor
from ..conventions import attrs, coord, depth_range_of
from ..imaging.scan import beam_reach
from ..provenance import provenance_attrs
from ..scene import regions as reg
from ..scene.deformation import required_depth, uniaxial_pixel_displacement
from ._config import source_spectrum
from .style import colorbar, legend_outside, new_figure, physical_image

__all__ = [
    "bscans_data",
    "plot_bscans",
    "plot_strain",
    "plot_volume",
    "strain_data",
    "volume_data",
]

#: Amplitude model of the beam scenes; its kurtosis enters the theory.
_AMPLITUDE = "rayleigh"
_KURTOSIS = 2.0


def _source(source: Mapping, n_pixels: int | None = None) -> xr.DataArray:
    """The ``source`` spectrum, with the beam section's own ``n_pixels`` if it gives one."""
    return source_spectrum(source, **({} if n_pixels is None else {"n_pixels": int(n_pixels)}))


def _regions(density_per_cell: float, pixel: float, pitch: float, ndim: int) -> xr.Dataset:
    rho = reg.cell_density(density_per_cell, pixel, pitch, ndim)
    return speckle.make_regions(reg.background(density=rho, amplitude_model=_AMPLITUDE))


def _line_scene(src: xr.DataArray, seed: int) -> dict:
    """Keywords of the independent-line scene builders on the grid of ``src`` (Poisson counts)."""
    n, h = int(src.attrs["n_pixels"]), depth_range_of(src, "source")
    return {
        "n_pixels": n,
        "depth_range": h,
        "seed": seed,
        "amplitude": _AMPLITUDE,
        "count": "poisson",
    }


def _line_method(beam: Mapping) -> str:
    """The A-scan method of the independent lines: ``direct`` or ``nufft`` as the beam's."""
    return "direct" if beam["method"] == "direct" else "nufft"


def _pooled(a: np.ndarray, b: np.ndarray, kind: str) -> float:
    """Pearson coefficient of two equally shaped samples (modulus for complex fields)."""
    if kind == "intensity":
        a, b = np.abs(a) ** 2, np.abs(b) ** 2
    a, b = a.ravel() - a.mean(), b.ravel() - b.mean()
    r = np.vdot(b, a) / np.sqrt(np.vdot(a, a).real * np.vdot(b, b).real)
    return float(abs(r)) if kind == "complex" else float(r.real)


def _lag_correlations(field: np.ndarray, lags: np.ndarray, axis: int) -> dict[str, np.ndarray]:
    """Pooled complex and intensity correlation of a (depth, line) field at lags along ``axis``."""
    out = {}
    for kind in ("complex", "intensity"):
        vals = []
        for lag in lags:
            if axis == 0:  # depth: periodic image (wrap-around), all pairs
                a, b = field, np.roll(field, -int(lag), axis=0)
            else:
                a, b = field[:, : field.shape[1] - lag], field[:, lag:]
            vals.append(_pooled(a, b, kind))
        out[kind] = np.array(vals)
    return out


def bscans_data(source: Mapping, beam: Mapping, seed: int) -> xr.Dataset:
    """B-scans of one shared scene for each waist/pitch ratio, and the independent-line B-scan.

    Returns a Dataset with ``field`` (``waist_pitch, depth, x``), ``independent`` (``depth,
    x``), measured and theoretical lateral (lag in lines) and axial (lag in pixels)
    correlations, complex and intensity.
    """
    src = _source(source, beam.get("n_pixels"))
    n, h = int(src.attrs["n_pixels"]), depth_range_of(src, "source")
    pixel, pitch = h / n, float(beam["pitch"])
    ratios = np.asarray(beam["waist_pitch"], dtype=float)
    xs = speckle.scan_lines(int(beam["n_lines"]), pitch)
    halo = beam_reach(float(ratios.max()) * pitch)
    regions = _regions(float(beam["density"]), pixel, pitch, 2)
    scene = speckle.shared_scene(
        regions, z_range=(0.0, h), x_range=(xs[0] - halo, xs[-1] + halo), seed=seed, tile=64.0
    )
    opts = {"chunk": int(beam["chunk"]), "method": beam["method"], "tol": beam["tol"]}
    images = [
        speckle.scan_image(scene, src, waist=r * pitch, lines=xs, **opts).field for r in ratios
    ]
    field = xr.concat(images, dim="waist_pitch", combine_attrs="drop").compute()
    field = field.assign_coords(waist_pitch=coord("waist_pitch", ratios))
    lines = speckle.random_scatterers(
        xs.size, float(beam["density"]), **_line_scene(src, seed), aline_pitch=pitch
    )
    indep = speckle.bscan(lines, src, method=_line_method(beam), tol=beam["tol"]).field
    indep = indep.assign_coords(x=field.x)
    lat = np.arange(int(beam["lags"]) + 1)
    ax = np.arange(int(beam["lags"]) + 1)
    rho = reg.cell_density(float(beam["density"]), pixel, pitch, 2)
    data = {}
    for name, axis, lags in (("lateral", 1, lat), ("axial", 0, ax)):
        meas = [_lag_correlations(field.sel(waist_pitch=r).values, lags, axis) for r in ratios]
        ind = _lag_correlations(indep.values, lags, axis)
        for kind in ("complex", "intensity"):
            dim = f"{name}_lag"
            data[f"{name}_{kind}"] = (("waist_pitch", dim), np.array([m[kind] for m in meas]))
            data[f"{name}_{kind}_independent"] = ((dim,), ind[kind])
            if name == "lateral":
                th = [lateral_correlation(lags * pitch, r * pitch)[kind].values for r in ratios]
                th_ind = (lags == 0).astype(float)
            else:
                th = [
                    axial_correlation(
                        lags,
                        src.values,
                        density=rho,
                        pixel_size=pixel,
                        waist=r * pitch,
                        kurtosis=_KURTOSIS,
                    )[kind].values
                    for r in ratios
                ]
                th_ind = axial_correlation(
                    lags,
                    src.values,
                    density=float(beam["density"]),
                    pixel_size=pixel,
                    kurtosis=_KURTOSIS,
                )[kind].values
            data[f"{name}_{kind}_theory"] = (("waist_pitch", dim), np.array(th))
            data[f"{name}_{kind}_independent_theory"] = ((dim,), th_ind)
    ds = xr.Dataset(
        {"field": field, "independent": indep, **data},
        coords={"lateral_lag": coord("lateral_lag", lat), "axial_lag": coord("axial_lag", ax)},
    )
    for name in data:
        ds[name].attrs = attrs("correlation", name.replace("_", " "))
    ds.field.attrs = attrs("field", "complex field of the scanned beam")
    ds.independent.attrs = attrs("field", "complex field, independent A-lines")
    ds.attrs.update(
        {
            "pitch": pitch,
            "pitch_units": attrs("length")["units"],
            "density_per_cell": float(beam["density"]),
            "density": rho,
            "density_units": attrs("area_density")["units"],
            "amplitude_model": _AMPLITUDE,
            "k0_dk": float(src.attrs["k0_dk"]),
            "method": beam["method"],
            **provenance_attrs(seed=seed),
        }
    )
    return ds


def _strain_images(scene, src, strains, nu, xs, w0, opts) -> xr.DataArray:
    strained = speckle.uniaxial_strain(scene, strains, poisson_ratio=nu, x_centre=float(xs.mean()))
    return speckle.scan_image(strained, src, waist=w0, lines=xs, **opts).field.compute()


def _compensated_correlations(ref: xr.DataArray, dfm: xr.DataArray) -> dict[str, np.ndarray]:
    """Area correlation after exact axial compensation, per strain."""
    r = ref
    d = dfm
    disp = uniaxial_pixel_displacement(d.strain.values, d.depth.values, d.x.values)
    comp = corr.compensate(d, disp[["uz"]])
    return {kind: corr.pearson(r, comp, kind=kind).values for kind in ("complex", "intensity")}


def strain_data(source: Mapping, beam: Mapping, seed: int) -> xr.Dataset:
    """Correlation vs strain after exact axial compensation: beam (nu = 0 and nu > 0) vs lines.

    Theory for the complex correlation under the beam: the axial factor of
    :func:`speckle.expected_correlation` times the lateral Poisson factor
    (:func:`speckle.analysis.beam.poisson_lateral_factor`) averaged over the lines.
    """
    cfg = beam["strain"]
    src = _source(source, beam.get("n_pixels"))
    n, h = int(src.attrs["n_pixels"]), depth_range_of(src, "source")
    pixel, pitch = h / n, float(beam["pitch"])
    strains = np.linspace(float(cfg["start"]), float(cfg["stop"]), int(cfg["num"]))
    nu = float(cfg["poisson_ratio"])
    w0 = float(cfg["waist_pitch"]) * pitch
    xs = speckle.scan_lines(int(cfg["n_lines"]), pitch)
    smax = float(max(strains.max(), 0.0))
    half = 0.5 * (xs[-1] - xs[0])
    halo = beam_reach(w0) + nu * smax * half + pitch
    regions = _regions(float(beam["density"]), pixel, pitch, 2)
    scene = speckle.shared_scene(
        regions,
        z_range=(0.0, required_depth(h, strains)),
        x_range=(xs[0] - halo, xs[-1] + halo),
        seed=seed,
        tile=64.0,
    )
    opts = {"chunk": int(beam["chunk"]), "method": beam["method"], "tol": beam["tol"]}
    ref = speckle.scan_image(scene, src, waist=w0, lines=xs, **opts).field.compute()
    data = {}
    for label, ratio in (("beam", 0.0), ("beam_poisson", nu)):
        dfm = _strain_images(scene, src, strains, ratio, xs, w0, opts)
        dfm.attrs.update(ref.attrs)
        for kind, vals in _compensated_correlations(ref, dfm).items():
            data[f"{kind}_{label}"] = (("strain",), np.asarray(vals, float))
    lines = speckle.deformable_scene(
        xs.size, float(beam["density"]), **_line_scene(src, seed), strain=strains
    )
    method = _line_method(beam)
    ref_l = speckle.bscan(speckle.uniaxial_strain(lines, 0.0).isel(strain=0), src, method=method)
    dfm_l = speckle.bscan(speckle.uniaxial_strain(lines, strains), src, method=method)
    disp = uniaxial_pixel_displacement(strains, dfm_l.depth.values, dfm_l.x.values)
    comp = corr.compensate(dfm_l, disp[["uz"]])
    for kind in ("complex", "intensity"):
        data[f"{kind}_lines"] = (("strain",), corr.pearson(ref_l, comp, kind=kind).values)
    axial = speckle.expected_correlation(
        strains, spectrum=src, density=float(beam["density"]), kurtosis=_KURTOSIS
    )
    lateral = poisson_lateral_factor(strains, nu, xs, float(xs.mean()), w0).mean(axis=1)
    data["complex_theory"] = (("strain",), axial.complex.values)
    data["complex_poisson_theory"] = (("strain",), axial.complex.values * lateral)
    data["intensity_lines_theory"] = (("strain",), axial.intensity.values)
    ds = xr.Dataset(data, coords={"strain": coord("strain", strains)})
    for name in ds.data_vars:
        ds[name].attrs = attrs("correlation", name.replace("_", " "))
    ds.attrs.update(
        {
            "waist": w0,
            "waist_units": attrs("length")["units"],
            "pitch": pitch,
            "poisson_ratio": nu,
            "density_per_cell": float(beam["density"]),
            "compensation": "exact axial (u_z = -s z), no lateral compensation",
            **provenance_attrs(seed=seed),
        }
    )
    return ds


def volume_data(source: Mapping, beam: Mapping, seed: int) -> xr.Dataset:
    """The 3-D volume of config ``beam.volume``, lazy (Dask): ``field`` (``depth, x, y``).

    Nothing is computed here; :func:`speckle.io.stream_to_netcdf` writes it tile by tile to a
    chunked NetCDF file (the pipeline's ``beam_volume`` rule).
    """
    cfg = beam["volume"]
    src = _source(source, cfg["n_pixels"])
    n, h = int(src.attrs["n_pixels"]), depth_range_of(src, "source")
    pitch = float(beam["pitch"])
    xs = speckle.scan_lines(int(cfg["n_lines"]), pitch)
    regions = _regions(float(cfg["density"]), h / n, pitch, 3)
    ds = speckle.image_regions(
        regions,
        src,
        seed=seed,
        tile=cfg["tile"],
        waist=float(cfg["waist_pitch"]) * pitch,
        lines=xs,
        y=xs,
        chunk=int(cfg["chunk"]),
        method=cfg["method"],
        tol=cfg["tol"],
    )
    ds = ds[["field"]]
    ds.attrs.update(provenance_attrs(seed=seed))
    return ds


def plot_volume(ds: xr.Dataset) -> Figure:
    """Orthogonal slices (x-z, y-z, en-face x-y) of a volume at the physical aspect ratio (1 µm
    = 1 µm on every axis), in dB with one colorbar; only the three slices are read.

    ``ds`` may be a lazily opened file (``speckle.io.open_dataset(path, load=False)``): keep it
    open while this runs.
    """
    f = ds.field
    xm, ym = f.sizes["x"] // 2, f.sizes["y"] // 2
    zm = f.sizes["depth"] // 2
    intensity = {
        "xz": np.abs(f.isel(y=ym).values) ** 2,
        "yz": np.abs(f.isel(x=xm).values) ** 2,
        "xy": np.abs(f.isel(depth=zm).values.T) ** 2,
    }
    titles = {
        "xz": f"x-z slice\nat y = {float(f.y[ym]):.0f} µm",
        "yz": f"y-z slice\nat x = {float(f.x[xm]):.0f} µm",
        "xy": f"en face (x-y) slice\nat depth {float(f.depth[zm]):.0f} µm",
    }
    axes_of = {"xz": (f.depth, f.x, "x"), "yz": (f.depth, f.y, "y"), "xy": (f.y, f.x, "x")}
    depth_span = float(f.depth[-1] - f.depth[0]) or 1.0
    lateral_span = max(float(f.x[-1] - f.x[0]), float(f.y[-1] - f.y[0]), 1e-9)
    # width ratios so the three panels share one height at 1 µm = 1 µm
    ratio = min(lateral_span / depth_span, 1.0)
    fig, axes = new_figure(1, 3, width=7.0, height=4.2, width_ratios=[ratio, ratio, 0.8])
    mean = np.mean([s.mean() for s in intensity.values()])
    im = None
    for ax, key in zip(axes[0], intensity, strict=True):
        rows, cols, xname = axes_of[key]
        im = physical_image(
            ax,
            10 * np.log10(intensity[key] / mean + 1e-12),
            rows.values,
            cols.values,
            xlabel=f"{xname} (µm)",
            cmap="gray",
            vmin=-20,
            vmax=10,
        )
        ax.set_title(titles[key])
        if key == "xy":
            ax.set_ylabel("y (µm)")
        else:
            ax.xaxis.set_major_locator(MaxNLocator(2))
    colorbar(fig, im, axes[0].tolist(), "intensity (dB re the slices' mean)", shrink=0.8)
    return fig


def plot_bscans(ds: xr.Dataset) -> Figure:
    """B-scans (dB) per waist/pitch and independent lines; lateral and axial correlation."""
    ratios = ds.waist_pitch.values
    fig, axes = new_figure(2, max(len(ratios) + 1, 2), width=3.0 * (len(ratios) + 1), height=6)
    imgs = [(f"w0 = {r:g} pitch", ds.field.sel(waist_pitch=r)) for r in ratios]
    imgs.append(("independent A-lines (paper)", ds.independent))
    im = None
    for ax, (title, f) in zip(axes[0], imgs, strict=False):
        i = np.abs(f.values) ** 2
        im = physical_image(
            ax,
            10 * np.log10(i / i.mean() + 1e-12),
            f.depth.values,
            f.x.values,
            xlabel="x (µm)",
            cmap="gray",
            vmin=-20,
            vmax=10,
        )
        ax.xaxis.set_major_locator(MaxNLocator(2))  # 3 labels overlapped on 128 lines
        ax.set_title(title)
    colorbar(fig, im, axes[0].tolist(), "intensity (dB re the image mean)", shrink=0.8)
    for ax, name in zip(axes[1, :2], ("lateral", "axial"), strict=True):
        lag = ds[f"{name}_lag"].values
        for j, r in enumerate(ratios):
            color = f"C{j}"
            for kind, mk in (("complex", "o"), ("intensity", "s")):
                ax.plot(
                    lag,
                    ds[f"{name}_{kind}"].sel(waist_pitch=r),
                    mk,
                    color=color,
                    label=f"w0/pitch {r:g}, {kind}" if name == "lateral" else None,
                )
                ax.plot(
                    lag, ds[f"{name}_{kind}_theory"].sel(waist_pitch=r), "-", color=color, lw=0.8
                )
        for kind, mk in (("complex", "x"), ("intensity", "+")):
            ax.plot(
                lag,
                ds[f"{name}_{kind}_independent"],
                mk,
                color="k",
                label=f"independent lines, {kind}" if name == "lateral" else None,
            )
            ax.plot(lag, ds[f"{name}_{kind}_independent_theory"], ":", color="k", lw=0.8)
        ax.set_xlabel("lag (lines)" if name == "lateral" else "lag (pixels)")
        ax.set_ylabel("correlation")
        ax.set_title(f"{name}: markers measured, lines theory")
    fig.legend(
        *axes[1, 0].get_legend_handles_labels(), loc="outside lower center", ncols=3, frameon=False
    )
    for ax in axes[1, 2:]:
        ax.axis("off")
    return fig


def plot_strain(ds: xr.Dataset) -> Figure:
    """Correlation vs strain: beam without / with Poisson expansion, independent lines."""
    fig, axes = new_figure(1, 2, width=8.0, height=3.2)
    s = 100 * ds.strain.values
    nu = ds.attrs["poisson_ratio"]
    for ax, kind in zip(axes[0], ("complex", "intensity"), strict=True):
        ax.plot(s, ds[f"{kind}_beam"], "o", label="beam, Poisson ratio ν = 0")
        ax.plot(s, ds[f"{kind}_beam_poisson"], "s", label=f"beam, Poisson ratio ν = {nu:g}")
        ax.plot(s, ds[f"{kind}_lines"], "x", color="k", label="independent lines")
        if kind == "complex":
            ax.plot(s, ds.complex_theory, "-", color="C0", lw=0.8, label="theory, ν = 0")
            ax.plot(
                s, ds.complex_poisson_theory, "-", color="C1", lw=0.8, label=f"theory, ν = {nu:g}"
            )
        else:
            ax.plot(s, ds.intensity_lines_theory, ":", color="k", lw=0.8, label="theory, lines")
        ax.set_xlabel("strain (%)")
        ax.set_ylabel(f"{kind} correlation")
        legend_outside(ax)
    return fig
