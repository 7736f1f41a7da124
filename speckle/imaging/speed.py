"""Moved to :mod:`speckle.studies.speed` (issue 32); the old names warn (``FutureWarning``).

Timing the methods against each other is a study of them; imaging imports no study: it is
imported only when an old name is used.
"""

from .._deprecate import moved

__getattr__ = moved(__name__, "speckle.studies.speed")
