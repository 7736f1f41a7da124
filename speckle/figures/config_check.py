"""Moved to :mod:`speckle.pipeline.checks`; the old names warn (``FutureWarning``) for a release."""

from .._deprecate import moved
from ..pipeline import checks

__getattr__ = moved(__name__, checks)
