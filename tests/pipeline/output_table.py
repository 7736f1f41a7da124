"""Summary table of every NetCDF output of the CI pipeline, to hold numbers still across a refactor.

Each variable and coordinate of each ``results_ci/**/*.nc`` file is summarised by its shape, dtype,
NaN count, sum, sum of absolute values, sum of squares and a few samples of the flattened array
(complex values as real and imaginary parts). Timings are excluded: they are measurements of the
machine, not results of the model (variables in seconds or per second, or whose name says
time). ``tests/pipeline/test_pipeline.py`` compares a fresh CI run with the checked-in table
``ci_outputs.json``: to :data:`RTOL_SAME` relative on the machine the table was written on (the
same CPU and numerical libraries, :func:`machine`), to :data:`RTOL_OTHER` elsewhere.

Regenerate the table only where a change of numbers is intended and explained in the commit::

    snakemake --cores 2 --configfile workflow/config/ci.yaml
    python tests/pipeline/output_table.py results_ci tests/pipeline/ci_outputs.json
"""

from __future__ import annotations

import json
import math
import sys
from importlib.metadata import version
from pathlib import Path

import llvmlite.binding
import numpy as np
import xarray as xr

TABLE = Path(__file__).with_name("ci_outputs.json")
#: Relative agreement asked of every summary number on the machine the table was written on.
#: Two CI-config runs of one commit on one machine (rocketlake, 2026-12-03) gave standard errors
#: of elastography/failure_maps.nc (a difference of nearly equal sums over seeds) that differ by
#: 1.04e-12 relative (threaded reductions summing in another order); 1e-11 keeps a 10x margin.
RTOL_SAME = 1e-11
#: ... and on any other. Another CPU makes numpy, numba (compiled for the host), OpenBLAS and
#: FINUFFT dispatch other SIMD kernels, so elementwise functions and reductions differ in their
#: last bits, which the statistics of fits on speckle amplify. Seen between an AVX-512 machine
#: (AMD EPYC) and a table written elsewhere: 73 of 597 variables above 1e-12, the largest 8e-8
#: (realism.nc's kurtosis standard errors), nothing structural (shapes, dtypes, NaN counts
#: equal). At 1e-6 every number still holds to six digits; intended changes smaller than that
#: (seen: 4e-8 and 2e-7, a float64 refinement kernel and the 8-point resampling) are flagged
#: only on the table's own machine.
RTOL_OTHER = 1e-6
#: Key of the table's record of the machine it was written on.
MACHINE = "__machine__"
#: Libraries whose versions decide the outputs' last bits.
LIBRARIES = ("numpy", "scipy", "numba", "finufft", "scikit-image", "xarray", "netCDF4")
#: Number of evenly spaced samples of the flattened array.
N_SAMPLES = 5


#: Variables left out, with the reason: each is a least-squares fit on speckle whose optimum
#: moves when the image changes in its last bits (thread-count-dependent sums such as
#: FINUFFT's), so an exact comparison would test the optimiser, not the model. The images they
#: are fitted on are in the table.
UNSTABLE_FITS = {
    "despeckle/methods.nc:edge_width": "erf fit of a step edge on speckle (seen 5e-12 apart)",
    "despeckle/methods.nc:edge_width_ratio": "the same fit, over the single look's",
    "despeckle/methods.nc:edge_width_se": "the same fit on each quarter of the lines",
    "despeckle/methods.nc:resolution_loss_with_edge": "the larger of resolution_loss and "
    "edge_width_ratio (the same fit)",
}


def _is_timing(name: str, var: xr.DataArray) -> bool:
    units = str(var.attrs.get("units", "")).strip().lower()
    return units in {"s", "seconds", "ms", "1/s"} or any(
        word in name.lower() for word in ("time", "seconds", "elapsed", "speed")
    )


def _parts(values: np.ndarray) -> dict[str, np.ndarray]:
    if np.iscomplexobj(values):
        return {"real": values.real, "imag": values.imag}
    if values.dtype.kind == "b":
        return {"": values.astype(np.int64)}
    return {"": values}


def summarise_array(values: np.ndarray) -> dict[str, object]:
    """Shape, dtype, NaN count, sums and samples of one array (see the module docstring)."""
    values = np.asarray(values)
    out: dict[str, object] = {"shape": list(values.shape), "dtype": values.dtype.str}
    if values.dtype.kind not in "biufc":
        out["samples"] = [str(v) for v in values.ravel()[:N_SAMPLES]]
        return out
    for label, part in _parts(values).items():
        flat = part.astype(np.float64).ravel()
        finite = np.where(np.isfinite(flat), flat, 0.0)
        key = f"{label}_" if label else ""
        picks = np.linspace(0, flat.size - 1, min(N_SAMPLES, flat.size)).astype(int)
        out[f"{key}nonfinite"] = int(flat.size - np.isfinite(flat).sum())
        out[f"{key}sum"] = float(finite.sum())
        out[f"{key}abs_sum"] = float(np.abs(finite).sum())
        out[f"{key}sum_sq"] = float((finite**2).sum())
        out[f"{key}samples"] = [float(v) if np.isfinite(v) else str(v) for v in flat[picks]]
    return out


