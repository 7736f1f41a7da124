"""Atomic file writes, without heavy imports (the SynthOCT command imports it; see
:mod:`speckle.io`, which re-exports :func:`atomic_path`)."""

from __future__ import annotations

import contextlib
import os
import tempfile
from collections.abc import Iterator
from pathlib import Path

__all__ = ["atomic_path"]


@contextlib.contextmanager
def atomic_path(path: str | os.PathLike) -> Iterator[Path]:
    """Yield a temporary path beside ``path``; on success it replaces ``path`` atomically.

    The temporary file lives in the same directory (so :func:`os.replace` is an atomic rename
    on the same file system) and keeps the suffix of ``path`` (so writers that pick a format
    from the suffix, e.g. matplotlib, behave the same). After the block it is flushed to disk
    (``fsync``) and renamed over ``path``; if the block raises, it is removed and ``path`` is
    untouched. Parent directories are created.

    Raises
    ------
    ValueError
        If ``path`` is an existing directory.
    """
    target = Path(path)
    if target.is_dir():
        raise ValueError(f"path must be a file path, got the directory {str(target)!r}")
    target.parent.mkdir(parents=True, exist_ok=True)
    fd, tmp = tempfile.mkstemp(
        prefix=f".{target.name}.", suffix=f"{target.suffix}.tmp", dir=target.parent
    )
    os.close(fd)
    tmp_path = Path(tmp)
    try:
        yield tmp_path
        with open(tmp_path, "rb+") as f:
            os.fsync(f.fileno())
        os.chmod(tmp_path, _file_mode(target))  # mkstemp makes 0600; keep the usual mode
        os.replace(tmp_path, target)
    except BaseException:
        tmp_path.unlink(missing_ok=True)
        raise
    with contextlib.suppress(OSError):  # persist the rename (not possible on every system)
        dfd = os.open(target.parent, os.O_RDONLY)
        try:
            os.fsync(dfd)
        finally:
            os.close(dfd)


def _file_mode(target: Path) -> int:
    """Permissions of the existing ``target``, else those of a new file (0666 minus umask)."""
    if target.exists():
        return target.stat().st_mode & 0o7777
    umask = os.umask(0)
    os.umask(umask)
    return 0o666 & ~umask
