"""Static speckle: the paper's Figs. 1, 2 and 5 (data sets and figures).

* Fig. 1 (:func:`single_scatterer`, :func:`plot_single_scatterer`): pixel image of one
  unit-amplitude scatterer at 0, 1 and 1.25 pixels and its spectral components
  ``S_n a exp(2i k_n z0)``. ``k0 = 0`` is the formal Fourier transform of the paper's Fig. 1
  (with ``dk = pi/H`` and the round-trip phase ``2 k_n z`` it equals the formal transform with
  spacing ``2 pi/H``); ``k0 != 0`` only adds the common phase ``2 k0 z0``.
* Fig. 2 (:func:`density_sweep`, :func:`plot_density_fragments`): B-scans for several scatterer
  densities, amplitudes divided by ``sqrt(density)``, one dataset with a ``density`` dim.
* Fig. 5 (:func:`k0_sweep`, :func:`plot_k0_fragments`): the same scatterers imaged for several
  ``k0/delta_k``, with amplitude histograms and Rayleigh fits, one dataset with a ``k0_dk`` dim.

Lengths in µm, wavenumbers in rad/µm. Sweeps run with :func:`speckle.sweep.sweep` (Dask); every
point derives its scatterers from ``seed`` only, so results do not depend on the scheduler.
"""

from __future__ import annotations

import inspect
from collections.abc import Mapping, Sequence

import numpy as np
import xarray as xr
from matplotlib.figure import Figure
from matplotlib.ticker import MaxNLocator

from .._validate import as_finite_array, check_int
from ..analysis.statistics import fit_rayleigh, histogram, rayleigh_pdf
from ..conventions import attrs, canonical_keys, coord, depth_range_of
from ..imaging.aline import ascan, pixel_depths
from ..provenance import provenance_attrs
from ..sweep import sweep
from ._config import dask_options, random_bscan, source_options, source_spectrum
from .style import colorbar, new_figure, physical_image

__all__ = [
    "dask_options",
    "density_sweep",
    "fragment",
    "k0_sweep",
    "plot_density_fragments",
    "plot_k0_fragments",
    "plot_single_scatterer",
    "single_scatterer",
    "source_options",
    "source_spectrum",
    "speckle_image",
]


# --- Fig. 1 -------------------------------------------------------------------------------


def single_scatterer(
    positions: Sequence[float],
    k0_dk: Sequence[float],
    *,
    n_pixels: int,
    pixel_size: float,
    shape: str = "rectangular",
    fwhm_fraction: float | None = None,
) -> xr.Dataset:
    """A-scans and spectral components of one unit-amplitude scatterer (the paper's Fig. 1).

    Parameters
    ----------
    positions : sequence of float
        Scatterer depths in pixels (units of ``H/N``), e.g. ``[0, 1, 1.25]``.
    k0_dk : sequence of float
        Values of ``k0/delta_k`` (>= 0); ``0`` is the formal Fourier transform.
    n_pixels, pixel_size, shape, fwhm_fraction
        Source, see :func:`source_spectrum`.

    Returns
    -------
    xarray.Dataset
        ``ascan`` (complex, dims ``k0_dk, position, depth``): ``A(q)`` of Eq. 4 (no
        normalisation); ``spectral_component`` (complex, dims ``k0_dk, position, wavenumber``):
        ``S_n exp(2i k_n z0)``, whose DFT over ``n`` is ``A(q)``; ``spectrum`` ``S_n``;
        coordinates ``position`` (pixels), ``z0`` (µm), ``depth`` (µm), ``pixel``, ``n``
        (spectral index) and ``k`` (``k_n`` in rad/µm, dims ``k0_dk, wavenumber``).
    """
    pos = as_finite_array(positions, "positions")
    ratios = as_finite_array(k0_dk, "k0_dk")
    if pos.ndim != 1 or ratios.ndim != 1 or pos.size == 0 or ratios.size == 0:
        raise ValueError("positions and k0_dk must be non-empty 1-D sequences")
    source = {"n_pixels": n_pixels, "pixel_size": pixel_size, "shape": shape}
    source["fwhm_fraction"] = fwhm_fraction
    sources = [source_spectrum(source, k0_dk=r) for r in ratios]
    h = depth_range_of(sources[0], "source")
    n = int(sources[0].attrs["n_pixels"])
    z0 = pos * (h / n)
    scans, comps, ks = [], [], []
    for src in sources:
        k = src.wavenumber.values
        k0 = float(src.attrs["k0"])
        scans.append(
            ascan(
                z0[:, None],
                np.ones((z0.size, 1)),
                n_pixels=n,
                depth_range=h,
                k0=k0,
                spectrum=src.values,
            )
        )
        comps.append(src.values * np.exp(2j * np.outer(z0, k)))
        ks.append(k)
    return xr.Dataset(
        {
            "ascan": (
                ("k0_dk", "position", "depth"),
                np.stack(scans),
                attrs("field", "pixel field A(q) of one unit scatterer"),
            ),
            "spectral_component": (
                ("k0_dk", "position", "wavenumber"),
                np.stack(comps),
                attrs("field", "spectral component S(k_n) exp(2i k_n z0)"),
            ),
            "spectrum": (("wavenumber",), sources[0].values, attrs("weight")),
        },
        coords={
            "k0_dk": coord("k0_dk", ratios),
            "position": coord("position", pos),
            "z0": coord("z", z0, dims="position"),
            "depth": coord("depth", pixel_depths(n, h), "depth of pixel centre q*H/N"),
            "pixel": coord("pixel", np.arange(n), dims="depth"),
            "n": coord("n", sources[0].n.values, dims="wavenumber"),
            "k": (
                ("k0_dk", "wavenumber"),
                np.stack(ks),
                attrs("wavenumber", "wavenumber k_n = k0 + n*pi/H"),
            ),
        },
        attrs={
            "n_pixels": n,
            "depth_range": h,
            "pixel_size": h / n,
            "spectrum_shape": shape,
            "fwhm_fraction": np.nan if fwhm_fraction is None else float(fwhm_fraction),
            **provenance_attrs(),
        },
    )


