"""Labelled arrays in, a numpy body, labelled arrays out: one decorator (as MetPy's
``preprocess_and_wrap``) instead of an ``isinstance(..., xr.DataArray)`` branch per function.

The decorated function's body sees plain numpy arrays for the arguments named in ``arrays``
(and in ``checks``); its result takes the labels (dims, coordinates, attributes) of the argument
named in ``wrap_like`` when that argument was a ``DataArray``, renamed and labelled from
:mod:`speckle.conventions`.

Array checks are declared once per argument (:class:`ArraySpec`: real or complex, finite,
non-empty, dims or ndim, minimum shape, same shape and coordinates as another argument) and
run here, once, before the body: the body checks only its scalars. A frame stack (an extra
leading dim named in ``stack``, e.g. ``frame`` or ``time``) is validated as a whole and passed
to the body as one array; :func:`map_frames` maps the body's numpy core over its frames
(in a loop, or lazily one Dask task per frame) without calling the public function again.
Grid parameters (``pixel_size``, ``pitch``, ``k0``, ...) named in ``from_grid`` are read from
the labelled argument's coordinates and attributes (:func:`speckle.conventions.grid`); a value
given as well must agree with them.
"""

from __future__ import annotations

import dataclasses
import functools
import inspect
import numbers
from collections.abc import Callable, Mapping, Sequence

import numpy as np
import xarray as xr

from .conventions import attrs, canonical_dims, grid

__all__ = ["ArraySpec", "Out", "check_same_grid", "map_frames", "preprocess_and_wrap"]

#: Leading dims whose indices a refusal names (``frames [2] hold NaN``).
FRAME_DIMS = ("frame", "time")

#: Relative difference above which a given grid value disagrees with the coordinates.
GRID_RTOL = 1e-9


@dataclasses.dataclass(frozen=True)
class ArraySpec:
    """What one array argument must be (checked by :func:`preprocess_and_wrap`, once).

    Attributes
    ----------
    kind : {"number", "real", "complex"}
        Allowed values: any number, real only (complex refused) or complex only (real refused).
    finite : bool
        NaN or inf refused (the count is named).
    nonempty : bool
        An empty array refused.
    dims : tuple of str, optional
        Required dims of a ``DataArray`` (transposed into this order, after any ``stack`` dim);
        a numpy array must have ``len(dims)`` axes (``+ 1`` with a stack) in this order.
    ndim : int or tuple of int, optional
        Allowed numbers of axes (when ``dims`` is not given).
    min_shape : tuple of int, optional
        Smallest size of each of the last axes (e.g. ``(2, 1)``: two depth pixels).
    same_as : str, optional
        Another checked argument this one must match: same shape, both labelled or both plain,
        same coordinates (refused, never aligned).
    labelled : bool
        A ``DataArray`` or ``Dataset`` is required (numpy refused).
    optional : bool
        ``None`` passes unchecked.
    lazy : bool
        A Dask-backed ``DataArray`` reaches the body as its Dask array (``.data``), not loaded.
    keep_labels : bool
        The body receives the checked ``DataArray`` itself (transposed to ``dims``), for
        results that are not on its grid (e.g. a Dataset built from its coordinates).
    variable : str, optional
        A ``Dataset`` argument stands for this variable (e.g. a B-scan's ``field``), its
        attributes merged with the Dataset's; a Dataset without it is refused.
    extra_dims : bool
        ``dims`` are required, any other dims allowed (kept in place, not transposed).
    """

    kind: str = "number"
    finite: bool = True
    nonempty: bool = True
    dims: tuple[str, ...] | None = None
    ndim: int | tuple[int, ...] | None = None
    min_shape: tuple[int, ...] | None = None
    same_as: str | None = None
    labelled: bool = False
    optional: bool = False
    lazy: bool = False
    keep_labels: bool = False
    variable: str | None = None
    extra_dims: bool = False

    def __post_init__(self):
        if self.kind not in ("number", "real", "complex"):
            raise ValueError(f"kind must be 'number', 'real' or 'complex', got {self.kind!r}")


