"""Argument checks shared by every public function.

Each helper raises ``TypeError`` for the wrong kind of value and ``ValueError`` for a value out of
range, always naming the parameter and the allowed range, before any work starts.
"""

from __future__ import annotations

import numbers
import os
from collections.abc import Iterable

import numpy as np

__all__ = [
    "MAX_BYTES",
    "as_finite_array",
    "broadcast",
    "check_bool",
    "check_choice",
    "check_int",
    "check_memory",
    "check_path",
    "check_real",
    "check_size",
]

#: Largest allocation (bytes) a single call may plan; larger requests are refused up front.
MAX_BYTES = 8 * 2**30


def check_real(
    value: object,
    name: str,
    *,
    low: float | None = None,
    high: float | None = None,
    low_inclusive: bool = True,
    high_inclusive: bool = True,
) -> float:
    """Return ``value`` as a finite float after checking it lies in the given interval.

    Parameters
    ----------
    value : object
        The value to check (a Python or numpy real scalar; ``bool`` is refused).
    name : str
        Parameter name used in the error message.
    low, high : float, optional
        Interval bounds; ``None`` means unbounded on that side.
    low_inclusive, high_inclusive : bool
        Whether each bound belongs to the allowed interval.

    Raises
    ------
    TypeError
        If ``value`` is not a real number.
    ValueError
        If ``value`` is NaN, infinite or outside the interval.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Real):
        raise TypeError(f"{name} must be a real number, got {type(value).__name__} {value!r}")
    x = float(value)
    lo = "-inf" if low is None else f"{low:g}"
    hi = "inf" if high is None else f"{high:g}"
    interval = f"{'[' if low_inclusive and low is not None else '('}{lo}, {hi}"
    interval += "]" if high_inclusive and high is not None else ")"
    if not np.isfinite(x):
        raise ValueError(f"{name} must be finite and in {interval}, got {x!r}")
    too_low = low is not None and (x < low or (x == low and not low_inclusive))
    too_high = high is not None and (x > high or (x == high and not high_inclusive))
    if too_low or too_high:
        raise ValueError(f"{name} must be in {interval}, got {x!r}")
    return x


def check_int(value: object, name: str, *, low: int | None = None, high: int | None = None) -> int:
    """Return ``value`` as an ``int`` after checking ``low <= value <= high``.

    Raises
    ------
    TypeError
        If ``value`` is not an integer (floats such as ``256.0`` are refused too).
    ValueError
        If ``value`` is out of range.
    """
    if isinstance(value, bool) or not isinstance(value, numbers.Integral):
        raise TypeError(f"{name} must be an integer, got {type(value).__name__} {value!r}")
    v = int(value)
    if (low is not None and v < low) or (high is not None and v > high):
        lo = "-inf" if low is None else str(low)
        hi = "inf" if high is None else str(high)
        raise ValueError(f"{name} must be an integer in [{lo}, {hi}], got {v}")
    return v


def check_bool(value: object, name: str) -> bool:
    """Return ``value`` as a ``bool`` after checking it is one (``True``/``False``/numpy bool).

    Strings (``"False"`` is truthy), numbers (``0.5``) and arrays are refused: they would be
    silently taken as a truth value.

    Raises
    ------
    TypeError
        If ``value`` is not a boolean.
    """
    if not isinstance(value, bool | np.bool_):
        raise TypeError(f"{name} must be True or False, got {type(value).__name__} {value!r}")
    return bool(value)


def check_choice(value: object, name: str, choices: Iterable[str]) -> str:
    """Return ``value`` after checking it is one of ``choices``."""
    choices = tuple(choices)
    if not isinstance(value, str) or value not in choices:
        raise ValueError(f"{name} must be one of {', '.join(map(repr, choices))}; got {value!r}")
    return value


def as_finite_array(value: object, name: str, *, dtype=float) -> np.ndarray:
    """Convert ``value`` to an array of ``dtype`` and check every element is finite.

    Raises
    ------
    TypeError
        If ``value`` cannot be converted to ``dtype`` or holds booleans or strings (``"8.0"``,
        ``True`` are refused, as by :func:`check_real`), or complex values for a real dtype.
    ValueError
        If any element is NaN or infinite.
    """
    try:
        arr = np.asarray(value)
        if arr.dtype.kind in "bUSV" or (
            arr.dtype.kind == "O"
            and any(isinstance(v, str | bytes | bool | np.bool_) for v in arr.ravel())
        ):
            raise TypeError
        if np.iscomplexobj(arr) and not np.issubdtype(np.dtype(dtype), np.complexfloating):
            raise TypeError
        arr = arr.astype(dtype, copy=False)
    except (TypeError, ValueError):
        raise TypeError(
            f"{name} must be an array of {np.dtype(dtype).name} values, got {type(value).__name__}"
        ) from None
    # a finite sum means every element is finite (NaN and inf propagate); only a non-finite
    # sum (a bad element, or an overflow of huge finite values) needs the elementwise check
    with np.errstate(over="ignore", invalid="ignore"):
        total = np.sum(arr)
    if not np.isfinite(total) and not np.all(np.isfinite(arr)):
        bad = int(np.size(arr) - np.count_nonzero(np.isfinite(arr)))
        raise ValueError(f"{name} must be finite; it holds {bad} NaN or infinite value(s)")
    return arr


def broadcast(**arrays: np.ndarray) -> list[np.ndarray]:
    """``np.broadcast_arrays`` of the named arrays, refusing mismatched shapes by name.

    Raises
    ------
    ValueError
        Naming every array and its shape when they do not broadcast together.
    """
    try:
        return list(np.broadcast_arrays(*arrays.values()))
    except ValueError:
        shapes = ", ".join(f"{k} {np.shape(v)}" for k, v in arrays.items())
        raise ValueError(
            f"{', '.join(arrays)} must have broadcastable shapes; got {shapes}"
        ) from None


def check_memory(nbytes: float, name: str, what: str, limit: float | None = None) -> None:
    """Refuse a request whose planned allocation ``nbytes`` exceeds ``limit`` (default
    :data:`MAX_BYTES`), naming the parameter that sets it and the estimate, before any work.

    Raises
    ------
    ValueError
        If ``nbytes > limit``.
    """
    cap = MAX_BYTES if limit is None else limit
    if nbytes > cap:
        raise ValueError(
            f"{name} too large: {what} would need ~{nbytes / 2**30:.3g} GiB, above the "
            f"{cap / 2**30:.3g} GiB limit (speckle._validate.MAX_BYTES); reduce {name} or "
            "process the work in parts"
        )


def check_size(
    value: object, name: str, *, low: int = 1, bytes_per: float = 8.0, what: str | None = None
) -> int:
    """:func:`check_int` (``value >= low``) of a size that allocates ``bytes_per`` bytes per
    unit, and :func:`check_memory` of that allocation: a huge size is refused by name before
    any array is made.

    Raises
    ------
    TypeError
        If ``value`` is not an integer.
    ValueError
        If ``value < low`` or ``bytes_per * value`` exceeds :data:`MAX_BYTES`.
    """
    n = check_int(value, name, low=low)
    check_memory(bytes_per * n, name, what or f"{n} values of {bytes_per:g} bytes")
    return n


def check_path(path: object, name: str = "path") -> object:
    """Return ``path`` after checking it names a file: a ``str``, ``bytes``, ``os.PathLike`` or
    a resource with ``open`` (``importlib.resources.files(...) / name``).

    A number is refused: an ``int`` would be taken by ``open`` as a file descriptor (and
    closed).

    Raises
    ------
    TypeError
        Naming ``name`` when ``path`` is none of these.
    """
    if isinstance(path, str | bytes | os.PathLike) or (
        hasattr(path, "open") and not isinstance(path, numbers.Number)
    ):
        return path
    raise TypeError(f"{name} must be a file path (str or os.PathLike), got {type(path).__name__}")
