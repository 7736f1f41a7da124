"""The fitted twin of a scanner: simulate it, compare it, predict its strain limits."""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass, field

import numpy as np
import xarray as xr
from scipy import optimize, stats

from ..._validate import check_choice, check_int, check_real
from ...analysis import autocorrelation as ac
from ...analysis.phase import DEFAULT_MAX_BIAS
from ...analysis.strain import STRAIN_METHODS, estimate_strain
from ...conventions import attrs, coord
from ...imaging.beam import beam_scan
from ...system.noise import add_complex_noise
from ..failure import method_options, strain_scores
from ._estimates import _jackknife
from ._inputs import _as_image, _column_groups, _data, _display, _log_data, _region
from ._theory import _acf, _weights

__all__ = ["SystemFit"]


@dataclass
class SystemFit:
    """The fitted twin of a scanner (:func:`fit_system`).

    Attributes
    ----------
    parameters : xarray.Dataset
        One variable per fitted quantity and its standard error ``<name>_se`` (units in attrs);
        attributes: ``spectrum_shape``, ``focused``, ``kind``, ``k0``, ``k0_dk`` and the fit
        settings.

    Examples
    --------
    >>> import speckle
    >>> from speckle.data import SAMPLE_PITCH, SAMPLE_PIXEL_SIZE, sample_path
    >>> image = speckle.load_image(
    ...     sample_path("pdms"),
    ...     kind="log",
    ...     pixel_size=SAMPLE_PIXEL_SIZE,
    ...     pitch=SAMPLE_PITCH["pdms"],
    ...     dims=("depth", "x"),
    ... )
    >>> fit = speckle.fit_system(image, region={"depth": [95, 135]}, noise_rows=[5, 40])
    >>> "waist" in fit.parameters and "waist_se" in fit.parameters
    True
    """

    parameters: xr.Dataset
    template: xr.DataArray = field(repr=False)
    settings: dict = field(repr=False)

    # -- the twin --------------------------------------------------------------------------
    def _value(self, name: str) -> float:
        return float(self.parameters[name])

    def _model(self, shape: tuple[int, int]) -> dict:
        p = self.parameters
        nz, nx = shape
        n = max(int(self.settings["n_pixels"]), nz + nz % 2)
        dz = float(p.attrs["depth_step_medium"])
        h = n * dz
        spec = _weights(p.attrs["spectrum_shape"], self._value("spectrum_width"), n)
        k0 = float(p.attrs["k0_dk"]) * n * np.pi / h
        rho = self._value("density")
        if not np.isfinite(rho) or rho > self.settings["max_density"]:
            rho = float(
                min(max(self._value("density_lower_bound"), 4.0), self.settings["max_density"])
            )
        pitch = float(p.attrs["pitch"])
        beam = {
            "lines": np.arange(nx) * pitch,
            "waist": self._value("waist"),
            "n_pixels": n,
            "depth_range": h,
            "k0": k0,
            "spectrum": spec,
            "method": "nufft",
            "tol": 1e-6,
        }
        if bool(p.attrs["focused"]):
            beam["focus"] = float(np.clip(self._value("focus_depth"), 0.0, h * (1 - 1e-9)))
            beam["rayleigh_range"] = self._value("rayleigh_range")
        return {"n": n, "h": h, "k0": k0, "rho": rho, "pitch": pitch, "beam": beam, "dz": dz}

    def _scatterers(self, m: dict, nx: int, seed: int, depth_range: float) -> dict[str, np.ndarray]:
        w0 = m["beam"]["waist"]
        x0, x1 = -4.5 * w0, (nx - 1) * m["pitch"] + 4.5 * w0
        count = round(m["rho"] * (depth_range / m["dz"]) * (x1 - x0) / m["pitch"])
        rng = np.random.default_rng(np.random.SeedSequence([seed, 20]))
        return {"z": rng.uniform(0.0, depth_range, count), "x": rng.uniform(x0, x1, count)}

    def _field(self, m: dict, sc: dict, strain: float = 0.0) -> np.ndarray:
        """Noise-free complex field (depth, x) of the scatterers, compressed by ``strain``."""
        z = sc["z"] * (1 - strain)
        amp = np.exp(-self._value("attenuation") * z) * (z < m["h"])
        a = beam_scan(z, sc["x"], amp.astype(complex), **m["beam"]).T
        return a

    def simulate(self, shape: tuple[int, int] | None = None, seed: int = 0) -> xr.DataArray:
        """A twin image of the fitted system: same kind, dims and coordinates as the region.

        Parameters
        ----------
        shape : (int, int), optional
            ``(depth, x)`` pixels; default the fitted region's shape (then its coordinates).
        seed : int
            Non-negative seed of the scene and the noise.
        """
        sd = check_int(seed, "seed", low=0)
        t = self.template
        shp = t.shape if shape is None else tuple(check_int(v, "shape", low=2) for v in shape)
        if len(shp) != 2:
            raise ValueError(f"shape must be (depth, x) pixels, got {shape!r}")
        m = self._model(shp)
        a = self._field(m, self._scatterers(m, shp[1], sd, m["h"]))[: shp[0]]
        snr = self._value("snr_db")
        if np.isfinite(snr):
            a = add_complex_noise(a, snr, seed=sd + 1)
        kind = self.parameters.attrs["kind"]
        values = self._render(a, kind)
        if shape is None or tuple(shape) == t.shape:
            coords = {k: t.coords[k] for k in ("depth", "x")}
        else:
            coords = {
                "depth": (
                    "depth",
                    t.depth.values[0]
                    + np.arange(shp[0]) * float(self.parameters.attrs["pixel_size"]),
                    t.depth.attrs,
                ),
                "x": ("x", t.x.values[0] + np.arange(shp[1]) * m["pitch"], t.x.attrs),
            }
        return xr.DataArray(
            values,
            dims=("depth", "x"),
            coords=coords,
            name="twin",
            attrs={
                **{
                    k: v
                    for k, v in t.attrs.items()
                    if k
                    in (
                        "kind",
                        "pixel_size",
                        "pitch",
                        "clip_low",
                        "clip_high",
                        "long_name",
                        "units",
                    )
                },
                "source": "speckle twin (SystemFit.simulate)",
                "seed": sd,
            },
        )

    def _render(self, a: np.ndarray, kind: str) -> np.ndarray:
        if kind == "complex":
            return a * np.sqrt(self.settings["mean_intensity"] / np.mean(np.abs(a) ** 2))
        inten = np.abs(a) ** 2
        inten = inten / inten.mean()
        inten = inten + self._value("twin_floor")
        if kind == "log":
            d = self._value("twin_gain") * np.log(inten) + self._value("twin_offset")
            hi = self.template.attrs.get("clip_high")
            if hi is not None:
                d = np.clip(np.round(d), self.template.attrs["clip_low"], hi)
            return d
        inten = inten * self.settings["mean_intensity"] / inten.mean()
        return np.sqrt(inten) if kind == "amplitude" else inten

    def _fit_detection(self, region: xr.DataArray) -> None:
        """The floor (and log mapping) that give a floorless twin the image's log moments.

        The floor of :func:`~speckle.analysis.measured.fit_floor` assumes fully developed
        speckle; a sparse scene raises the skewness of the log data too. Here a floorless
        noisy twin image ``I0`` (seed 0, the region's shape) is taken as it is, and ``b`` solves
        ``skewness(ln(I0/<I0> + b)) = skewness`` of the image (``b = 0`` if the twin is already
        less skewed); its SE follows from the image's skewness SE. For log data ``g`` and ``c``
        then match the standard deviation and mean of ``D``.
        """
        p = self.parameters
        shape = self.template.shape
        m = self._model(shape)
        a = self._field(m, self._scatterers(m, shape[1], 0, m["h"]))[: shape[0]]
        if np.isfinite(self._value("snr_db")):
            a = add_complex_noise(a, self._value("snr_db"), seed=1)
        i0 = np.abs(a).ravel() ** 2
        i0 = i0 / i0.mean()
        target, target_se = self._value("skewness"), self._value("skewness_se")

        def gap(b):
            return float(stats.skew(np.log(i0 + b))) - target

        if gap(0.0) >= 0 or gap(5.0) < 0:
            b, b_se = 0.0, 0.0
        else:
            b = float(optimize.brentq(gap, 0.0, 5.0, xtol=1e-7))
            h = max(1e-4, 0.05 * b)
            slope = (gap(b + h) - gap(max(b - h, 0.0))) / (b + h - max(b - h, 0.0))
            b_se = target_se / abs(slope) if slope != 0 else np.inf
        ln = np.log(i0 + b)
        if p.attrs["kind"] == "log":
            d = region.values.ravel()
            g = float(d.std() / ln.std())
            c = float(d.mean() - g * ln.mean())
        else:
            g, c = 1.0, 0.0
        p["twin_floor"] = (
            (),
            b,
            attrs("dimensionless", "intensity floor / mean speckle intensity, twin-matched"),
        )
        p["twin_floor_se"] = (
            (),
            float(b_se),
            attrs("dimensionless", "standard error of twin_floor"),
        )
        p["twin_gain"] = ((), g, attrs("dimensionless", "g of the twin's log mapping"))
        p["twin_offset"] = ((), c, attrs("dimensionless", "c of the twin's log mapping"))

    # -- comparison ------------------------------------------------------------------------
    def compare(self, image: xr.DataArray, *, seed: int = 0) -> xr.Dataset:
        """Measured statistics against the twin's (same region, estimator and blocks).

        Returns
        -------
        xarray.Dataset
            Dim ``source`` = ``("measured", "twin")``: ``autocorrelation`` (``source, axis,
            lag``), ``skewness``, ``excess_kurtosis`` (of the log data), ``contrast_excess``
            and ``mean_log_profile`` (``source, row``), each with ``*_se``; ``z_score`` (the
            largest ``|measured - twin| / combined SE`` per statistic); histograms of the
            standardised log data; ``measured_image`` and ``twin_image`` (the region).
        """
        region = _region(_as_image(image), self.settings["region"])
        twin = self.simulate(seed=seed)
        stats_ = [self._statistics(x) for x in (region, twin)]
        if "frame" in region.dims:  # statistics pooled over frames; panels of the first
            region = region.isel(frame=0)
        ds = xr.concat(stats_, dim="source").assign_coords(source=["measured", "twin"])
        for k in ("autocorrelation", "skewness", "excess_kurtosis", "contrast_excess"):
            diff = abs(ds[k].sel(source="measured") - ds[k].sel(source="twin"))
            comb = np.hypot(ds[f"{k}_se"].sel(source="measured"), ds[f"{k}_se"].sel(source="twin"))
            z = diff / comb
            if k == "autocorrelation":
                z = z.sel(lag=slice(1, None))
            ds[f"z_{k}"] = (
                (),
                float(z.max()),
                attrs("dimensionless", f"largest |measured - twin| / combined SE, {k}"),
            )
        edges = np.linspace(-5, 3, 41)
        for name, x in (("measured", region), ("twin", twin)):
            lg = _log_data(x)
            zs = (lg - lg.mean()) / lg.std()
            ds[f"{name}_log_histogram"] = (
                ("bin",),
                np.histogram(zs, edges, density=True)[0],
                attrs("dimensionless", f"probability density of the standardised {name} log data"),
            )
            ds[f"{name}_image"] = (
                ("depth", "x"),
                _display(x),
                {
                    "long_name": f"{name} region, dB re mean"
                    if x.attrs["kind"] != "log"
                    else f"{name} region (log data)"
                },
            )
        ds = ds.assign_coords(
            bin=coord(
                "dimensionless",
                0.5 * (edges[1:] + edges[:-1]),
                "standardised log intensity",
                dims="bin",
            ),
            depth=region.depth,
            x=region.x,
        )
        ds.attrs.update(kind=self.parameters.attrs["kind"], seed=int(seed))
        return ds

    def _statistics(self, image: xr.DataArray) -> xr.Dataset:
        s = self.settings
        data = _data(image, None, s["refractive_index"])
        nx, nf = image.sizes["x"], image.sizes.get("frame", 1)
        blocks = np.array_split(np.arange(nx), s["n_blocks"])

        def one(cols):
            inten, _, g, _ = data.pieces(cols)
            i_all = np.hstack(inten)
            lg = (
                np.hstack([data.signal[:, c] for c in cols])
                if data.kind == "log"
                else np.log(i_all)
            )
            return {
                "depth": _acf(inten, s["max_lag"], "depth"),
                "lateral": _acf(inten, s["max_lag"], "lateral"),
                "skewness": float(stats.skew(lg.ravel())),
                "excess_kurtosis": float(stats.kurtosis(lg.ravel())),
                "contrast_excess": float(i_all.var() / i_all.mean() ** 2 - 1),
                "profile": lg.mean(axis=1) / g,
            }

        whole = one(_column_groups(nx, nf, [np.arange(nx)]))
        se = _jackknife(
            [one(_column_groups(nx, nf, blocks[:i] + blocks[i + 1 :])) for i in range(len(blocks))],
            list(whole),
        )
        lag = np.arange(s["max_lag"] + 1)
        acf = np.stack([whole["depth"], whole["lateral"]])
        acf_se = np.stack([se["depth"], se["lateral"]])
        return xr.Dataset(
            {
                "autocorrelation": (
                    ("axis", "lag"),
                    acf,
                    attrs("correlation", "intensity autocorrelation"),
                ),
                "autocorrelation_se": (
                    ("axis", "lag"),
                    acf_se,
                    attrs("correlation", "standard error of the autocorrelation"),
                ),
                **{
                    k: ((), whole[k], attrs("dimensionless", k.replace("_", " ")))
                    for k in ("skewness", "excess_kurtosis", "contrast_excess")
                },
                **{
                    f"{k}_se": (
                        (),
                        float(se[k]),
                        attrs("dimensionless", f"standard error of {k}"),
                    )
                    for k in ("skewness", "excess_kurtosis", "contrast_excess")
                },
                "mean_log_profile": (
                    ("row",),
                    whole["profile"] - whole["profile"].mean(),
                    attrs("dimensionless", "mean ln intensity per row, minus its mean"),
                ),
                "mean_log_profile_se": (
                    ("row",),
                    se["profile"],
                    attrs("dimensionless", "standard error of mean_log_profile"),
                ),
            },
            coords={
                "axis": ["depth", "lateral"],
                "lag": coord("lag", lag, "lag (pixels or lines)"),
                "row": np.arange(image.sizes["depth"]),
            },
        )

    # -- strain limits ---------------------------------------------------------------------
    def failure_maps(
        self,
        strains: Sequence[float] = (1e-4, 1e-3, 3e-3, 1e-2, 3e-2),
        methods: Sequence[str] = ("vector", "wls", "tracking", "correlation"),
        *,
        shape: tuple[int, int] = (128, 32),
        window: tuple[int, int] | None = None,
        seed: int = 0,
    ) -> xr.Dataset:
        """Each strain estimator's errors on twin image pairs under uniform compression.

        Parameters
        ----------
        strains : sequence of float
            Interframe strains (compression > 0), each in (-0.5, 0.5).
        methods : sequence of str
            Estimators of :func:`speckle.estimate_strain` (``"vector_unaligned"`` etc. as in
            the elastography config: ``_aligned``/``_unaligned`` set ``align``).
        shape : (int, int)
            Twin image ``(depth, x)`` pixels.
        window : (int, int), optional
            Estimator window (depth, x) in pixels; default each method's own.
        seed : int
            Scene seed; frame noise uses ``seed + 1``, ``seed + 2``.

        Returns
        -------
        xarray.Dataset
            ``median_error``, ``rms_error``, ``answered`` (fraction of pixels with an answer)
            over ``(strain, method)``; the twin's parameters in the attributes.
        """
        s_values = [check_real(s, "strains", low=-0.5, high=0.5) for s in strains]
        if not s_values:
            raise ValueError("strains must hold at least one strain")
        labels = [str(m) for m in methods]
        for lab in labels:
            check_choice(method_options(lab)[0], "methods", STRAIN_METHODS)
        shp = tuple(check_int(v, "shape", low=8) for v in shape)
        m = self._model(shp)
        smax = max(abs(v) for v in s_values)
        depth = m["h"] / (1 - smax)
        sc = self._scatterers(m, shp[1], check_int(seed, "seed", low=0), depth)
        snr = self._value("snr_db")
        ref = self._field(m, sc)[: shp[0]]
        if np.isfinite(snr):
            a1 = add_complex_noise(ref, snr, seed=seed + 1)
        else:
            a1 = ref
        # the phase methods' lag from the fitted spectrum (speckle.analysis.phase.choose_lag's
        # rule on the theory, |gamma(L)|^2 < DEFAULT_MAX_BIAS), not from one noisy image
        gamma2 = ac.axial_correlation_theory(np.arange(shp[0]), m["beam"]["spectrum"])
        below = np.flatnonzero(gamma2[1:] < DEFAULT_MAX_BIAS)
        lag = int(below[0] + 1) if below.size else shp[0] // 4
        res = np.empty((len(s_values), len(labels), 3))
        for i, s in enumerate(s_values):
            dfm = self._field(m, sc, s)[: shp[0]]
            a2 = add_complex_noise(dfm, snr, seed=seed + 2) if np.isfinite(snr) else dfm
            for j, lab in enumerate(labels):
                method, opts = method_options(lab)
                if method in ("vector", "wls"):
                    opts = {"lag": lag, **opts}
                est = estimate_strain(
                    a1, a2, k0=m["k0"], pixel_size=m["dz"], method=method, window=window, **opts
                )
                res[i, j] = strain_scores(est, abs(s) if method == "correlation" else s)
        coords = {
            "strain": (
                "strain",
                np.asarray(s_values),
                attrs("strain"),
            ),
            "method": labels,
        }
        return xr.Dataset(
            {
                "median_error": (
                    ("strain", "method"),
                    res[..., 0],
                    attrs("strain", "median error"),
                ),
                "rms_error": (("strain", "method"), res[..., 1], attrs("strain", "rms error")),
                "answered": (
                    ("strain", "method"),
                    res[..., 2],
                    attrs("dimensionless", "fraction of pixels answered"),
                ),
            },
            coords=coords,
            attrs={
                "lag": lag,
                "shape": list(shp),
                "seed": int(seed),
                "k0": m["k0"],
                "pixel_size": m["dz"],
                "density": m["rho"],
                "window": "method default" if window is None else list(window),
            },
        )
