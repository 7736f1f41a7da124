"""Shared fixtures and hypothesis profile."""

from __future__ import annotations

import os
from pathlib import Path

import matplotlib
import pytest
from hypothesis import settings

matplotlib.use("Agg")

settings.register_profile("ci", max_examples=30, deadline=None, derandomize=True)
settings.register_profile("dev", max_examples=30, deadline=None)
settings.load_profile("ci" if os.environ.get("CI") else "dev")

REPO = Path(__file__).resolve().parents[1]


@pytest.fixture(scope="session")
def repo_root() -> Path:
    """Repository root (the folder holding the Snakefile)."""
    return REPO


# --- malformed-input property tests (issue 21): one checker shared by the feature groups ---
#: Values a hostile user passes for any parameter: wrong types, strings that look like
#: numbers or booleans, non-finite and out-of-range numbers, wrong shapes.
MALFORMED = (None, "8", "False", True, -1, 0, 0.5, 1.5, float("nan"), float("inf"), -1e300,
             1e300, [], [1.0, 2.0, 3.0], {"a": 1}, 1j)  # fmt: skip


def _finite_result(out) -> bool:
    import numpy as np
    import xarray as xr

    if isinstance(out, tuple):
        return all(_finite_result(o) for o in out)
    if isinstance(out, np.ndarray | float | int | complex):
        return bool(np.all(np.isfinite(out)))
    if isinstance(out, xr.DataArray | xr.Dataset):
        arrays = [out] if isinstance(out, xr.DataArray) else list(out.data_vars.values())
        return all(a.dtype.kind in "fcbiu" and bool(np.all(np.isfinite(a.values))) for a in arrays)
    return out is not None


@pytest.fixture(scope="session")
def malformed():
    """``(values, check)``: :data:`MALFORMED` (draw one with ``st.data()``) and
    ``check(call, param, value)``: ``call()`` raises TypeError/ValueError naming ``param`` (or
    its first word) or returns a finite answer; any other exception fails the test."""

    def check(call, param: str, value) -> None:
        try:
            out = call()
        except (TypeError, ValueError) as err:
            msg, first = str(err), param.split("_")[0]
            assert param in msg or (len(first) > 2 and first in msg), (param, value, msg)
        else:
            assert _finite_result(out), (param, value)

    return MALFORMED, check
