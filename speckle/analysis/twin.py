"""Moved to :mod:`speckle.studies.twin` (issue 32); the old names warn (``FutureWarning``).

``analysis`` measures images and imports no imaging: the study is imported only when an old
name is used.
"""

from .._deprecate import moved

__getattr__ = moved(__name__, "speckle.studies.twin")
