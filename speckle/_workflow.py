"""Moved to :mod:`speckle.pipeline.runner` (kept for scripts written against the old path)."""

from .pipeline.runner import log_to, run

__all__ = ["log_to", "run"]
