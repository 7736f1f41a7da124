"""Old names that moved keep working for one release, with a ``FutureWarning`` (as xrft does).

A module whose names moved keeps only a shim: ``__getattr__ = moved(__name__, new_module,
names)``. Each old name resolves to the new module's object on use and warns, naming the new
spelling; ``tests/test_layout.py`` lists the shim modules (``SHIMS``), the only modules allowed
to import against the flow. A module that keeps code of its own and lost some names to a later
layer passes the new module's name instead: it is imported only when an old name is used.

A module PATH that was retired (kind ``module`` of :data:`speckle.conventions.RETIRED`: the
module went private or into a private folder) keeps a file at the old path whose only line is
``__getattr__, __dir__, __all__ = retired_module(__name__, new_module)``: importing it warns
once, naming the new import, and its names are the new module's. Where the old module shared
its name with a public function of its package (``speckle.system.rolloff``), the package keeps
the function: see :func:`retired_module`.
"""

from __future__ import annotations

import functools
import importlib
import inspect
import sys
import types
import warnings
from collections.abc import Callable, Iterable, Mapping

__all__ = ["keyword_only", "moved", "renamed_parameters", "retired_module", "retired_names"]


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


def retired_names(package: str, getattr_: Callable[[str], object]) -> Callable[[str], object]:
    """A package ``__getattr__``: retired public names resolve to their new ones, warning.

    The retired names are those of :data:`speckle.conventions.RETIRED` of kind ``function``
    or ``constant`` whose new name the package exports (its ``__all__``); a retired module
    path of the package (kind ``module``, e.g. ``speckle.imaging.nufft``) is its shim module,
    imported (and warning once) on first use, and wins over a retired function of the same
    name (``speckle.scene.layers`` stays the module). Any other name goes to ``getattr_`` (the
    package's lazy ``__getattr__``). The old names are not in ``__all__``.

    Parameters
    ----------
    package : str
        The package's ``__name__``.
    getattr_ : callable
        The package's own ``__getattr__``.

    Returns
    -------
    callable
        The package's ``__getattr__``.

    Examples
    --------
    >>> import warnings, speckle
    >>> with warnings.catch_warnings(record=True) as seen:
    ...     warnings.simplefilter("always")
    ...     table = speckle.METHODS
    >>> table is speckle.ASCAN_METHODS, str(seen[0].message).split(";")[0]
    (True, 'speckle.METHODS is now speckle.ASCAN_METHODS')
    """

    def __getattr__(name: str) -> object:
        from .conventions import RETIRED  # here: ``import speckle`` imports no xarray

        module = sys.modules[package]
        public = getattr(module, "__all__", ())
        if name not in public and RETIRED.get(f"{package}.{name}", ("", ""))[1] == "module":
            return importlib.import_module(f"{package}.{name}")  # the shim warns
        new, kind = RETIRED.get(name, (None, None))
        if kind in ("function", "constant") and new in public:
            warnings.warn(
                f"{package}.{name} is now {package}.{new}; the old name will be removed in the "
                "next release",
                FutureWarning,
                stacklevel=2,
            )
            return getattr_(new)
        return getattr_(name)

    return __getattr__


class _KeepsPublicNames(types.ModuleType):
    """A package whose public names stay theirs when a same-named retired module is imported.

    The import system binds a submodule on its package (``setattr(package, child, module)``)
    after running it; for the shim at ``speckle/system/rolloff.py`` that would replace the
    public function ``speckle.system.rolloff`` by the shim. The names in
    ``__retired_shadowed__`` are not rebound to their own submodule (``lazy_loader`` guards a
    function named after its module the same way). Installed by :func:`retired_module` only
    when such a shim is imported: ``import speckle`` swaps no class.
    """

    def __setattr__(self, name: str, value: object) -> None:
        if name in self.__dict__.get("__retired_shadowed__", ()) and value is sys.modules.get(
            f"{self.__name__}.{name}"
        ):
            return  # the import system binding the retired module: the public name stays
        super().__setattr__(name, value)


