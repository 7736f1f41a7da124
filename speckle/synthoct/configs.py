"""Named scanner configurations of the SynthOCT challenge and of the group's 2025 phantoms.

``"challenge"`` is the INI that the challenge's baseline writes (``Part1_Generator.py`` of
``SynthOCTChallenge/SynthOCT_Baseline``): 256 pixels of 6 µm, λ = 1.3 µm, 512 A-lines over
3072 µm, one B-scan, beam radius 10 µm, 300,000 scatterers (:class:`ScannerConfig`'s
defaults). ``"2025"`` is the configuration of the group's 2025 digital phantoms (Nikoshin et
al., SASHIMI 2025, as the :class:`ScannerConfig` docstring records it): 601 pixels of 2.2 µm,
975 A-lines over 3000 µm, beam radius 6 µm, 255,000 scatterers; the wavelength (not stated
there) is taken as the challenge's 1.3 µm, one B-scan at ``y = 0``. ``"reduced"`` is the
challenge's scanner on a quarter of its box (128 pixels of 6 µm, 128 lines over 768 µm,
37,500 scatterers: the same density), the size of the closed loop's tests.
"""

from __future__ import annotations

import dataclasses

from .files import ScannerConfig

__all__ = ["SYNTHOCT_CONFIGS", "synthoct_config"]

#: Named configurations: name -> the fields that differ from :class:`ScannerConfig`'s defaults.
SYNTHOCT_CONFIGS: dict[str, dict[str, object]] = {
    "challenge": {},
    "reduced": {"n_pixels": 128, "n_lines": 128, "x_max": 768.0, "n_scatterers": 37_500},
    "2025": {
        "n_pixels": 601,
        "pixel_size": 2.2,
        "n_lines": 975,
        "x_max": 3000.0,
        "beam_radius": 6.0,
        "n_scatterers": 255_000,
    },
}


def synthoct_config(name: str, **changes: object) -> ScannerConfig:
    """The scanner configuration of the challenge or of the 2025 digital phantoms.

    Parameters
    ----------
    name : {"challenge", "2025", "reduced"}
        ``"challenge"``: the baseline's INI (256 pixels of 6 µm, 512 lines over 3072 µm,
        radius 10 µm, 300,000 scatterers); ``"2025"``: 601 pixels of 2.2 µm, 975 lines over
        3000 µm, radius 6 µm, 255,000 scatterers; ``"reduced"``: the challenge's scanner on
        128 x 128 pixels (module docstring).
    **changes
        Fields of :class:`ScannerConfig` to replace (e.g. ``n_scatterers``; checked as the
        class checks them).

    Returns
    -------
    ScannerConfig
        The named configuration with ``changes`` applied (lengths in µm).

    Raises
    ------
    ValueError
        An unknown name; TypeError/ValueError of :class:`ScannerConfig` for a bad change.

    Examples
    --------
    >>> cfg = synthoct_config("2025")
    >>> cfg.n_pixels, cfg.pixel_size, cfg.beam_radius, round(cfg.depth_range, 1)
    (601, 2.2, 6.0, 1322.2)
    """
    if not isinstance(name, str) or name not in SYNTHOCT_CONFIGS:
        raise ValueError(f"name must be one of {sorted(SYNTHOCT_CONFIGS)}, got {name!r}")
    fields = {f.name for f in dataclasses.fields(ScannerConfig)}
    unknown = sorted(set(changes) - fields)
    if unknown:
        raise TypeError(f"unknown ScannerConfig fields {unknown}; known: {sorted(fields)}")
    return ScannerConfig(**{**SYNTHOCT_CONFIGS[name], **changes})
