"""Labelled arrays in, a numpy body, labelled arrays out: one decorator (as MetPy's
``preprocess_and_wrap``) instead of an ``isinstance(..., xr.DataArray)`` branch per function.

The decorated function's body sees plain numpy arrays for the arguments named in ``arrays``;
its result takes the labels (dims, coordinates, attributes) of the argument named in
``wrap_like`` when that argument was a ``DataArray``, renamed and labelled from
:mod:`speckle.conventions`. Checks stay in the body, done once, on the numpy values.
"""

from __future__ import annotations

import functools
import inspect
from collections.abc import Callable, Mapping, Sequence

import numpy as np
import xarray as xr

from .conventions import attrs

__all__ = ["preprocess_and_wrap"]


def preprocess_and_wrap(
    *,
    arrays: Sequence[str] = (),
    wrap_like: str | None = None,
    name: str | None = None,
    quantity: str | None = None,
    long_name: str | None = None,
    attrs_from: Mapping[str, str] | None = None,
) -> Callable[[Callable], Callable]:
    """Decorator: ``DataArray`` arguments to numpy, the result labelled like one of them.

    Parameters
    ----------
    arrays : sequence of str
        Arguments whose ``DataArray`` values the body receives as numpy arrays (``.values``);
        any other value passes unchanged.
    wrap_like : str, optional
        The argument whose labels the result takes. When it was a ``DataArray`` the result is
        ``argument.copy(data=result)``, renamed ``name`` and given the attributes
        ``conventions.attrs(quantity, long_name)``; otherwise a 0-d result is returned as a
        float and any other as the body returned it. None: the result as the body returned it.
    name, quantity, long_name : str, optional
        The labelled result's name, quantity (a key of ``conventions.QUANTITIES``) and long
        name.
    attrs_from : mapping, optional
        Attribute -> argument: the labelled result also records these arguments' values (e.g.
        ``{"filter": "name"}``).

    Returns
    -------
    callable
        The decorator.

    Examples
    --------
    >>> import numpy as np, xarray as xr
    >>> @preprocess_and_wrap(arrays=["x"], wrap_like="x", name="twice", quantity="length",
    ...                      long_name="twice x")
    ... def twice(x):
    ...     return 2 * np.asarray(x)
    >>> twice(1.5)
    3.0
    >>> out = twice(xr.DataArray([1.0, 2.0], dims="depth"))
    >>> out.name, out.attrs["units"], out.values.tolist()
    ('twice', 'um', [2.0, 4.0])
    """

    def decorator(func: Callable) -> Callable:
        signature = inspect.signature(func)
        named = [*arrays, *([wrap_like] if wrap_like else []), *(attrs_from or {}).values()]
        missing = [a for a in named if a not in signature.parameters]
        if missing:
            raise TypeError(f"{func.__name__} has no arguments {missing}")

        @functools.wraps(func)
        def wrapper(*args, **kwargs):
            bound = signature.bind(*args, **kwargs)
            bound.apply_defaults()
            template = bound.arguments.get(wrap_like) if wrap_like else None
            for arg in arrays:
                if isinstance(bound.arguments.get(arg), xr.DataArray):
                    bound.arguments[arg] = bound.arguments[arg].values
            out = func(*bound.args, **bound.kwargs)
            if wrap_like is None:
                return out
            if isinstance(template, xr.DataArray):
                result = template.copy(data=out)
                if name is not None:
                    result = result.rename(name)
                if quantity is not None:
                    result = result.assign_attrs(attrs(quantity, long_name))
                if attrs_from:
                    result = result.assign_attrs(
                        {k: bound.arguments[arg] for k, arg in attrs_from.items()}
                    )
                return result
            return float(out) if np.ndim(out) == 0 else out

        return wrapper

    return decorator
