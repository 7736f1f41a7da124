"""Old names that moved keep working for one release, with a ``FutureWarning`` (as xrft does).

A module whose names moved keeps only a shim: ``__getattr__ = moved(__name__, new_module,
names)``. Each old name resolves to the new module's object on use and warns, naming the new
spelling; ``tests/test_layout.py`` lists the shim modules (``SHIMS``), the only modules allowed
to import against the flow. A module that keeps code of its own and lost some names to a later
layer passes the new module's name instead: it is imported only when an old name is used.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import types
import warnings
from collections.abc import Callable, Iterable, Mapping

__all__ = ["keyword_only", "moved"]


def moved(
    old: str,
    new: types.ModuleType | str,
    names: Iterable[str] | None = None,
    renamed: Mapping[str, str] | None = None,
) -> Callable[[str], object]:
    """A module ``__getattr__`` resolving the moved ``names`` of ``old`` in ``new``, warning.

    Parameters
    ----------
    old : str
        The old module's ``__name__``.
    new : module or str
        The module the names now live in, or its name: imported when an old name is first
        used (for a name that moved to a later layer, which the old module may not import).
    names : iterable of str, optional
        Names kept under the same spelling; default the new module's ``__all__`` (read when
        an attribute of the old module is first asked for).
    renamed : mapping, optional
        Old name -> new name, for names that were renamed while moving.

    Returns
    -------
    callable
        The ``__getattr__`` of the old module: ``FutureWarning`` naming ``new.<name>``, then
        the object; ``AttributeError`` for any other name.

    Examples
    --------
    >>> import math, warnings
    >>> getattr_ = moved("old.place", math, ["pi"])
    >>> with warnings.catch_warnings(record=True) as seen:
    ...     warnings.simplefilter("always")
    ...     value = getattr_("pi")
    >>> value == math.pi, str(seen[0].message)
    (True, 'old.place.pi moved to math.pi; the old name will be removed in the next release')
    """

    listed = None if names is None else {**{n: n for n in names}, **dict(renamed or {})}

    def __getattr__(name: str) -> object:
        if (listed is not None and name not in listed) or name.startswith("__"):
            raise AttributeError(f"module {old!r} has no attribute {name!r}")  # nothing imported
        module = importlib.import_module(new) if isinstance(new, str) else new
        table = listed or {**{n: n for n in module.__all__}, **dict(renamed or {})}
        if name not in table:
            raise AttributeError(f"module {old!r} has no attribute {name!r}")
        target = f"{module.__name__}.{table[name]}"
        warnings.warn(
            f"{old}.{name} moved to {target}; the old name will be removed in the next release",
            FutureWarning,
            stacklevel=2,
        )
        return getattr(module, table[name])

    return __getattr__


def keyword_only(*names: str) -> Callable[[Callable], Callable]:
    """Decorator: options ``names`` became keyword-only; positional use warns for a release.

    The decorated function declares ``names`` after ``*``; a call that still passes them by
    position (in the old order, ``names``) gets a ``FutureWarning`` naming the keywords, then
    runs as if they were passed by keyword. ``inspect.signature`` shows the new signature.

    Parameters
    ----------
    *names : str
        The options, in their old positional order.

    Returns
    -------
    callable
        The decorator.

    Examples
    --------
    >>> import warnings
    >>> @keyword_only("scale")
    ... def area(width, height, *, scale=1.0):
    ...     return width * height * scale
    >>> area(2.0, 3.0, scale=2.0)
    12.0
    >>> with warnings.catch_warnings(record=True) as seen:
    ...     warnings.simplefilter("always")
    ...     value = area(2.0, 3.0, 2.0)
    >>> value, str(seen[0].message)
    (12.0, 'area(): pass scale= by keyword; positional use will be an error in the next release')
    """

    def decorate(func: Callable) -> Callable:
        params = inspect.signature(func).parameters.values()
        n_positional = sum(p.kind in (p.POSITIONAL_ONLY, p.POSITIONAL_OR_KEYWORD) for p in params)
        keyword = {p.name for p in params if p.kind is p.KEYWORD_ONLY}
        if not set(names) <= keyword:
            raise TypeError(f"{func.__qualname__}: {sorted(set(names) - keyword)} not keyword-only")

        @functools.wraps(func)
        def wrapper(*args, **kwargs):
            if len(args) > n_positional:
                extra = args[n_positional:]
                if len(extra) > len(names):
                    raise TypeError(
                        f"{func.__qualname__}() takes at most {n_positional + len(names)} "
                        f"positional arguments ({len(args)} given)"
                    )
                given = dict(zip(names, extra, strict=False))
                twice = sorted(given.keys() & kwargs.keys())
                if twice:
                    raise TypeError(f"{func.__qualname__}() got multiple values for {twice}")
                warnings.warn(
                    f"{func.__qualname__}(): pass {', '.join(f'{n}=' for n in given)} by "
                    "keyword; positional use will be an error in the next release",
                    FutureWarning,
                    stacklevel=2,
                )
                args, kwargs = args[:n_positional], {**kwargs, **given}
            return func(*args, **kwargs)

        return wrapper

    return decorate
