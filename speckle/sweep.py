"""Parameter sweeps evaluated in parallel with Dask.

:func:`sweep` maps a function over the Cartesian product of parameter values with
``dask.delayed`` and stacks the results into one labelled dataset with a dim per parameter. The
scheduler is Dask's: threads or processes on one machine, or a ``dask.distributed`` cluster
(``address`` of a running scheduler) to scale past one machine. Results do not depend on the
scheduler or the number of workers as long as ``func`` derives its random numbers from its
arguments (e.g. :func:`speckle.scene.scatterers.line_generator`), never from global state.
"""

from __future__ import annotations

import contextlib
import itertools
import logging
from collections.abc import Callable, Mapping, Sequence

import dask
import numpy as np
import xarray as xr

from ._validate import check_bool, check_choice, check_int

__all__ = ["SCHEDULERS", "dask_scheduler", "sweep"]

SCHEDULERS = ("synchronous", "threads", "processes", "distributed")
log = logging.getLogger(__name__)


@contextlib.contextmanager
def dask_scheduler(
    scheduler: str = "threads", address: str | None = None, n_workers: int | None = None
):
    """Context in which Dask computations run on ``scheduler`` (the config's ``dask`` section).

    ``"distributed"``: a ``dask.distributed`` client of the scheduler at ``address``, or of a
    local cluster of ``n_workers`` single-threaded processes started (and closed) here.
    """
    check_choice(scheduler, "scheduler", SCHEDULERS)
    workers = None if n_workers is None else check_int(n_workers, "n_workers", low=1)
    if scheduler != "distributed":
        with dask.config.set(scheduler=scheduler, num_workers=workers):
            yield
        return
    from dask.distributed import Client, LocalCluster

    with contextlib.ExitStack() as stack:
        if not address:
            address = stack.enter_context(
                LocalCluster(
                    n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None
                )
            )
        stack.enter_context(Client(address))
        yield


def _compute(
    tasks: list, scheduler: str, address: str | None, n_workers: int | None, progress: bool
) -> list:
    if scheduler != "distributed":
        if progress:
            from dask.diagnostics import ProgressBar

            with ProgressBar(dt=1.0):
                return list(dask.compute(*tasks, scheduler=scheduler, num_workers=n_workers))
        return list(dask.compute(*tasks, scheduler=scheduler, num_workers=n_workers))
    from dask.distributed import Client, LocalCluster, as_completed

    with contextlib.ExitStack() as stack:
        if not address:  # a local cluster for this sweep, closed with it (also on errors)
            address = stack.enter_context(
                LocalCluster(
                    n_workers=n_workers,
                    threads_per_worker=1,
                    processes=True,
                    dashboard_address=None,
                )
            )
        client = stack.enter_context(Client(address))
        futures = client.compute(tasks)
        index = {f.key: i for i, f in enumerate(futures)}
        results: list = [None] * len(futures)
        for done, future in enumerate(as_completed(futures), start=1):
            results[index[future.key]] = future.result()
            if progress:
                log.info("sweep: %d/%d points done", done, len(futures))
    return results


def sweep(
    func: Callable[..., xr.Dataset | xr.DataArray],
    grid: Mapping[str, Sequence],
    *,
    fixed: Mapping[str, object] | None = None,
    scheduler: str = "threads",
    address: str | None = None,
    n_workers: int | None = None,
    progress: bool = False,
) -> xr.Dataset:
    """Evaluate ``func`` on every point of a parameter grid in parallel, stacked by parameter.

    Parameters
    ----------
    func : callable
        Called as ``func(**point, **fixed)`` and returning an ``xarray.Dataset`` or
        ``DataArray`` (all points must return the same variables and dims).
    grid : mapping of str to sequence
        Parameter name -> values. Each name becomes a dim of the result, with the values as
        its coordinate, in the given order.
    fixed : mapping, optional
        Keyword arguments passed unchanged to every call.
    scheduler : {"synchronous", "threads", "processes", "distributed"}
        Dask scheduler. ``"distributed"`` connects to ``address`` or starts a local cluster.
    address : str, optional
        Address of a running ``dask.distributed`` scheduler (e.g. ``"tcp://host:8786"``).
    n_workers : int, optional
        Worker count for local schedulers (>= 1; default: Dask's choice).
    progress : bool
        Report progress (a Dask progress bar, or log lines on a distributed cluster).

    Returns
    -------
    xarray.Dataset
        The results concatenated along the grid dims (grid dims first).
    """
    check_choice(scheduler, "scheduler", SCHEDULERS)
    check_bool(progress, "progress")
    if n_workers is not None:
        check_int(n_workers, "n_workers", low=1)
    if not grid:
        raise ValueError("grid must name at least one parameter")
    names = list(grid)
    values = [list(np.atleast_1d(np.asarray(grid[k])).tolist()) for k in names]
    for k, v in zip(names, values, strict=True):
        if len(v) == 0:
            raise ValueError(f"grid[{k!r}] must hold at least one value")
    fixed = dict(fixed or {})
    points = list(itertools.product(*values))
    tasks = [dask.delayed(func)(**dict(zip(names, p, strict=True)), **fixed) for p in points]
    results = _compute(tasks, scheduler, address, n_workers, progress)
    results = [
        r.to_dataset(name=r.name or "data") if isinstance(r, xr.DataArray) else r for r in results
    ]
    nested: list = results
    for size in reversed([len(v) for v in values[1:]]):
        nested = [nested[i : i + size] for i in range(0, len(nested), size)]
    out = xr.combine_nested(nested, concat_dim=names, combine_attrs="drop_conflicts")
    out = out.assign_coords({k: (k, v) for k, v in zip(names, values, strict=True)})
    return out.transpose(*names, ...)
