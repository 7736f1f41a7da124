"""Old place of the loader of users' OCT images: now :func:`speckle.io.load_image` (issue 32).

``speckle.analysis.image_files.load_image`` (and ``IMAGE_KINDS``, ``IMAGE_DIMS``) resolve to
:mod:`speckle.io`'s with a ``FutureWarning`` for one release.
"""

from .._deprecate import moved

__all__: list[str] = []

__getattr__ = moved(__name__, "speckle.io", ["IMAGE_DIMS", "IMAGE_KINDS", "load_image"])