@dataclasses.dataclass
class Out:
    """A body's result to label like ``wrap_like``: values, name, attrs and extra coordinates.

    With a plain (numpy) ``wrap_like`` argument the caller gets ``values``; with a
    ``DataArray`` a ``DataArray`` on its dims and coordinates, named ``name``, with exactly
    ``attrs`` and the coordinates ``coords`` (name -> ``(values, attrs)`` on the same dims).
    """

    values: object
    name: str | None = None
    attrs: Mapping[str, object] = dataclasses.field(default_factory=dict)
    coords: Mapping[str, tuple[object, Mapping[str, object]]] = dataclasses.field(
        default_factory=dict
    )


def _is_dask(data: object) -> bool:
    return hasattr(data, "dask") and hasattr(data, "map_blocks") and hasattr(data, "rechunk")


def check_same_grid(x: xr.DataArray, y: xr.DataArray, names: tuple[str, str]) -> None:
    """``ValueError`` unless every dim ``x`` and ``y`` share has the same size and coordinates.

    Nothing is aligned, padded or cut: the message names both arguments and the first
    difference.
    """
    a_name, b_name = names
    for d in [d for d in x.dims if d in y.dims]:
        if x.sizes[d] != y.sizes[d]:
            raise ValueError(
                f"{a_name} and {b_name} differ along {d!r}: {x.sizes[d]} vs {y.sizes[d]} "
                f"values; put both on the same grid or select the same region of both "
                f"(e.g. .isel({d}=slice(...)) on each)"
            )
        if d in x.coords and d in y.coords:
            a, b = np.asarray(x[d].values), np.asarray(y[d].values)
            if not np.array_equal(a, b):
                i = int(np.flatnonzero(a != b)[0])
                raise ValueError(
                    f"{a_name} and {b_name} have different {d!r} coordinates (first difference "
                    f"at index {i}: {a[i]!r} vs {b[i]!r}); put both on the same grid or select "
                    "the same region of both"
                )


def _finite_sum(data) -> bool:
    """True when the sum of ``data`` is finite: then every value is (one pass, no mask); a
    NaN, an inf or an overflow makes it non-finite and the values are counted."""
    total = data.sum()  # (no errstate: it costs half the sum of a 256 x 64 image)
    if hasattr(total, "compute"):
        total = total.compute()
    return bool(np.isfinite(total))