def plot_single_scatterer(ds: xr.Dataset) -> Figure:
    """Fig. 1: pixel images ``|A(q)|`` (left) and spectral components (right) per position.

    One row per scatterer position; the right-hand columns show ``Re`` and ``Im`` of the
    spectral components for each ``k0/delta_k`` in ``ds`` (``k0 = 0``: formal Fourier
    transform). The amplitude image does not depend on ``k0``; it is drawn for the first value.
    """
    npos, nk = ds.sizes["position"], ds.sizes["k0_dk"]
    fig, axes = new_figure(
        npos, 1 + nk, width=3.0 + 2.6 * nk, height=1.6 * npos + 0.4, sharex="col"
    )
    q = ds.pixel.values
    for i in range(npos):
        row = ds.isel(position=i)
        ax = axes[i, 0]
        amp = np.abs(row.ascan.isel(k0_dk=0).values)
        ax.bar(q, amp, width=0.9, color="0.6", edgecolor="k", linewidth=0.5)
        ax.plot([float(row.position)], [amp.max() * 1.08], "k*", ms=7)
        ax.set_xlim(q[0] - 0.5, q[-1] + 0.5)
        ax.set_ylim(0, amp.max() * 1.2)
        ax.set_ylabel("|A(q)|")
        ax.set_title(f"z0 = {float(row.position):g} px = {float(row.z0):.3g} µm")
        for j in range(nk):
            comp = row.spectral_component.isel(k0_dk=j).values
            ax = axes[i, 1 + j]
            n = ds.n.values
            ax.vlines(n - 0.12, 0, comp.real, color="C0", lw=1.2, label="real part")
            ax.vlines(n + 0.12, 0, comp.imag, color="C3", lw=1.2, label="imaginary part")
            ax.axhline(0, color="k", lw=0.5)
            ax.set_ylim(-1.15 * float(ds.spectrum.max()), 1.15 * float(ds.spectrum.max()))
            if i == 0:
                kind = "formal Fourier transform" if float(ds.k0_dk[j]) == 0 else "OCT"
                ax.set_title(f"k0/Δk = {float(ds.k0_dk[j]):g} ({kind})")
            ax.set_ylabel("S(k_n) exp(2i k_n z0)")
    handles, labels = axes[0, 1].get_legend_handles_labels()
    star = axes[0, 0].lines[0]
    fig.legend(
        [star, *handles],
        ["scatterer position z0", *labels],
        loc="outside lower center",
        ncols=3,
        frameon=False,
    )
    fig.suptitle("One scatterer at depth z0 per row: pixel amplitudes and spectral components")
    axes[-1, 0].set_xlabel("pixel q")
    for j in range(nk):
        axes[-1, 1 + j].set_xlabel("spectral index n")
    return fig


# --- Figs. 2 and 5 ------------------------------------------------------------------------


