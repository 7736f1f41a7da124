"""
Fig. 2: B-scans for several scatterer densities
===============================================

Fragments of B-scans with 0.5 to 4 scatterers per pixel (amplitudes divided by the square root
of the density, as in the paper). Few scatterers per pixel give isolated bright points; from
about one per pixel the speckle is developed. Reduced here to 12 A-lines; the pipeline target
is ``results/fig2/fig2.png``.
"""

from speckle.figures import static
from speckle.pipeline import default_config

config = default_config()  # the pipeline's default config, shipped with the package
fig2, source = config["fig2"], config["source"]

ds = static.density_sweep(
    fig2["densities"],
    k0_dk=source["k0_dk"],
    n_alines=12,
    seed=config["seed"],
    normalise=fig2["normalise"],
    **static.source_options(source),
)
fig = static.plot_density_fragments(ds, fig2["fragment"])