def _values(name: str, value: object, spec: ArraySpec, stack: Sequence[str]):
    """(checked values, the labelled template or None, stacked?) of one argument."""
    template = None
    if isinstance(value, xr.Dataset):
        if spec.variable is None:
            raise TypeError(f"{name} must be an array or DataArray, got a Dataset")
        if spec.variable not in value.data_vars:
            raise TypeError(
                f"{name} must hold a variable {spec.variable!r} (a Dataset such as a B-scan "
                f"from speckle.bscan), got variables {list(value.data_vars)}"
            )
        var = value[spec.variable]  # attrs merged on a copy: the caller's object is unchanged
        value = var.assign_attrs({**value.attrs, **var.attrs})
    if isinstance(value, xr.DataArray):
        value = canonical_dims(value, name)  # (depth, aline) -> (depth, x), warning (issue 32)
        if spec.dims is not None and spec.extra_dims:
            missing = [d for d in spec.dims if d not in value.dims]
            if missing:
                raise ValueError(
                    f"{name} must have dims {spec.dims} (and any others), got {value.dims}"
                )
        elif spec.dims is not None:
            extra = [d for d in value.dims if d not in spec.dims]
            missing = [d for d in spec.dims if d not in value.dims]
            stacked = [d for d in extra if d in stack]
            if missing or len(extra) > len(stacked) or len(stacked) > 1:
                allowed = f"{spec.dims}" + (f" (plus one of {tuple(stack)} first)" if stack else "")
                raise ValueError(f"{name} must have dims {allowed}, got {value.dims}")
            value = value.transpose(*stacked, *spec.dims)
        template = value
        data = value.data if spec.lazy and _is_dask(value.data) else value.values
    elif spec.labelled:
        what = "DataArray or Dataset" if spec.variable else "DataArray"
        raise TypeError(
            f"{name} must be a labelled xarray {what} (coordinates give its grid), got "
            f"{type(value).__name__}"
        )
    elif isinstance(value, np.ndarray) or (spec.lazy and _is_dask(value)):
        data = value
    elif isinstance(value, (numbers.Number, list, tuple, np.generic)) and not isinstance(
        value, bool
    ):
        data = np.asarray(value)
    else:
        raise TypeError(f"{name} must be a numeric array, got {type(value).__name__}")
    kind = data.dtype.kind  # (dtype.kind: a fraction of np.issubdtype's cost per call)
    if kind not in "iufc":
        raise TypeError(f"{name} must hold numbers, got dtype {data.dtype}")
    if spec.kind == "complex" and kind != "c":
        raise TypeError(
            f"{name} must be complex (the phase carries the signal), got dtype {data.dtype}"
        )
    if spec.kind == "real" and kind == "c":
        raise TypeError(f"{name} must be real, got complex dtype {data.dtype}")
    n_core = len(spec.dims) if spec.dims is not None and not spec.extra_dims else None
    # a stack is a named leading dim: only a DataArray has one
    labelled_stack = template is not None and stack and n_core is not None
    allowed = (n_core, n_core + 1) if labelled_stack else (n_core,)
    if spec.ndim is not None:
        allowed = (spec.ndim,) if isinstance(spec.ndim, int) else tuple(spec.ndim)
    if allowed != (None,) and data.ndim not in allowed:
        what = f"{' or '.join(map(str, allowed))}-D"
        if spec.dims is not None:
            what = f"{n_core}-D {spec.dims}"
        raise ValueError(
            f"{name} must be {what}"
            + (f" (a DataArray: or a stack along {tuple(stack)})" if stack else "")
            + f", got shape {data.shape}"
        )
    stacked = n_core is not None and data.ndim == n_core + 1
    if spec.nonempty and data.size == 0:
        raise ValueError(f"{name} must not be empty, got shape {data.shape}")
    if spec.min_shape is not None:
        core = data.shape[data.ndim - len(spec.min_shape) :]
        if any(s < m for s, m in zip(core, spec.min_shape, strict=True)):
            least = tuple(spec.min_shape)
            if spec.dims is not None and len(spec.dims) == len(least):
                least = (
                    "("
                    + ", ".join(f"{d} >= {m}" for d, m in zip(spec.dims, least, strict=True))
                    + ")"
                )
            raise ValueError(f"{name} must be at least {least} pixels, got shape {data.shape}")
    if stacked and data.shape[0] < 1:
        raise ValueError(f"{name} has an empty {tuple(stack)} stack")
    if spec.finite and kind in "fc" and not _finite_sum(data):
        finite = np.isfinite(data)
        n_bad = finite.size - finite.sum()
        if hasattr(n_bad, "compute"):
            n_bad = n_bad.compute()
        if n_bad:
            where = ""
            if stacked or (spec.dims is not None and spec.dims[0] in (*stack, *FRAME_DIMS)):
                bad = np.flatnonzero(~np.asarray(finite.all(axis=tuple(range(1, data.ndim)))))
                where = f" in frames {bad[:10].tolist()}{' ...' if bad.size > 10 else ''}"
            raise ValueError(
                f"{name} holds {int(n_bad)} NaN or infinite {'pixels' if spec.dims else 'values'} "
                f"of {finite.size}{where}; "
                "crop, drop or fill them first"
            )
    return data, template, stacked


def _same(name: str, other: str, a, b, stack: Sequence[str] = ()) -> None:
    """Refuse ``a`` (argument ``name``) unless it matches ``b`` (argument ``other``)."""
    (da, ta, sa), (db, tb, sb) = a, b
    if (ta is None) != (tb is None):
        raise TypeError(f"{other} and {name} must both be numpy arrays or both DataArrays")
    if sa != sb:
        which = other if sa is False else name
        dim = "/".join(stack) or "frame"
        first = stack[0] if stack else "frame"
        raise ValueError(
            f"only {which} has a {dim!r} dim: give both the same leading {dim} dim (pairs "
            f"{other}[i], {name}[i]) or select one of it (.isel({first}=i))"
        )
    if da.shape != db.shape:
        raise ValueError(
            f"{other} and {name} differ in shape: {db.shape} vs {da.shape}; they must have the "
            "same shape (nothing is aligned or cut)"
        )
    if ta is not None and not isinstance(ta, xr.Dataset):
        check_same_grid(tb, ta, (other, name))