def retired_module(
    old: str, new: str, *, use: str | None = None
) -> tuple[Callable[[str], object], Callable[[], list[str]], list[str]]:
    """``(__getattr__, __dir__, __all__)`` of a module kept at a retired path; warns once.

    Called from the shim's module body, so it runs once, when the old path is first
    imported: one ``FutureWarning`` names the new import, then the old path gives the new
    module's ``__all__`` names without further warnings (``from speckle.system.rolloff import
    rolloff_curve`` keeps working). If the old module's name is a public name of its package
    (the function ``speckle.system.rolloff``), that name stays the function: the package does
    not let the import system rebind it to this module (:class:`_KeepsPublicNames`), whatever
    the order of imports. ``import speckle.system.rolloff as m`` then gives the function, as
    in the release before, when the module was public: import its names with ``from``.

    Parameters
    ----------
    old : str
        The retired path (the shim's ``__name__``); a key of kind ``module`` of
        :data:`speckle.conventions.RETIRED`.
    new : str
        The module that holds the code now (private).
    use : str, optional
        What to use instead, for the warning; default ``from <package> import <names>``, the
        new module's names that its package exports.

    Returns
    -------
    tuple
        The shim's ``__getattr__``, ``__dir__`` and ``__all__`` (the new module's).

    Examples
    --------
    >>> import sys, warnings
    >>> sys.modules.pop("speckle.system.rolloff", None) and None
    >>> with warnings.catch_warnings(record=True) as seen:
    ...     warnings.simplefilter("always")
    ...     from speckle.system.rolloff import rolloff
    >>> import speckle
    >>> rolloff is speckle.system.rolloff, str(seen[0].message).split("use ")[1].split(";")[0]
    (True, 'from speckle.system import rolloff')
    """
    module = importlib.import_module(new)
    package, _, child = old.rpartition(".")
    parent = sys.modules[package]
    public = getattr(parent, "__all__", ())
    if use is None:
        names = [n for n in module.__all__ if n in public]
        use = f"from {package} import {', '.join(names)}"
    # the warning points at the line that asked for the old path: the first frame outside the
    # shim, the import machinery and this module (``speckle.imaging.nufft`` as an attribute
    # comes through ``retired_names`` and ``importlib.import_module``)
    frame = sys._getframe(1)
    while frame.f_back is not None and (
        frame.f_globals.get("__name__") == old
        or "importlib" in frame.f_code.co_filename
        or frame.f_code.co_filename == __file__
    ):
        frame = frame.f_back
    warnings.warn_explicit(
        f"the module {old} is retired (now the private {new}): use {use}; the old path will "
        "be removed in the next release",
        FutureWarning,
        frame.f_code.co_filename,
        frame.f_lineno,
        module=frame.f_globals.get("__name__", "<string>"),
        registry=frame.f_globals.setdefault("__warningregistry__", {}),
    )
    if child in public:
        if type(parent) is types.ModuleType:
            parent.__class__ = _KeepsPublicNames
        shadowed = parent.__dict__.get("__retired_shadowed__", frozenset())
        parent.__dict__["__retired_shadowed__"] = shadowed | {child}
    names = list(module.__all__)

    def __getattr__(name: str) -> object:
        if name in names:
            return getattr(module, name)
        retired = module.__dict__.get("__getattr__")  # the new module's own retired names
        if retired is not None and not name.startswith("__"):
            try:
                return retired(name)  # they warn on their own
            except AttributeError:
                pass
        raise AttributeError(f"module {old!r} has no attribute {name!r}")

    def __dir__() -> list[str]:
        return sorted(names)

    return __getattr__, __dir__, names


def renamed_parameters(renames: Mapping[str, str]) -> Callable[[Callable], Callable]:
    """Decorator: retired keyword arguments (old -> new) still work for a release, warning.

    Parameters
    ----------
    renames : mapping of str to str
        Old keyword -> new parameter name (which the decorated function must have).

    Returns
    -------
    callable
        The decorator: a call with an old keyword warns (``FutureWarning`` naming the new one)
        and passes the value under the new name; giving both is a ``TypeError``.

    Examples
    --------
    >>> import warnings
    >>> @renamed_parameters({"window": "apodization"})
    ... def f(n, *, apodization="none"):
    ...     return apodization
    >>> with warnings.catch_warnings(record=True) as seen:
    ...     warnings.simplefilter("always")
    ...     value = f(4, window="hann")
    >>> value, str(seen[0].message).split(";")[0]
    ('hann', "f: parameter 'window' is now 'apodization'")
    """
    table = dict(renames)

    def decorator(func: Callable) -> Callable:
        params = inspect.signature(func).parameters
        wrong = [f"{o}->{n}" for o, n in table.items() if n not in params or o in params]
        if wrong:
            raise TypeError(f"{func.__name__}: renames {wrong} do not match its parameters")

        @functools.wraps(func)
        def wrapper(*args, **kwargs):
            for old, new in table.items():
                if old not in kwargs:
                    continue
                if new in kwargs:
                    raise TypeError(
                        f"{func.__name__} got both {old!r} (retired) and {new!r}: give {new!r}"
                    )
                warnings.warn(
                    f"{func.__name__}: parameter {old!r} is now {new!r}; the old name will be "
                    "removed in the next release",
                    FutureWarning,
                    stacklevel=2,
                )
                kwargs[new] = kwargs.pop(old)
            return func(*args, **kwargs)

        return wrapper

    return decorator


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
