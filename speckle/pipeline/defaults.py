"""The pipeline's default config, shipped with the package (the gallery runs from an install).

``speckle/data/config.yaml`` is the repository's ``workflow/config/config.yaml`` (a link in the
repository, a copy in an installed package): :func:`default_config` reads it wherever the package
is, so that examples and notebooks need no clone of the repository.
"""

from __future__ import annotations

from importlib import resources

import yaml

__all__ = ["default_config"]


def default_config() -> dict:
    """The pipeline's default config as a new dict (the parsed ``workflow/config/config.yaml``).

    Returns
    -------
    dict
        Every section of the default config (lengths in µm, as in the file); a fresh copy on
        each call, so that callers may change it.

    Examples
    --------
    >>> from speckle.pipeline import default_config
    >>> config = default_config()
    >>> config["source"]["pixel_size"], config["seed"]
    (8.0, 20140601)
    """
    text = resources.files("speckle.data").joinpath("config.yaml").read_text(encoding="utf-8")
    return yaml.safe_load(text)