def _fill_grid(bound, from_grid: Mapping[str, str], func_name: str) -> None:
    """Grid parameters from the labelled argument; a given value must agree."""
    grids = {}  # one grid read per labelled argument
    for param, source in from_grid.items():
        given = bound.arguments.get(param)
        src = bound.arguments.get(source)
        if src is None:
            continue  # an optional source not given: the body decides what it needs
        if not isinstance(src, (xr.DataArray, xr.Dataset)):
            if given is None:
                raise ValueError(
                    f"{func_name} needs {param}: give {param}= or {source} as a labelled "
                    f"DataArray whose coordinates and attributes give it"
                )
            continue
        if source not in grids:
            grids[source] = grid(src, what=source)
        found = getattr(grids[source], param)
        if found is None:
            if given is None:
                try:
                    grid(src, need=(param,), what=source)  # raises, naming what is missing
                except ValueError as err:
                    raise ValueError(
                        f"{func_name} needs {param}: give {param}= ({source} does not carry "
                        f"it, e.g. a measured image: {err})"
                    ) from None
            continue
        if given is not None and not isinstance(given, bool):
            try:
                value = float(given)
            except (TypeError, ValueError):
                continue  # the body refuses it, naming the parameter
            if not np.isclose(value, found, rtol=GRID_RTOL, atol=0):
                where = "coordinates" if param in ("pixel_size", "pitch") else "attributes"
                raise ValueError(
                    f"{param}={given!r} disagrees with {source}'s {where} ({found!r}); "
                    f"drop {param}= (it is read from them) or relabel {source}"
                )
        bound.arguments[param] = found


def _label(out: object, template: xr.DataArray | None) -> object:
    if isinstance(out, tuple):
        return tuple(_label(o, template) for o in out)
    if not isinstance(out, Out):
        return out
    if template is None:
        return out.values
    result = xr.DataArray(
        out.values, dims=template.dims, coords=template.coords, name=out.name, attrs=out.attrs
    )
    if out.coords:
        result = result.assign_coords(
            {k: (template.dims, v, dict(a)) for k, (v, a) in out.coords.items()}
        )
    return result


def map_frames(core: Callable, *arrays: object, ndim: int, n_out: int = 1) -> list:
    """``core`` (numpy in, ``n_out`` arrays of the input's shape out) over a frame stack.

    ``arrays`` of ``ndim`` axes are passed through (``core(*arrays)``); with one more leading
    axis, ``core`` runs per frame: in a loop for numpy, one Dask task per frame for Dask
    arrays (lazy; chunks rechunked to whole frames). Returns the list of ``n_out`` results,
    stacked along the leading axis.
    """
    first = arrays[0]
    if first.ndim == ndim:
        out = core(*arrays)
        return list(out) if n_out > 1 else [out]
    if any(_is_dask(a) for a in arrays):
        if not all(_is_dask(a) for a in arrays):
            raise TypeError(
                "the frame stacks must all be Dask-backed or all in memory (use "
                ".chunk({'frame': 1}) on each)"
            )
        whole = {0: 1, **{i: -1 for i in range(1, first.ndim)}}
        arrays = [a.rechunk(whole) for a in arrays]

        def block(*frames):
            return np.stack([np.asarray(o) for o in _as_list(core(*(f[0] for f in frames)))])[None]

        both = arrays[0].map_blocks(
            block,
            *arrays[1:],
            dtype=float,
            new_axis=1,
            chunks=((1,) * first.shape[0], (n_out,), *((s,) for s in first.shape[1:])),
        )
        return [both[:, i] for i in range(n_out)]
    rows = [_as_list(core(*(a[i] for a in arrays))) for i in range(first.shape[0])]
    return [np.stack([r[i] for r in rows]) for i in range(n_out)]


def _as_list(out: object) -> list:
    return list(out) if isinstance(out, (tuple, list)) else [out]


