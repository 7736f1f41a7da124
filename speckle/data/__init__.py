"""Data shipped with the package: the measured OCT sample (MIT-licensed, see its README).

:func:`sample_path` is the one accessor for the shipped files; the pipeline's default config
names the same files relative to the repository root (``speckle/data/oct_mit_sample/...``).
"""

from __future__ import annotations

from importlib import resources
from pathlib import Path

__all__ = ["SAMPLES", "SAMPLE_PITCH", "SAMPLE_PIXEL_SIZE", "sample_path"]

#: Short name -> file of the measured sample (two 512 x 512 uint8 crops, (depth, aline)).
SAMPLES = {
    "pdms": "pdms_thick_rel_001_crop.npy",
    "thumb": "thumb_relaxed_276_crop.npy",
}
#: Axial pixel of the device in µm (optical path per pixel, from the source repository).
SAMPLE_PIXEL_SIZE = 5.75
#: Lateral A-line pitch in µm, per sample: *assumed* in the source repository's notebook (the
#: B-scan spans the 4 mm suction aperture), not recorded by the device.
SAMPLE_PITCH = {"pdms": 4000.0 / 2540, "thumb": 4000.0 / 1272}


def sample_path(name: str = "pdms") -> Path:
    """Path of a shipped measured B-scan.

    Parameters
    ----------
    name : {"pdms", "thumb"}
        ``"pdms"``: PDMS phantom (homogeneous speckle below the surface at row ~62);
        ``"thumb"``: a thumb (layered tissue).

    Returns
    -------
    pathlib.Path
        The ``.npy`` file inside the installed package.

    Raises
    ------
    ValueError
        If ``name`` is not one of :data:`SAMPLES`.
    """
    if name not in SAMPLES:
        raise ValueError(f"name must be one of {sorted(SAMPLES)}, got {name!r}")
    return Path(str(resources.files(__name__).joinpath("oct_mit_sample", SAMPLES[name])))
