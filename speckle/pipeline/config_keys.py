"""Retired config keys read under their new names when the workflow loads (issue 32).

The Snakefile calls :func:`rename_retired_keys` before the schema validates the config, so a
config written before a key was renamed keeps working for a release, with a ``FutureWarning``
naming the new key; a config that gives both the old and the new key is refused.
"""

from __future__ import annotations

import os
import warnings
from collections.abc import Mapping, MutableMapping, Sequence
from pathlib import Path

import yaml

__all__ = ["rename_retired_keys"]

#: Config keys renamed (issue 32: the lateral pixel index is ``x``, as the image's dim): old
#: key path -> new key. An old key is read for one release, with a ``FutureWarning``.
RETIRED_KEYS = {
    "fig2.fragment.aline": "x",
    "fig5.fragment.aline": "x",
}


def _section(config: object, path: Sequence[str]) -> object:
    """The mapping at key ``path`` of ``config`` (None when absent)."""
    for key in path:
        if not isinstance(config, Mapping):
            return None
        config = config.get(key)
    return config if isinstance(config, Mapping) else None


def rename_retired_keys(
    config: MutableMapping, given: Sequence[Mapping | str | os.PathLike] | None = None
) -> MutableMapping:
    """Read the retired keys of a pipeline config (:data:`RETIRED_KEYS`) under their new names.

    Run when the workflow loads, before the schema validates ``config``: an old config (e.g.
    ``fig2.fragment.aline``) keeps working for a release with a ``FutureWarning`` naming the
    new key (``fig2.fragment.x``); a config that gives both is refused.

    Parameters
    ----------
    config : mutable mapping
        The merged config (Snakemake's ``config``), changed in place: each old key's value
        moves to the new key (replacing the default's value).
    given : sequence of mapping or path, optional
        What the user wrote, in the order Snakemake layers it: the config files passed with
        ``--configfile`` (paths, read as YAML). One of them giving both keys is refused;
        across them the last one naming either key wins, as in Snakemake's merge (an old key
        found in ``config`` but in none of them, e.g. from ``--config``, wins too). Default:
        ``[config]`` (a config given as a whole).

    Returns
    -------
    mutable mapping
        ``config`` itself.

    Raises
    ------
    ValueError
        Naming the key path, when one config gives both the old and the new key.

    Warns
    -----
    FutureWarning
        Naming the new key path, for each old key given.

    Examples
    --------
    >>> import warnings
    >>> config = {"fig2": {"fragment": {"depth": 100, "aline": 0, "size": 10}}}
    >>> with warnings.catch_warnings(record=True) as seen:
    ...     warnings.simplefilter("always")
    ...     fragment = rename_retired_keys(config)["fig2"]["fragment"]
    >>> fragment, str(seen[0].message).split(":")[0]
    ({'depth': 100, 'size': 10, 'x': 0}, 'config key fig2.fragment.aline is now fig2.fragment.x')
    """
    sources = [config] if given is None else list(given)
    for i, src in enumerate(sources):
        if isinstance(src, str | os.PathLike):
            sources[i] = yaml.safe_load(Path(src).read_text()) or {}
    for old_path, new in RETIRED_KEYS.items():
        *parent, old = old_path.split(".")
        where = ".".join(parent)
        last = None  # the key the last source giving either names: it wins, as in a merge
        for found in (_section(src, parent) for src in sources):
            if found is not None and old in found and new in found:
                raise ValueError(
                    f"config key {where} has both {old!r} (retired) and {new!r}: give only "
                    f"{where}.{new}"
                )
            if found is not None and (old in found or new in found):
                last = old if old in found else new
        section = _section(config, parent)
        if section is None or old not in section:
            continue
        warnings.warn(
            f"config key {old_path} is now {where}.{new}: rename it in your config file; the "
            "old key will be refused in the next release",
            FutureWarning,
            stacklevel=1,  # (named after this module: Snakemake drops a Snakefile's warnings)
        )
        value = section.pop(old)
        if last != new:
            section[new] = value
    return config
