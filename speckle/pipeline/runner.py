"""Running the pipeline's Snakemake scripts: everything a script prints or raises goes to its log.

Every script in ``workflow/scripts/`` defines ``main(snakemake)`` and ends with ``run(main)``:

* :func:`log_to` sends the script's output to the rule's ``log:`` file while ``main`` runs:
  ``print``, Dask progress bars, ``logging`` (INFO and above), warnings, uncaught exceptions
  with their traceback, and the output of child processes (Dask worker processes, local
  ``dask.distributed`` workers), whose file descriptors 1 and 2 point at the log too.
* :func:`run` does nothing when the script is *imported* rather than run. Snakemake runs a
  ``script:`` as ``__main__``; the worker processes of Dask's ``processes`` scheduler and of a
  local ``dask.distributed`` cluster are started with ``spawn``, which re-imports the main
  module (as ``__mp_main__``) in every worker. Without this guard each worker would run the
  whole script again, without the ``snakemake`` object Snakemake's preamble defines, and die.
  The functions a sweep sends to the workers live in importable ``speckle`` modules, so the
  workers need nothing from the script.
"""

from __future__ import annotations

import contextlib
import logging
import os
import sys
from collections.abc import Callable, Iterator
from typing import Any

__all__ = ["log_to", "run"]

log = logging.getLogger(__name__)


@contextlib.contextmanager
def log_to(path: str | os.PathLike | None) -> Iterator[None]:
    """Send stdout, stderr, ``logging`` (INFO) and warnings to ``path`` while the block runs.

    Both the Python streams and the process's file descriptors 1 and 2 are redirected (the log
    is truncated first), so output of C extensions and of child processes started inside the
    block (e.g. Dask workers) lands in the log as well. Everything is restored on exit.
    ``path=None`` leaves the streams alone.
    """
    if path is None:
        yield
        return
    os.makedirs(os.path.dirname(os.path.abspath(path)), exist_ok=True)
    root = logging.getLogger()
    with open(path, "w", buffering=1) as stream:
        for s in (sys.stdout, sys.stderr):
            s.flush()
        saved = {fd: os.dup(fd) for fd in (1, 2)}
        for fd in saved:
            os.dup2(stream.fileno(), fd)
        handler = logging.StreamHandler(stream)
        handler.setFormatter(logging.Formatter("%(asctime)s %(levelname)s %(name)s %(message)s"))
        old_level = root.level
        root.addHandler(handler)
        root.setLevel(logging.INFO)
        logging.captureWarnings(True)
        try:
            with contextlib.redirect_stdout(stream), contextlib.redirect_stderr(stream):
                yield
        finally:
            logging.captureWarnings(False)
            root.removeHandler(handler)
            root.setLevel(old_level)
            stream.flush()
            for fd, copy in saved.items():
                os.dup2(copy, fd)
                os.close(copy)


def run(main: Callable[[Any], None]) -> None:
    """Run a pipeline script's ``main(snakemake)`` with all its output in the rule's log.

    Call it as the last line of a Snakemake ``script:``, with the script's ``main`` function.
    When the script runs as ``__main__`` (Snakemake), ``main`` is called with the ``snakemake``
    object of the script's preamble inside :func:`log_to` on the rule's first ``log:`` file; an
    exception is written to the log with its traceback and re-raised (so the job fails and
    Snakemake shows it too). When the script is imported (a spawned worker process re-importing
    the main module), nothing happens.

    Parameters
    ----------
    main : callable
        Function of the script taking Snakemake's ``snakemake`` object.
    """
    if main.__module__ != "__main__":
        return
    smk = getattr(sys.modules["__main__"], "snakemake", None)
    if smk is None:
        raise RuntimeError(
            "speckle.pipeline.runner.run must be called from a Snakemake script "
            "(no `snakemake` object in __main__)"
        )
    with log_to(smk.log[0] if len(smk.log) else None):
        try:
            main(smk)
        except BaseException:
            log.exception("rule %s failed", smk.rule)
            raise
