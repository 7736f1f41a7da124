"""Public names of :mod:`speckle.pipeline` (``lazy_loader.attach_stub``, type checkers)."""

from . import adapters as adapters
from . import checks as checks
from . import config_keys as config_keys
from . import defaults as defaults
from . import dynamics_checks as dynamics_checks
from . import outputs as outputs
from . import phantom_checks as phantom_checks
from . import phantom_real_checks as phantom_real_checks
from . import runner as runner
from . import synthoct_checks as synthoct_checks
from .adapters import (
    dask_options,
    random_bscan,
    resolve_source,
    scene_kwargs,
    source_options,
    source_spectrum,
    spectrum_kwargs,
    system_from_config,
)
from .checks import (
    check_config,
    check_despeckle,
    check_scan_table,
    check_sections,
    check_twin,
    figure_bytes,
    tol_floor,
)
from .config_keys import (
    rename_retired_keys,
)
from .defaults import (
    default_config,
)
from .outputs import (
    save,
)
from .runner import (
    log_to,
    run,
)

__all__ = [
    "check_config",
    "check_despeckle",
    "check_scan_table",
    "check_sections",
    "check_twin",
    "dask_options",
    "default_config",
    "figure_bytes",
    "log_to",
    "random_bscan",
    "rename_retired_keys",
    "resolve_source",
    "run",
    "save",
    "scene_kwargs",
    "source_options",
    "source_spectrum",
    "spectrum_kwargs",
    "system_from_config",
    "tol_floor",
]