def preprocess_and_wrap(
    *,
    arrays: Sequence[str] = (),
    checks: Mapping[str, ArraySpec] | None = None,
    stack: Sequence[str] = (),
    from_grid: Mapping[str, str] | None = None,
    wrap_like: str | None = None,
    name: str | None = None,
    quantity: str | None = None,
    long_name: str | None = None,
    attrs_from: Mapping[str, str] | None = None,
) -> Callable[[Callable], Callable]:
    """Decorator: ``DataArray`` arguments checked and turned to numpy, the result labelled.

    Parameters
    ----------
    arrays : sequence of str
        Arguments whose ``DataArray`` values the body receives as numpy arrays (``.values``);
        any other value passes unchanged (no checks).
    checks : mapping of str to ArraySpec, optional
        Arguments checked once, before the body, against their :class:`ArraySpec` (each
        refusal a ``TypeError`` or ``ValueError`` naming the argument and what is allowed);
        the body receives their numpy (or Dask, ``lazy``) values, transposed to ``dims``.
    stack : sequence of str
        Dims that may lead an argument with ``dims`` as a frame stack (e.g. ``("frame",)``);
        checked as a whole, passed as one array (see :func:`map_frames`).
    from_grid : mapping of str to str, optional
        Parameter -> argument: the parameter (a field of :func:`speckle.conventions.grid`,
        e.g. ``pixel_size``) is read from that argument when labelled; a value also given must
        agree (relative 1e-9), and one is required when the argument is plain numpy.
    wrap_like : str, optional
        The argument whose labels the result takes. When it was a ``DataArray``, a result of
        type :class:`Out` (or a tuple of them) becomes a ``DataArray`` on its dims and
        coordinates; any other array result is ``argument.copy(data=result)``, renamed
        ``name`` and given the attributes ``conventions.attrs(quantity, long_name)``.
        Otherwise a 0-d result is returned as a float, an :class:`Out` as its values, and
        anything else as the body returned it. None: the result as the body returned it.
    name, quantity, long_name : str, optional
        The labelled result's name, quantity (a key of ``conventions.QUANTITIES``) and long
        name.
    attrs_from : mapping, optional
        Attribute -> argument: the labelled result also records these arguments' values (e.g.
        ``{"filter": "name"}``).

    Returns
    -------
    callable
        The decorator; the decorated function has ``__wrapped__`` (the body) and
        ``__speckle_checks__`` (its checks).

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
    >>> @preprocess_and_wrap(checks={"a": ArraySpec(kind="real", ndim=1)})
    ... def total(a):
    ...     return float(a.sum())
    >>> total([1.0, np.nan])
    Traceback (most recent call last):
    ...
    ValueError: a holds 1 NaN or infinite values of 2; crop, drop or fill them first
    """
    checks = dict(checks or {})

    def decorator(func: Callable) -> Callable:
        signature = inspect.signature(func)
        same = [s.same_as for s in checks.values() if s.same_as]
        named = [
            *arrays,
            *checks,
            *same,
            *([wrap_like] if wrap_like else []),
            *(attrs_from or {}).values(),
            *(from_grid or {}),
            *(from_grid or {}).values(),
        ]
        missing = [a for a in named if a not in signature.parameters]
        if missing:
            raise TypeError(f"{func.__name__} has no arguments {missing}")

        @functools.wraps(func)
        def wrapper(*args, **kwargs):
            bound = signature.bind(*args, **kwargs)
            bound.apply_defaults()
            if from_grid:
                _fill_grid(bound, from_grid, func.__name__)
            template = bound.arguments.get(wrap_like) if wrap_like else None
            seen = {}
            for arg, spec in checks.items():
                value = bound.arguments.get(arg)
                if value is None and spec.optional:
                    continue
                seen[arg] = _values(arg, value, spec, stack)
                if spec.same_as is not None and spec.same_as in seen:
                    _same(arg, spec.same_as, seen[arg], seen[spec.same_as], stack)
                bound.arguments[arg] = seen[arg][
                    1 if spec.keep_labels and seen[arg][1] is not None else 0
                ]
            if wrap_like in seen:
                template = seen[wrap_like][1]
            for arg in arrays:
                if isinstance(bound.arguments.get(arg), xr.DataArray):
                    bound.arguments[arg] = bound.arguments[arg].values
            out = func(*bound.args, **bound.kwargs)
            if wrap_like is None:
                return out
            if isinstance(out, (Out, tuple)):
                return _label(out, template if isinstance(template, xr.DataArray) else None)
            if isinstance(template, xr.DataArray) and isinstance(out, np.ndarray):
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
            if isinstance(out, (xr.DataArray, xr.Dataset)):
                return out
            return float(out) if np.ndim(out) == 0 else out

        wrapper.__speckle_checks__ = checks
        return wrapper

    return decorator