def speckle_image(
    density: float,
    k0_dk: float,
    *,
    n_alines: int,
    n_pixels: int,
    pixel_size: float,
    seed: int,
    shape: str = "rectangular",
    fwhm_fraction: float | None = None,
    normalise: str = "density",
) -> xr.Dataset:
    """B-scan of equal-amplitude scatterers (fixed count per A-line), seeded by ``seed`` only.

    The scatterers depend on ``(seed, density, n_alines, n_pixels, pixel_size)`` and not on
    ``k0_dk``, so a sweep over ``k0_dk`` images the same scatterers (the paper's Fig. 5). Scenes
    of different densities are nested: A-line ``i`` always draws from the stream
    ``line_generator(seed, i)``, so a lower density's scatterers are the first ones of a higher
    density's.

    Parameters
    ----------
    density : float
        Scatterers per pixel ``N_sc/N`` (> 0 when ``normalise != "none"``).
    k0_dk : float
        ``k0/delta_k`` (>= 0).
    n_alines : int
        Number of A-lines (>= 1).
    n_pixels, pixel_size, shape, fwhm_fraction
        Source, see :func:`source_spectrum`.
    seed : int
        Root seed (>= 0).
    normalise : {"none", "density", "expected"}
        Passed to :func:`speckle.bscan` (``"density"``: divide by ``sqrt(density)``).

    Returns
    -------
    xarray.Dataset
        The :func:`speckle.bscan` dataset (dims ``depth, x``).
    """
    source = {"n_pixels": n_pixels, "pixel_size": pixel_size, "k0_dk": k0_dk, "shape": shape}
    source["fwhm_fraction"] = fwhm_fraction
    return random_bscan(source, density, n_alines=n_alines, seed=seed, normalise=normalise)[0]


def _image_sweep(
    grid: Mapping[str, Sequence[float]], image: Mapping, dask: Mapping | None, progress: bool
) -> xr.Dataset:
    """:func:`speckle_image` over ``grid`` with :func:`speckle.sweep.sweep`; ``image`` fixed."""
    # unknown or missing keywords fail here, naming the argument, before any work
    inspect.signature(speckle_image).bind(**dict.fromkeys(grid, 0.0), **image)
    out = sweep(speckle_image, grid, fixed=image, progress=progress, **dask_options(dask or {}))
    (name,) = grid
    out[name].attrs.update(attrs(name))
    out.attrs.update({k: v for k, v in image.items() if v is not None})
    out.attrs.update(provenance_attrs(seed=image["seed"]))
    return out


def density_sweep(
    densities: Sequence[float],
    *,
    dask: Mapping | None = None,
    progress: bool = False,
    **image: object,
) -> xr.Dataset:
    """B-scans for several densities (the paper's Fig. 2), stacked along a ``density`` dim.

    Parameters
    ----------
    densities : sequence of float
        Scatterers per pixel ``N_sc/N``, one B-scan each.
    dask : mapping, optional
        The pipeline's ``dask`` config (``scheduler``, ``address``, ``n_workers``) for
        :func:`speckle.sweep.sweep`; default: local threads.
    progress : bool
        Report the sweep's progress (see :func:`speckle.sweep.sweep`).
    **image
        The other keyword arguments of :func:`speckle_image` (``k0_dk``, ``n_alines``,
        ``n_pixels``, ``pixel_size``, ``seed``, ...), the same for every density.
    """
    return _image_sweep({"density": list(densities)}, image, dask, progress)


def k0_sweep(
    k0_dk: Sequence[float],
    *,
    bins: int = 50,
    dask: Mapping | None = None,
    progress: bool = False,
    **image: object,
) -> xr.Dataset:
    """Same scatterers imaged for several ``k0/delta_k`` (the paper's Fig. 5), with statistics.

    Parameters
    ----------
    k0_dk : sequence of float
        Values of ``k0/delta_k``, one B-scan each.
    bins : int
        Number of amplitude-histogram bins (>= 1).
    dask, progress
        As in :func:`density_sweep`.
    **image
        The other keyword arguments of :func:`speckle_image` (``density``, ``n_alines``, ...).

    Returns
    -------
    xarray.Dataset
        The B-scans stacked along ``k0_dk`` plus, per ``k0_dk``, the amplitude histogram of all
        pixels (``amplitude_density``, dims ``k0_dk, bin``; ``statistics.histogram``
        with common bins from 0 to the largest amplitude) and the maximum-likelihood Rayleigh
        fit (:func:`speckle.analysis.statistics.fit_rayleigh`): ``rayleigh_sigma`` and its
        goodness-of-fit variables ``rayleigh_ks_statistic``, ``rayleigh_chi2``, ... (dim
        ``k0_dk``).
    """
    nb = check_int(bins, "bins", low=1)
    out = _image_sweep({"k0_dk": list(k0_dk)}, image, dask, progress)
    amp = out.amplitude
    value_range = (0.0, float(amp.max()))
    hists, fits = [], []
    for r in out.k0_dk.values:
        values = amp.sel(k0_dk=r)
        hists.append(histogram(values, nb, range=value_range))
        fits.append(fit_rayleigh(values))
    out["amplitude_density"] = xr.concat(hists, dim=out.k0_dk)
    fit = xr.concat(fits, dim=out.k0_dk)
    return out.assign({f"rayleigh_{name}": var for name, var in fit.data_vars.items()})


