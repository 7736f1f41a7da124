"""Public names of :mod:`speckle.scene` (``lazy_loader.attach_stub``, type checkers)."""

from . import deformation as deformation
from . import mechanics as mechanics
from . import motion as motion
from . import regions as regions
from . import scatterers as scatterers
from . import shared as shared
from ._layers import (
    layer_stack,
    region_values,
)
from .deformation import (
    deformable_scene,
    displace,
    translate,
    uniaxial_strain,
)
from .mechanics import (
    compress_phantom,
    displacement_at,
    inclusion_labels,
    inclusion_strain,
    layer_strains,
    layered_labels,
)
from .motion import (
    ballistic_motion,
    brownian_motion,
    bulk_motion,
    flow_motion,
    moving_mask,
    poiseuille_velocity,
)
from .regions import (
    make_regions,
    rasterize,
    region_label,
)
from .scatterers import (
    random_scatterers,
)
from .shared import (
    from_lines,
    shared_scene,
)

__all__ = [
    "ballistic_motion",
    "brownian_motion",
    "bulk_motion",
    "compress_phantom",
    "deformable_scene",
    "displace",
    "displacement_at",
    "flow_motion",
    "from_lines",
    "inclusion_labels",
    "inclusion_strain",
    "layer_stack",
    "layer_strains",
    "layered_labels",
    "make_regions",
    "moving_mask",
    "poiseuille_velocity",
    "random_scatterers",
    "rasterize",
    "region_label",
    "region_values",
    "shared_scene",
    "translate",
    "uniaxial_strain",
]