def summarise(results: Path) -> dict[str, dict[str, object]]:
    """Summary of every variable and coordinate of every NetCDF file under ``results``."""
    table: dict[str, dict[str, object]] = {}
    for path in sorted(results.rglob("*.nc")):
        rel = path.relative_to(results).as_posix()
        with xr.open_dataset(path, engine="netcdf4", auto_complex=True) as ds:
            for name, var in {**ds.coords, **ds.data_vars}.items():
                if _is_timing(str(name), var) or f"{rel}:{name}" in UNSTABLE_FITS:
                    continue
                table[f"{rel}:{name}"] = summarise_array(var.values)
    return table


def machine() -> dict[str, str]:
    """What decides the last bits of the outputs: the CPU as LLVM names it (numba compiles for
    it; numpy, OpenBLAS and FINUFFT choose their kernels by the same features) and the versions
    of :data:`LIBRARIES`."""
    return {"cpu": llvmlite.binding.get_host_cpu_name()} | {n: version(n) for n in LIBRARIES}


def tolerance(table_machine: dict | None) -> float:
    """:data:`RTOL_SAME` on the machine a table was written on, else :data:`RTOL_OTHER`."""
    return RTOL_SAME if table_machine == machine() else RTOL_OTHER


def _close(a: float, b: float, scale: float, rtol: float) -> bool:
    return math.isclose(a, b, rel_tol=rtol, abs_tol=rtol * scale)


def _abs_sum(summary: dict, field: str) -> float:
    """Sum of absolute values of the part (real, imaginary or whole) a summary field is of."""
    prefix = field.split("_")[0] + "_" if field.startswith(("real_", "imag_")) else ""
    return float(summary.get(f"{prefix}abs_sum", 0.0))


def compare(new: dict, old: dict, rtol: float = RTOL_SAME) -> list[str]:
    """Differences between two tables, one line each (empty when they agree).

    Sums are compared to ``rtol`` times the sum of absolute values (cancellation-safe), sums of
    squares relative to themselves, samples to ``rtol`` times the larger of their own magnitude
    and the part's mean magnitude; everything else (shape, dtype, NaN counts) exactly.
    """
    problems = [f"{key}: missing from the new run" for key in old.keys() - new.keys()]
    problems += [f"{key}: not in the table" for key in new.keys() - old.keys()]
    for key in sorted(old.keys() & new.keys()):
        a, b = new[key], old[key]
        for field in sorted(a.keys() | b.keys()):
            va, vb = a.get(field), b.get(field)
            if field.endswith("samples") and "shape" in b and b.get("dtype", "")[1:2] in "biufc":
                mean = _abs_sum(b, field) / max(math.prod(b["shape"]), 1)
                ok = len(va or []) == len(vb) and all(
                    x == y
                    if isinstance(x, str) or isinstance(y, str)
                    else _close(x, y, max(abs(y), mean), rtol)
                    for x, y in zip(va, vb, strict=True)
                )
            elif field.endswith("abs_sum") or field.endswith("sum_sq"):
                ok = isinstance(va, float) and _close(va, vb, abs(vb), rtol)
            elif field.endswith("sum"):
                ok = isinstance(va, float) and _close(va, vb, _abs_sum(b, field), rtol)
            else:
                ok = va == vb
            if not ok:
                problems.append(f"{key}.{field}: {va!r} != {vb!r} (table)")
    return problems


def load_table(path: Path = TABLE) -> tuple[dict, dict | None]:
    """The checked-in table's variables, and the machine it was written on (None if unrecorded)."""
    table = json.loads(path.read_text())
    return {k: v for k, v in table.items() if k != MACHINE}, table.get(MACHINE)


if __name__ == "__main__":
    results, out = Path(sys.argv[1]), Path(sys.argv[2])
    tmp = out.with_suffix(".tmp")
    table = summarise(results) | {MACHINE: machine()}
    tmp.write_text(json.dumps(table, indent=1, sort_keys=True) + "\n")
    tmp.replace(out)
    print(f"{out}: {len(load_table(out)[0])} variables, written on {machine()}")
