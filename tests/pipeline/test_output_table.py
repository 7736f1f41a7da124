"""The output table's comparison: exact where the table was written, six digits elsewhere."""

from __future__ import annotations

import copy

import numpy as np
from output_table import RTOL_OTHER, RTOL_SAME, compare, machine, summarise_array, tolerance


def _table(values) -> dict:
    return {"run.nc:x": summarise_array(np.asarray(values))}


def test_tolerance_is_strict_only_on_the_tables_machine():
    here = machine()
    assert tolerance(here) == RTOL_SAME
    assert tolerance(None) == RTOL_OTHER  # a table without a record
    for key in here:
        other = dict(here, **{key: "something else"})
        assert tolerance(other) == RTOL_OTHER, key


def test_last_bit_differences_pass_elsewhere_real_changes_fail_everywhere():
    x = np.linspace(1.0, 2.0, 11)
    old = _table(x)
    jitter = _table(x * (1 + 1e-9))  # what another CPU's kernels give (seen: up to 8e-8)
    assert compare(jitter, old, RTOL_SAME)
    assert not compare(jitter, old, RTOL_OTHER)
    change = _table(x * (1 + 1e-5))  # a change of numbers
    assert compare(change, old, RTOL_OTHER)
    nan = x.copy()
    nan[3] = np.nan  # structure is compared exactly at any tolerance
    assert any("nonfinite" in p for p in compare(_table(nan), old, 1.0))
    bigger = copy.deepcopy(old)
    bigger["run.nc:y"] = bigger["run.nc:x"]
    assert compare(old, bigger, 1.0) == ["run.nc:y: missing from the new run"]