def fragment(ds: xr.Dataset, frag: Mapping[str, int]) -> xr.Dataset:
    """The ``size`` x ``size`` pixel fragment of a B-scan starting at pixel ``depth``, ``x``.

    ``frag`` holds integer pixel indices ``depth`` and ``x`` (top-left corner) and ``size``
    (the retired key ``aline`` is read as ``x``, warning); a fragment that does not fit in the
    image raises ``ValueError``.
    """
    frag = canonical_keys(frag, "fragment")
    size = check_int(frag["size"], "fragment.size", low=1)
    d0 = check_int(frag["depth"], "fragment.depth", low=0, high=ds.sizes["depth"] - size)
    a0 = check_int(frag["x"], "fragment.x", low=0, high=ds.sizes["x"] - size)
    return ds.isel(depth=slice(d0, d0 + size), x=slice(a0, a0 + size))


def _amplitude_label(ds: xr.Dataset) -> str:
    norm = ds.attrs.get("normalise", "density")
    return "|A| / sqrt(N_sc/N)" if norm == "density" else f"|A| ({norm})"


def _fragment_panels(axes, ds: xr.Dataset, dim: str, frag: Mapping[str, int], label: str):
    """The fragment of each ``dim`` value on one grey scale, axes in µm (physical aspect)."""
    part = fragment(ds, frag).amplitude
    vmax = float(part.max())
    im = None
    for ax, value in zip(axes, ds[dim].values, strict=True):
        img = part.sel({dim: value}).transpose("depth", "x")
        im = physical_image(
            ax, img.values, img.depth.values, img.x.values, cmap="gray", vmin=0, vmax=vmax
        )
        ax.xaxis.set_major_locator(MaxNLocator(3))
        ax.set_title(f"{label} = {value:g}")
    return im


def plot_density_fragments(ds: xr.Dataset, frag: Mapping[str, int]) -> Figure:
    """Fig. 2: the same-size amplitude fragment for each density, one grey scale for all,
    axes in µm."""
    n = ds.sizes["density"]
    fig, axes = new_figure(1, n, width=2.0 * n + 1.0, height=2.6)
    im = _fragment_panels(axes[0], ds, "density", frag, "N_sc/N")
    colorbar(fig, im, axes[0].tolist(), _amplitude_label(ds), shrink=0.8)
    return fig


def plot_k0_fragments(ds: xr.Dataset, frag: Mapping[str, int]) -> Figure:
    """Fig. 5: fragments for each ``k0/delta_k`` (top) and their amplitude histograms (bottom).

    Each histogram shows the Rayleigh pdf of its own fit and, dashed, the fit of the first
    ``k0/delta_k`` to show that both textures share one Rayleigh distribution.
    """
    n = ds.sizes["k0_dk"]
    fig, axes = new_figure(2, n, width=2.6 * n + 0.6, height=5.0)
    im = _fragment_panels(axes[0], ds, "k0_dk", frag, "k0/Δk")
    colorbar(fig, im, axes[0].tolist(), _amplitude_label(ds), shrink=0.8)
    hist = ds.amplitude_density
    x = hist.bin.values
    width = float(np.diff(x).mean()) if x.size > 1 else 1.0
    sigma0 = float(ds.rayleigh_sigma.isel(k0_dk=0))
    xs = np.linspace(0, x.max() + width / 2, 200)
    for ax, value in zip(axes[1], ds.k0_dk.values, strict=True):
        sig = float(ds.rayleigh_sigma.sel(k0_dk=value))
        ax.bar(
            x,
            hist.sel(k0_dk=value).values,
            width=width,
            color="0.75",
            edgecolor="0.4",
            linewidth=0.3,
        )
        ax.plot(xs, rayleigh_pdf(xs, sig), "k-", lw=1.2, label="Rayleigh fit to this histogram")
        ax.plot(
            xs,
            rayleigh_pdf(xs, sigma0),
            "r--",
            lw=0.8,
            label=f"Rayleigh fit at k0/Δk = {float(ds.k0_dk[0]):g}",
        )
        ax.set_xlabel(f"pixel amplitude {_amplitude_label(ds)}")
        ax.set_ylabel("probability density")
        npx = ds.sizes["depth"] * ds.sizes["x"]
        ax.set_title(f"k0/Δk = {value:g}: {npx} pixels, fit σ = {sig:.3g}")
    fig.legend(
        *axes[1, 0].get_legend_handles_labels(), loc="outside lower center", ncols=2, frameon=False
    )
    return fig
