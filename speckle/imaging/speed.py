"""Moved to :mod:`speckle.studies.speed` (issue 32); the old names warn (``FutureWarning``).

Timing the methods against each other is a study of them; imaging imports no study: it is
imported only when an old name is used.
"""

from .._deprecate import moved

__getattr__ = moved(
    __name__,
    "speckle.studies.speed",
    [
        "FAILURE_CASES",
        "beam_speed_accuracy",
        "failure_map",
        "random_beam_scene",
        "random_scene",
        "speed_accuracy",
    ],
)
