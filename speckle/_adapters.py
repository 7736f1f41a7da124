"""The config adapter's core: a ``source`` section -> the model's keyword arguments.

Plain dictionaries in, keyword arguments out, nothing imported from the model: it sits below
every layer so that ``analysis`` (the realism study) and ``figures`` (every figure built from
config, through :mod:`speckle.figures._config`) share one adapter.
"""

from __future__ import annotations

from collections.abc import Mapping

from ._validate import check_int, check_real

__all__ = ["scene_kwargs", "spectrum_kwargs"]


def _grid(source: Mapping) -> tuple[int, float]:
    """``(N, H = N * pixel_size)`` of a source section, checked."""
    missing = [k for k in ("n_pixels", "pixel_size") if source.get(k) is None]
    if missing:
        raise ValueError(f"the source section needs {missing} (it has {sorted(source)})")
    n = check_int(source["n_pixels"], "n_pixels", low=2)
    return n, n * check_real(source["pixel_size"], "pixel_size", low=0, low_inclusive=False)


def spectrum_kwargs(source: Mapping, **override: object) -> dict:
    """Keyword arguments of :func:`speckle.spectrum` from a ``source`` config section.

    The one adapter from the pipeline's source parameters to the model's: every spectrum a
    figure builds from config goes through it.

    Parameters
    ----------
    source : mapping
        The section in model form (:func:`resolve_source`): ``n_pixels`` (>= 2),
        ``pixel_size`` (µm, > 0), ``k0_dk``, optional ``shape`` (``"rectangular"`` by default,
        ``"gaussian"`` or ``"array"``), ``fwhm_fraction`` (used by ``"gaussian"`` only) and
        ``weights`` (used by ``"array"`` only). Other keys are ignored.
    **override
        Values replacing the section's, e.g. the ``k0_dk`` of a sweep point or a figure's own
        ``n_pixels``.

    Returns
    -------
    dict
        ``n_pixels``, ``depth_range`` (``H = n_pixels * pixel_size``, µm), ``k0_dk``, ``shape``
        and,
        for a Gaussian, ``fwhm_fraction`` (a fraction of ``delta_k``) or, for an array,
        ``weights``.

    Raises
    ------
    ValueError
        If ``n_pixels``, ``pixel_size`` or ``k0_dk`` is missing, ``n_pixels < 2`` or
        ``pixel_size <= 0``; :func:`speckle.spectrum` checks the rest.
    """
    s = {**source, **override}
    n, h = _grid(s)
    if s.get("k0_dk") is None:
        raise ValueError(f"the source section needs 'k0_dk' (it has {sorted(s)})")
    shape = s.get("shape") or "rectangular"
    out = {"n_pixels": n, "depth_range": h, "k0_dk": s["k0_dk"], "shape": shape}
    if shape == "gaussian":
        out["fwhm_fraction"] = s.get("fwhm_fraction")
    elif shape == "array":
        out["weights"] = s.get("weights")
    return out


def scene_kwargs(source: Mapping, **override: object) -> dict:
    """Keyword arguments ``n_pixels`` and ``depth_range`` (``H``, µm) of the scene builders
    (:func:`speckle.random_scatterers`, :func:`speckle.deformable_scene`) from a ``source``
    section, so that a scene and the spectrum of :func:`spectrum_kwargs` share one grid.

    Raises
    ------
    ValueError
        As :func:`spectrum_kwargs`, for ``n_pixels`` and ``pixel_size``.
    """
    n, h = _grid({**source, **override})
    return {"n_pixels": n, "depth_range": h}
